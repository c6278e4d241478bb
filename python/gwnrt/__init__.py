"""gwnrt: generalized winding numbers of triangle meshes, from Python.

A :class:`Model` is built once from a mesh (arrays, an object with ``.vertices`` and ``.faces``,
or a file through :func:`load`); its queries take points as an ``(k, 3)`` array and return numpy
arrays in input order. The surface is S = boundary of {w > level} (level 1/2 by default): the
mesh where it separates inside from outside, smooth caps over its holes.

Inputs: float32 C-contiguous arrays are used in place; anything else (float64, lists, strided
views) is converted to float32 once. Every batch runs in C++ with the GIL released, on all cores
or on ``threads=`` TBB workers (0 to 1024; 0 or None: all cores). Bad input raises ``ValueError`` with the C++ library's message (the
point, face or option at fault); unreadable files ``OSError``; allocations ``MemoryError``; other
failures ``RuntimeError``. ``device="cuda"`` (or ``"auto"``) runs the batch on the GPU where the
module was built with the CUDA backend and one is usable.
"""

from __future__ import annotations

import math
import os
import warnings
from typing import NamedTuple, Optional, Sequence

import numpy as np

from . import _gwnrt

__all__ = [
    "Model", "load", "write_mesh", "mesh_topology", "device_available", "device_status",
    "DistanceResult", "BoundaryDistanceResult", "SignedDistanceResult", "ProjectionResult", "TraceResult",
    "MeshResult", "HIT_NONE", "HIT_SHEET", "HIT_SMOOTH", "PIECE_SHEET", "PIECE_SMOOTH", "PIECE_BOUND",
]

# TraceResult.kind: what a ray hit (trace/trace_types.h HitKind).
HIT_NONE, HIT_SHEET, HIT_SMOOTH = 0, 1, 2
# SignedDistanceResult.piece: which distance won (sdf/signed_distance.h DistancePiece).
PIECE_SHEET, PIECE_SMOOTH, PIECE_BOUND = 0, 1, 2


class DistanceResult(NamedTuple):
    """Distance to the mesh M, the nearest triangle and the barycentrics (u, v) of the closest
    point on it: point = (1 - u - v) a + u b + v c."""
    distance: np.ndarray  # (k,) float32
    triangle: np.ndarray  # (k,) int32
    barycentrics: np.ndarray  # (k, 2) float32


class BoundaryDistanceResult(NamedTuple):
    """Distance to the boundary curve of M (+inf for a closed mesh) and the nearest segment (-1: none)."""
    distance: np.ndarray
    segment: np.ndarray


class SignedDistanceResult(NamedTuple):
    """The signed distance to S (negative inside {w > level}) and its parts: sdf1 = (level - w)/|grad w|
    and sdf2, its curvature correction (NaN where the sdf did not need them), the distance to the
    sheet triangles and the nearest one, and which piece won (PIECE_*)."""
    sdf: np.ndarray
    sdf1: np.ndarray
    sdf2: np.ndarray
    sheet_distance: np.ndarray
    sheet_triangle: np.ndarray
    piece: np.ndarray


class ProjectionResult(NamedTuple):
    """Newton projection onto the smooth pieces of S: the point reached, whether it converged
    (|w - level| <= tolerance), the steps taken and w - level there."""
    point: np.ndarray
    converged: np.ndarray
    iterations: np.ndarray
    residual: np.ndarray


class TraceResult(NamedTuple):
    """Per ray: hit, t (in units of the ray's direction; inf on a miss), position, unit outward
    normal, kind (HIT_SHEET: on a mesh triangle; HIT_SMOOTH: a smooth cap), triangle (sheet hits;
    -1 otherwise), Harnack steps, a cap that ended the trace (reported as a miss), triangle
    crossings walked, and rejected input (non-finite numbers, zero direction)."""
    hit: np.ndarray
    t: np.ndarray
    position: np.ndarray
    normal: np.ndarray
    kind: np.ndarray
    triangle: np.ndarray
    steps: np.ndarray
    capped: np.ndarray
    crossings: np.ndarray
    invalid: np.ndarray


