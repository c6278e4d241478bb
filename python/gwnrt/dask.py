"""gwnrt on Dask: point queries over a dask.array of points, and meshing many files.

The model is built once per worker process and reused for every chunk that worker evaluates:
from a path (each worker reads the file), or from arrays (a :class:`ModelSource`: one key of the
graph that every chunk depends on, so each worker receives the arrays once; a Future of one, from
``client.scatter(source, broadcast=True)``, also works). The same code runs on the threaded scheduler, on
``distributed.Client()`` (a local cluster) and on ``distributed.Client("tcp://scheduler:8786")``.

Inside a distributed worker each chunk runs on as many TBB threads as the worker has threads, so
that workers sharing a machine do not oversubscribe it; elsewhere on all cores.
"""

from __future__ import annotations

import collections
import os
import threading
import time
from typing import Optional, Sequence

import dask
import dask.array as da
import dask.bag as db
import numpy as np

import gwnrt
from . import _gwnrt

__all__ = [
    "ModelSource", "query", "winding_number", "gradient", "hessian", "unsigned_distance", "boundary_distance",
    "signed_distance", "project", "harnack_bound", "extract_surfaces", "worker_stats",
]


class ModelSource:
    """What a worker builds its model from: a mesh file, or vertices and faces arrays (or an
    object with .vertices and .faces), with gwnrt.Model's build options (classify_sheets, level,
    sheet_method)."""

    def __init__(self, mesh, faces=None, **build_options):
        if isinstance(mesh, (str, os.PathLike)) and faces is None:
            self.path = os.fspath(mesh)
            self.vertices = self.faces = None
            try:  # a file rewritten since is another source: workers build it anew
                stat = os.stat(self.path)
                self.file_version = (stat.st_mtime_ns, stat.st_size)
            except OSError:
                self.file_version = None  # the workers report the error
        else:
            if faces is None:
                mesh, faces = gwnrt._mesh_arrays(mesh)
            self.path = None
            self.vertices = np.ascontiguousarray(mesh, dtype=np.float32)
            self.faces = np.ascontiguousarray(faces, dtype=np.int64)  # one token whatever the integer type
            self.file_version = None
        self.build_options = build_options
        # The key of the workers' model cache: the file and options, or the arrays' contents.
        self.token = dask.base.tokenize(self.path, self.file_version, self.vertices, self.faces,
                                        sorted(build_options.items()))

    def __dask_tokenize__(self):
        return self.token

    def build(self, threads: Optional[int] = None) -> gwnrt.Model:
        if self.path is not None:
            return gwnrt.load(self.path, threads=threads, **self.build_options)
        return gwnrt.Model(self.vertices, self.faces, threads=threads, **self.build_options)

    def __repr__(self) -> str:
        what = self.path if self.path is not None else f"{len(self.vertices)} vertices, {len(self.faces)} faces"
        return f"gwnrt.dask.ModelSource({what})"


# -- the worker side ------------------------------------------------------------------------------
# Models built in this process, by ModelSource.token (the few most recent), and what was done here.
_KEEP_MODELS = 4
_models: "collections.OrderedDict[str, list]" = collections.OrderedDict()
_models_lock = threading.Lock()
_stats = collections.Counter()


def _worker_threads() -> Optional[int]:
    """The TBB threads a chunk may use: the distributed worker's thread count inside one."""
    try:
        from distributed import get_worker
        worker = get_worker()
    except (ImportError, ValueError):
        return None
    state = getattr(worker, "state", None)  # distributed >= 2022.11 keeps it there
    return getattr(state, "nthreads", None) or getattr(worker, "nthreads", None)


def _model_for(source: ModelSource, threads: Optional[int]) -> gwnrt.Model:
    """The model of `source`, built once in this process (concurrent chunks wait for one build)."""
    with _models_lock:
        entry = _models.get(source.token)
        if entry is None:
            entry = _models[source.token] = [threading.Lock(), None]
            while len(_models) > _KEEP_MODELS:
                _models.popitem(last=False)
        _models.move_to_end(source.token)
    with entry[0]:
        if entry[1] is None:
            entry[1] = source.build(threads)
            with _models_lock:
                _stats["models_built"] += 1
    return entry[1]