class MeshResult(NamedTuple):
    """A mesh of S: vertices (n, 3), faces (m, 3) counter-clockwise seen from outside, unit outward
    normals, and the attributes asked for (None otherwise): the nearest source triangle and its
    barycentrics ('source'), texture coordinates ('uv'), RGBA colours ('color'); stats says what
    the mesher did (grid, counts, seconds, message)."""
    vertices: np.ndarray
    faces: np.ndarray
    normals: Optional[np.ndarray]
    source_triangles: Optional[np.ndarray]
    source_barycentrics: Optional[np.ndarray]
    uvs: Optional[np.ndarray]
    colors: Optional[np.ndarray]
    stats: dict


# The fields whose result is a named tuple, with the query columns that fill it, in its order;
# every other field's result is its one column. Model's methods and gwnrt.dask share it.
_NAMED_RESULTS = {
    "unsigned_distance": (DistanceResult, ("distance", "triangle", "barycentrics")),
    "boundary_distance": (BoundaryDistanceResult, ("boundary_distance", "boundary_segment")),
    "signed_distance": (SignedDistanceResult, ("sdf", "sdf1", "sdf2", "sheet_distance", "sheet_triangle", "piece")),
    "projection": (ProjectionResult, ("projection", "converged", "iterations", "residual")),
}


def _field_result(field, columns):
    """One field's result from query's columns (numpy or dask arrays)."""
    if field not in _NAMED_RESULTS:
        return columns[field]
    result, keys = _NAMED_RESULTS[field]
    return result(*(columns[key] for key in keys))


def _mesh_arrays(mesh):
    """(vertices, faces) of an object with .vertices and .faces (trimesh) or .triangles (open3d)."""
    vertices = getattr(mesh, "vertices", None)
    faces = getattr(mesh, "faces", None)
    if faces is None:
        faces = getattr(mesh, "triangles", None)
    if vertices is None or faces is None:
        raise TypeError("expected vertices and faces arrays, or an object with .vertices and .faces "
                        f"(or .triangles), got {type(mesh).__name__}")
    return np.asarray(vertices), np.asarray(faces)


class Model:
    """A mesh with everything the queries need, built once: Model(vertices, faces) from an (n, 3)
    float array and an (m, 3) integer array, or Model(mesh) from an object with .vertices and
    .faces. classify_sheets: classify which triangles S runs along, for `level` (needed by
    signed_distance; set_sheet_level changes the level later). The multipole tree is built now,
    the boundary, its cone and the sheets on the first query that reads them."""

    def __init__(self, vertices, faces=None, *, classify_sheets: bool = True, level: float = 0.5,
                 sheet_method: str = "auto", threads: Optional[int] = None):
        if faces is None:
            vertices, faces = _mesh_arrays(vertices)
        self._native = _gwnrt.Model(vertices, faces, classify_sheets=classify_sheets, level=level,
                                    sheet_method=sheet_method, threads=threads)

    _origin = np.zeros(3)

    @classmethod
    def _from_native(cls, native) -> "Model":
        model = cls.__new__(cls)
        model._native = native
        return model

    @property
    def origin(self) -> np.ndarray:
        """Where the model's coordinate 0 lies in its file's coordinates (float64): non-zero only
        for a far-off mesh loaded with recentre=True. vertices and every position in and out are
        relative to it."""
        return self._origin.copy()

    _load_report = None

    @property
    def load_report(self) -> Optional[dict]:
        """For a model from gwnrt.load: the file's format, file_vertices (an STL's corners),
        vertices_used and positions_used (after welding bit-identical positions),
        boundary_edges_by_index and boundary_edges (after welding: what the model uses),
        boundary_loops, tolerance_welded and degenerate_triangles. None for a model from arrays."""
        if self._load_report is None:
            return None
        if "positions_used" not in self._load_report:  # computed on first need: sorts of the whole mesh
            self._load_report.update(self._native.weld_summary())
        return dict(self._load_report)

    # -- the mesh --------------------------------------------------------------------------------
    @property
    def vertices(self) -> np.ndarray:
        """The mesh's vertex positions (a float32 copy)."""
        return self._native.vertices

    @property
    def faces(self) -> np.ndarray:
        """The mesh's triangles (an int64 copy)."""
        return self._native.faces

    @property
    def vertex_count(self) -> int:
        return self._native.vertex_count

    @property
    def triangle_count(self) -> int:
        return self._native.triangle_count

    @property
    def bounds(self) -> np.ndarray:
        """The mesh's box: [[xmin, ymin, zmin], [xmax, ymax, zmax]]."""
        return self._native.bounds

    @property
    def sheet_level(self) -> Optional[float]:
        """The level the sheets are classified for (None when built without them)."""
        return self._native.sheet_level

    @property
    def boundary_segment_count(self) -> int:
        """Edges of the boundary curve of M (0 for a closed mesh)."""
        return self._native.boundary_segment_count

    def set_sheet_level(self, level: float) -> None:
        """Classify the sheets for another level (waits for running queries on this model)."""
        self._native.set_sheet_level(level)

    # -- point queries ---------------------------------------------------------------------------
    def query(self, points, fields: Sequence[str], *, method: str = "auto", order: int = 2, beta: float = 2.0,
              level: Optional[float] = None, max_iterations: int = 32, tolerance: float = 1e-4,
              threads: Optional[int] = None, device: str = "cpu") -> dict:
        """Several fields in one pass over the points, as a dict of arrays. fields: w, gradient,
        hessian, unsigned_distance, boundary_distance, signed_distance, pseudo_distance,
        sheet_distance, projection, harnack_bound. method: how w, grad w and H_w are evaluated
        (auto, crossing: exact, taylor: the multipole tree at `order` and `beta`, brute: the
        double sum). level: None takes the level the sheets were classified for."""
        if isinstance(fields, str):
            fields = [fields]
        return _gwnrt.query(self._native, points, list(fields), method=method, order=order, beta=beta,
                            level=level, newton_iterations=max_iterations, newton_tolerance=tolerance,
                            threads=threads, device=device)

    def _field(self, field, points, **options):
        return _field_result(field, self.query(points, [field], **options))

    def winding_number(self, points, method: str = "auto", order: int = 2, beta: float = 2.0, *,
                       threads: Optional[int] = None, device: str = "cpu") -> np.ndarray:
        """w at each point, (k,) float32."""
        return self._field("w", points, method=method, order=order, beta=beta, threads=threads, device=device)

    def gradient(self, points, method: str = "auto", order: int = 2, beta: float = 2.0, *,
                 threads: Optional[int] = None, device: str = "cpu") -> np.ndarray:
        """grad w at each point, (k, 3) float32."""
        return self._field("gradient", points, method=method, order=order, beta=beta, threads=threads,
                           device=device)

    def hessian(self, points, method: str = "auto", order: int = 2, beta: float = 2.0, *,
                threads: Optional[int] = None, device: str = "cpu") -> np.ndarray:
        """The Hessian of w at each point, (k, 3, 3) float32."""
        return self._field("hessian", points, method=method, order=order, beta=beta, threads=threads,
                           device=device)

    def unsigned_distance(self, points, *, threads: Optional[int] = None, device: str = "cpu") -> DistanceResult:
        return self._field("unsigned_distance", points, threads=threads, device=device)

    def boundary_distance(self, points, *, threads: Optional[int] = None,
                          device: str = "cpu") -> BoundaryDistanceResult:
        return self._field("boundary_distance", points, threads=threads, device=device)

    def signed_distance(self, points, level: Optional[float] = None, method: str = "auto", order: int = 2,
                        beta: float = 2.0, *, threads: Optional[int] = None, device: str = "cpu") -> SignedDistanceResult:
        """The signed distance to S for `level` (None: the sheets' level; another level needs
        set_sheet_level first)."""
        return self._field("signed_distance", points, method=method, order=order, beta=beta, level=level,
                           threads=threads, device=device)

    def project(self, points, level: Optional[float] = None, method: str = "auto", order: int = 2,
                beta: float = 2.0, *, max_iterations: int = 32, tolerance: float = 1e-4,
                threads: Optional[int] = None, device: str = "cpu") -> ProjectionResult:
        return self._field("projection", points, method=method, order=order, beta=beta, level=level,
                           max_iterations=max_iterations, tolerance=tolerance, threads=threads, device=device)

    def harnack_bound(self, points, level: Optional[float] = None, beta: float = 2.0, *,
                      threads: Optional[int] = None, device: str = "cpu") -> np.ndarray:
        """rho(x) <= the distance from x to S, a proven lower bound."""
        return self._field("harnack_bound", points, beta=beta, level=level, threads=threads, device=device)

    # -- rays ------------------------------------------------------------------------------------
    def trace(self, origins, directions, tnear=0.0, tfar=math.inf, *, mode: str = "gwn", level: float = 0.5,
              epsilon: float = 1e-5, max_steps: int = 4096, max_crossings: int = 65536, beta: float = 2.0,
              exact: bool = False, threads: Optional[int] = None, device: str = "cpu") -> TraceResult:
        """The first hit of each ray o + t d, t in [tnear, tfar], on S (mode 'gwn') or on the
        solid-angle level set (mode 'solid_angle'). origins and directions: (k, 3) or one (3,)
        row for every ray; tnear and tfar: a number or (k,). epsilon: the stopping distance of the
        Harnack steps, relative to the mesh's box diagonal."""
        o, d = _rows3(origins), _rows3(directions)
        k = len(o) if o.ndim == 2 else 0
        if o.shape[1:] == (3,) and d.shape[1:] == (3,) and len(o) != len(d):  # a single row serves every ray
            if len(o) != 1 and len(d) != 1:
                raise ValueError(f"origins has {len(o)} rows and directions {len(d)}: the same number, or one row")
            k = len(d) if len(o) == 1 else len(o)
            o, d = np.broadcast_to(o, (k, 3)), np.broadcast_to(d, (k, 3))
        near = _per_ray(tnear, k, "tnear")
        far = _per_ray(tfar, k, "tfar")
        r = _gwnrt.trace(self._native, o, d, near, far, mode=mode, level=level, epsilon=epsilon,
                         max_steps=max_steps, max_crossings=max_crossings, beta=beta, exact=exact,
                         threads=threads, device=device)
        return TraceResult(r["hit"], r["t"], r["position"], r["normal"], r["kind"], r["triangle"], r["steps"],
                           r["capped"], r["crossings"], r["invalid"])

    # -- meshing ---------------------------------------------------------------------------------
    def extract_surface(self, resolution: int = 256, *, cell_size: Optional[float] = None, method: str = "dc",
                        level: Optional[float] = None, smooth_angle: float = 30.0, soup: bool = False,
                        attributes: Sequence[str] = (), winding_method: str = "auto", order: int = 2,
                        beta: float = 2.0, memory_budget: int = 8 << 30, threads: Optional[int] = None,
                        device: str = "cpu") -> MeshResult:
        """A closed mesh of S: `resolution` cells along the longest side of its box (or cells of
        `cell_size`), by dual contouring ('dc') or marching cubes ('mc'). attributes: any of
        'source', 'uv', 'color'. Refused, saying what it would need, beyond memory_budget bytes."""
        r = _gwnrt.extract_surface(self._native, resolution=resolution, cell_size=cell_size or 0.0, method=method,
                                   level=level, smooth_angle=smooth_angle, soup=soup, attributes=list(attributes),
                                   winding_method=winding_method, order=order, beta=beta,
                                   memory_budget=memory_budget, threads=threads, device=device)
        return MeshResult(r["vertices"], r["faces"], r.get("normals"), r.get("source_triangles"),
                          r.get("source_barycentrics"), r.get("uvs"), r.get("colors"), r["stats"])

    def __repr__(self) -> str:
        return f"gwnrt.Model({self.vertex_count} vertices, {self.triangle_count} triangles)"