def worker_stats() -> dict:
    """In this process: models built, chunks and points evaluated (``client.run(worker_stats)``
    asks every worker)."""
    return {"pid": os.getpid(), **{k: _stats[k] for k in ("models_built", "chunks", "points")}}


def _query_chunk(points, source, fields, options, layout):
    options = dict(options)  # the graph's one dict, shared by the chunks of this process
    threads = options.pop("threads", None) or _worker_threads()
    model = _model_for(source, threads)
    columns = model.query(points, fields, threads=threads, **options)
    with _models_lock:  # a worker may run chunks on several threads
        _stats["chunks"] += 1
        _stats["points"] += len(points)
    if len(layout) == 1:
        return columns[layout[0][0]]
    packed = np.empty(len(points), dtype=np.dtype(layout))
    for key, _, _ in layout:
        packed[key] = columns[key]
    return packed


# -- the client side ------------------------------------------------------------------------------
def _as_source(model_source):
    """A ModelSource (or a distributed Future of one) for what the caller gave."""
    if isinstance(model_source, gwnrt.Model):
        raise TypeError("pass a path or gwnrt.dask.ModelSource(vertices, faces), not a gwnrt.Model: "
                        "each worker builds its own model")
    if isinstance(model_source, (str, os.PathLike)):
        return ModelSource(model_source)
    if isinstance(model_source, ModelSource):
        if model_source.vertices is None:
            return model_source  # a path: a few bytes in every task
        # Arrays: one key of the graph that every chunk's task depends on, so that each worker
        # receives them once, whichever scheduler runs the graph.
        return dask.delayed(model_source, pure=True)
    try:
        from distributed import Future
        if isinstance(model_source, Future):  # the caller scattered a ModelSource
            return model_source
    except ImportError:
        pass
    raise TypeError(f"model_source must be a path, a gwnrt.dask.ModelSource or a Future of one, "
                    f"got {type(model_source).__name__}")


def _as_points(points):
    if not isinstance(points, da.Array):
        points = da.from_array(np.asarray(points), chunks=(1 << 20, 3))
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (k, 3), got {points.shape}")
    return points.rechunk({1: 3})


def query(model_source, points, fields: Sequence[str], **options) -> dict:
    """The fields (as gwnrt.Model.query names them) at every point of a (k, 3) dask array
    (chunked by rows; a numpy array is chunked by 2^20 rows), as a dict of dask arrays: lazy,
    one task per chunk computing every field, on the worker's cached model (compute the arrays
    together, dask.compute(*result.values()), for one evaluation of each chunk). options: those
    of gwnrt.Model.query."""
    if isinstance(fields, str):
        fields = [fields]
    layout = [(key, np.dtype(dtype), tuple(trailing)) for key, dtype, trailing in _gwnrt.query_columns(list(fields))]
    points = _as_points(points)
    source = _as_source(model_source)
    if len(layout) == 1:
        key, dtype, trailing = layout[0]
        new_axis = list(range(1, 1 + len(trailing))) or None
        chunks = (points.chunks[0],) + tuple((n,) for n in trailing)
        result = points.map_blocks(_query_chunk, source, list(fields), dict(options), layout, dtype=dtype,
                                   chunks=chunks, drop_axis=1, new_axis=new_axis,
                                   meta=np.empty((0,) + trailing, dtype))
        return {key: result}
    packed_dtype = np.dtype(layout)
    packed = points.map_blocks(_query_chunk, source, list(fields), dict(options), layout, dtype=packed_dtype,
                               chunks=(points.chunks[0],), drop_axis=1, meta=np.empty((0,), packed_dtype))
    out = {}
    for key, dtype, trailing in layout:
        new_axis = list(range(1, 1 + len(trailing))) or None
        out[key] = packed.map_blocks(lambda block, key=key: block[key], dtype=dtype,
                                     chunks=(packed.chunks[0],) + tuple((n,) for n in trailing), new_axis=new_axis,
                                     meta=np.empty((0,) + trailing, dtype))
    return out