def _rows3(x):
    """A (3,) row as (1, 3); any other shape as it is (the module checks it)."""
    a = np.asarray(x)
    return a.reshape(1, 3) if a.shape == (3,) else a


def _per_ray(x, k, name):
    a = np.asarray(x, dtype=np.float32)
    if a.ndim == 0 or a.shape == (1,):
        return np.full(k, a.reshape(()), dtype=np.float32)
    if a.shape != (k,):
        raise ValueError(f"{name} must be a number or have shape ({k},), got {a.shape}")
    return a


def load(path, *, classify_sheets: bool = True, level: float = 0.5, sheet_method: str = "auto",
         threads: Optional[int] = None, recentre: bool = False, weld_tolerance: float = 0.0) -> Model:
    """A Model from an OBJ, PLY or STL file (what the file had that gwnrt does not read is
    reported as a warning). recentre: a mesh far from the origin for its size (a georeferenced
    scan) is read in double and moved by -model.origin before float keeps it; subtract origin
    from the points you ask about and add it to the positions you get (write_mesh's origin=).
    Vertices at bit-identical positions are one for the topology (an STL's repeated corners, OBJ
    seams); weld_tolerance (a fraction of the box's diagonal, at most 0.01) also moves vertices
    closer than that onto each other. model.load_report says what loading and welding found."""
    native, notes, origin, load_report = _gwnrt.Model.load(
        os.fspath(path), classify_sheets=classify_sheets, level=level, sheet_method=sheet_method, threads=threads,
        recentre=recentre, weld_tolerance=weld_tolerance)
    if notes:
        warnings.warn(f"{os.fspath(path)}: {notes}", stacklevel=2)
    model = Model._from_native(native)
    model._origin = np.array(origin, dtype=np.float64)
    model._load_report = load_report
    return model


def write_mesh(path, mesh, faces=None, *, normals=None, uvs=None, colors=None, source_triangles=None,
               source_barycentrics=None, format: str = "auto", soup: bool = False, origin=None) -> None:
    """Writes a mesh to binary PLY or OBJ (by the extension, or format='ply'/'obj'): a MeshResult
    (every array it has), or vertices and faces arrays with optional per-vertex normals, uvs,
    colours and source triangles and barycentrics (PLY only keeps the last two). origin (three
    numbers, e.g. a recentred model's Model.origin) is added to the positions in double, and they
    are then written in double."""
    if faces is None:
        if isinstance(mesh, MeshResult):
            normals = mesh.normals if normals is None else normals
            uvs = mesh.uvs if uvs is None else uvs
            colors = mesh.colors if colors is None else colors
            source_triangles = mesh.source_triangles if source_triangles is None else source_triangles
            source_barycentrics = mesh.source_barycentrics if source_barycentrics is None else source_barycentrics
        mesh, faces = _mesh_arrays(mesh)
    _gwnrt.write_mesh(os.fspath(path), mesh, faces, normals=normals, uvs=uvs, colors=colors,
                      source_triangles=source_triangles, source_barycentrics=source_barycentrics, format=format,
                      soup=soup, origin=(0.0, 0.0, 0.0) if origin is None else tuple(float(c) for c in origin))


def mesh_topology(mesh, faces=None, *, weld: bool = False) -> dict:
    """Counts that say whether a mesh is a closed, consistently oriented 2-manifold: boundary,
    non-manifold and inconsistent edges, non-manifold vertices, degenerate triangles, components;
    watertight (no boundary edges), manifold (no non-manifold edges or vertices) and
    closed_manifold (both, consistently oriented, no degenerate triangles). weld: make exactly
    equal positions one vertex first (for soups)."""
    if faces is None:
        mesh, faces = _mesh_arrays(mesh)
    return _gwnrt.mesh_topology(mesh, faces, weld=weld)


def device_available() -> bool:
    """Whether device='cuda' can run (the CUDA backend built in and a usable GPU)."""
    return _gwnrt.device_available()[0]


def device_status() -> str:
    """Why device='cuda' cannot run ('' when it can)."""
    usable, why = _gwnrt.device_available()
    return "" if usable else why