def _field(field, model_source, points, options):
    return gwnrt._field_result(field, query(model_source, points, [field], **options))


def winding_number(model_source, points, **options) -> da.Array:
    """w at every point (a lazy dask array); options: method, order, beta, threads."""
    return _field("w", model_source, points, options)


def gradient(model_source, points, **options) -> da.Array:
    return _field("gradient", model_source, points, options)


def hessian(model_source, points, **options) -> da.Array:
    return _field("hessian", model_source, points, options)


def unsigned_distance(model_source, points, **options) -> gwnrt.DistanceResult:
    return _field("unsigned_distance", model_source, points, options)


def boundary_distance(model_source, points, **options) -> gwnrt.BoundaryDistanceResult:
    return _field("boundary_distance", model_source, points, options)


def signed_distance(model_source, points, **options) -> gwnrt.SignedDistanceResult:
    return _field("signed_distance", model_source, points, options)


def project(model_source, points, **options) -> gwnrt.ProjectionResult:
    return _field("projection", model_source, points, options)


def harnack_bound(model_source, points, **options) -> da.Array:
    return _field("harnack_bound", model_source, points, options)


# -- meshing many files ---------------------------------------------------------------------------
def _mesh_file(job, build_options, options, file_format, threads):
    path, output = job
    report = {"path": path, "output": None, "seconds": 0.0, "vertices": 0, "triangles": 0, "watertight": None,
              "manifold": None, "closed_manifold": None, "message": None, "error": None}
    start = time.perf_counter()
    try:
        threads = threads or _worker_threads()
        model = gwnrt.load(path, threads=threads, **build_options)
        mesh = model.extract_surface(threads=threads, **options)
        gwnrt.write_mesh(output, mesh, format=file_format)
        topology = gwnrt.mesh_topology(mesh)
        report.update(output=output, vertices=len(mesh.vertices), triangles=len(mesh.faces),
                      watertight=topology["watertight"], manifold=topology["manifold"],
                      closed_manifold=topology["closed_manifold"], message=mesh.stats["message"])
    except Exception as e:  # reported, so that one bad file does not fail the others
        report["error"] = f"{type(e).__name__}: {e}"
    report["seconds"] = time.perf_counter() - start
    return report


def extract_surfaces(paths: Sequence, out_dir, *, format: str = "ply", threads: Optional[int] = None,
                     build_options: Optional[dict] = None, **options) -> list:
    """Meshes S of every file as one Dask bag task per file (on the active distributed client when
    there is one), writing OUT_DIR/<name>.<format>; returns one report per file, in order: path,
    output, seconds, vertices, triangles, watertight, manifold, closed_manifold, and error (None,
    or why that file failed: the others go on). options: those of gwnrt.Model.extract_surface.
    Raises ValueError, before any work, where an output would be one of the inputs."""
    if format not in ("ply", "obj", "stl"):
        raise ValueError(f"format must be 'ply', 'obj' or 'stl', got '{format}'")
    out_dir = os.fspath(out_dir)
    os.makedirs(out_dir, exist_ok=True)
    jobs, taken = [], set()
    for path in map(os.fspath, paths):
        stem = name = os.path.splitext(os.path.basename(path))[0]
        copy = 1
        while name in taken:  # two inputs of one name: stem-2, stem-3, ... whichever is free
            copy += 1
            name = f"{stem}-{copy}"
        taken.add(name)
        jobs.append((path, os.path.join(out_dir, f"{name}.{format}")))
    # An output on one of the inputs (OUT_DIR the inputs' folder, or a link to one) would destroy
    # it: refused before any task runs.
    inputs = [path for path, _ in jobs if os.path.exists(path)]
    for _, output in jobs:
        for path in inputs:
            if os.path.exists(output) and os.path.samefile(output, path):
                raise ValueError(f"{output}: the output is the input {path} (the same file), which writing it "
                                 f"would destroy; choose another out_dir")
    if not jobs:
        return []
    bag = db.from_sequence(jobs, npartitions=len(jobs))
    return bag.map(_mesh_file, build_options or {}, options, format, threads).compute()
