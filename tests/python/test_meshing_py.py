"""Model.extract_surface, write_mesh and mesh_topology from Python: the mesh of S checked with the
numpy references (distance to the source mesh, w on either side), the files written read back
with small parsers written here."""

import os

import numpy as np
import pytest

import gwnrt
import reference_np as ref


def mesh64(model):
    return model.vertices.astype(np.float64), model.faces


@pytest.fixture(scope="module")
def octahedron_surface(octahedron):
    model = gwnrt.Model(octahedron)
    return model, model.extract_surface(32, attributes=["source"])


@pytest.fixture(scope="module")
def bunny_surface(bunny):
    return bunny, bunny.extract_surface(64, attributes=["source"])


@pytest.fixture(scope="module", params=["octahedron", "bunny"])
def surface(request):
    return request.getfixturevalue(request.param + "_surface")


def sample_rows(count, limit, seed):
    return np.random.default_rng(seed).choice(count, min(count, limit), replace=False)


def test_extract_surface_is_closed_and_well_formed(surface):
    _, mesh = surface
    n = len(mesh.vertices)
    assert mesh.vertices.shape == (n, 3) and mesh.vertices.dtype == np.float32
    assert mesh.faces.ndim == 2 and mesh.faces.shape[1] == 3 and len(mesh.faces) > 100
    assert mesh.faces.min() >= 0 and mesh.faces.max() < n
    topology = gwnrt.mesh_topology(mesh.vertices, mesh.faces)
    assert topology["closed_manifold"], topology
    assert topology["boundary_edges"] == 0 and topology["unreferenced_vertices"] == 0
    assert gwnrt.mesh_topology(mesh) == topology  # a MeshResult has .vertices and .faces
    assert mesh.normals.shape == (n, 3)
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1.0, atol=1e-5)
    assert mesh.uvs is None and mesh.colors is None
    assert mesh.stats["message"] == "" and mesh.stats["cell_size"] > 0
    # The repair's counts: whatever it found, nothing is left.
    assert mesh.stats["self_intersections_left"] == 0
    assert mesh.stats["repaired_vertex_moves"] >= 0 and mesh.stats["repair_rounds"] >= 0


def test_extract_surface_lies_on_the_input(surface):
    model, mesh = surface
    v, f = mesh64(model)
    cell = mesh.stats["cell_size"]
    rows = sample_rows(len(mesh.vertices), 400, 1)
    x = mesh.vertices[rows].astype(np.float64)
    distance, _ = ref.unsigned_distance(v, f, x)
    # Dual contouring places each vertex in its cell, near the sheet it crosses: within a cell of
    # the input (measured 0.6 cell at the octahedron's corners, 0.2 on the bunny).
    assert distance.max() < cell, distance.max() / cell
    # Outward normals: the numpy w is 0 a third of a cell outside and 1 a third inside, at the
    # vertices within a sixth of a cell of M: all of them on the convex octahedron but for its six
    # tips (there the normal is an average and the offset leaves the narrow solid corner), nearly
    # all on the bunny (its thin ears may have both sides within reach).
    h = cell / 3
    near = distance < h / 2
    octahedron = len(f) == 8
    if octahedron:
        near &= np.linalg.norm(x[:, None] - v[None], axis=-1).min(axis=1) > cell
    assert near.mean() > 0.5
    x, n = x[near], mesh.normals[rows][near].astype(np.float64)
    outside = ref.winding_number(v, f, x + h * n) < 0.5
    inside = ref.winding_number(v, f, x - h * n) > 0.5
    assert outside.mean() >= 0.98 and inside.mean() >= 0.98
    if octahedron:
        assert outside.all() and inside.all()


def test_extract_surface_source_attributes(surface):
    model, mesh = surface
    v, f = mesh64(model)
    n = len(mesh.vertices)
    assert mesh.source_triangles.shape == (n,) and mesh.source_triangles.dtype == np.int32
    assert mesh.source_barycentrics.shape == (n, 2) and mesh.source_barycentrics.dtype == np.float32
    assert mesh.source_triangles.min() >= 0 and mesh.source_triangles.max() < len(f)
    # The source point (1-u-v) a + u b + v c is the point of M nearest the vertex.
    rows = sample_rows(n, 300, 2)
    x = mesh.vertices[rows].astype(np.float64)
    tri = mesh.source_triangles[rows]
    u, w = mesh.source_barycentrics[rows].astype(np.float64).T
    assert (u >= -1e-6).all() and (w >= -1e-6).all() and (u + w <= 1 + 1e-6).all()
    source = (1 - u - w)[:, None] * v[f[tri, 0]] + u[:, None] * v[f[tri, 1]] + w[:, None] * v[f[tri, 2]]
    distance, _ = ref.unsigned_distance(v, f, x)
    np.testing.assert_allclose(np.linalg.norm(source - x, axis=1), distance, atol=1e-6 * ref.box_diagonal(v))


def test_extract_surface_marching_cubes_closed(octahedron):
    mesh = gwnrt.Model(octahedron).extract_surface(24, method="mc")
    assert gwnrt.mesh_topology(mesh)["closed_manifold"]


def test_extract_surface_open_mesh_is_capped(open_cube):
    # The open cube's S: its walls plus a smooth cap over the hole, meshed closed.
    mesh = gwnrt.Model(open_cube).extract_surface(24)
    assert gwnrt.mesh_topology(mesh)["closed_manifold"]
    assert mesh.stats["smooth_edges"] > 0 and mesh.stats["sheet_edges"] > 0
    assert not gwnrt.mesh_topology(open_cube)["closed_manifold"]
    assert gwnrt.mesh_topology(open_cube)["boundary_edges"] == 4


def test_extract_surface_bad_options(octahedron):
    model = gwnrt.Model(octahedron)
    with pytest.raises(ValueError, match="method must be 'dc'"):
        model.extract_surface(8, method="bogus")
    with pytest.raises(ValueError, match="unknown attribute 'bogus'"):
        model.extract_surface(8, attributes=["bogus"])
    with pytest.raises(ValueError, match="resolution"):
        model.extract_surface(0)
    with pytest.raises(ValueError, match=r"resolution .* must lie in \[1, "):
        model.extract_surface(-1)
    with pytest.raises(ValueError, match="UVs"):
        model.extract_surface(8, attributes=["uv"])  # the octahedron has none
    with pytest.raises(MemoryError, match="memory budget"):
        model.extract_surface(64, memory_budget=1000)


def read_obj(path):
    """v and f lines of an OBJ (f entries as v, v//vn, v/vt/vn or v/vt: the first index, 1-based)."""
    vertices, normals, faces = [], [], []
    with open(path) as fh:
        for line in fh:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                vertices.append([float(x) for x in parts[1:4]])
            elif parts[0] == "vn":
                normals.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                faces.append([int(p.split("/")[0]) - 1 for p in parts[1:]])
    return np.array(vertices), np.array(normals), np.array(faces, dtype=np.int64)


PLY_TYPES = {"float": "<f4", "double": "<f8", "uint": "<u4", "int": "<i4", "uchar": "u1"}


def read_ply(path):
    """A binary little-endian PLY whose vertex properties are scalars and whose faces are
    `list uchar int` triangles: (vertex record array, faces)."""
    with open(path, "rb") as fh:
        data = fh.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    assert header[0] == "ply" and header[1] == "format binary_little_endian 1.0"
    elements, current = [], None
    for line in header:
        parts = line.split()
        if parts[0] == "element":
            current = (parts[1], int(parts[2]), [])
            elements.append(current)
        elif parts[0] == "property":
            current[2].append(parts[1:])
    (vname, vcount, vprops), (fname, fcount, fprops) = elements
    assert vname == "vertex" and fname == "face" and fprops == [["list", "uchar", "int", "vertex_indices"]]
    vtype = np.dtype([(p[1], PLY_TYPES[p[0]]) for p in vprops])
    verts = np.frombuffer(data, vtype, vcount, end)
    ftype = np.dtype([("n", "u1"), ("i", "<i4", 3)])
    faces = np.frombuffer(data, ftype, fcount, end + vcount * vtype.itemsize)
    assert (faces["n"] == 3).all() and end + vcount * vtype.itemsize + fcount * ftype.itemsize == len(data)
    return verts, faces["i"].astype(np.int64)


def test_write_mesh_obj_and_ply_read_back(bunny_surface, tmp_path):
    _, mesh = bunny_surface
    obj, ply = tmp_path / "bunny.obj", tmp_path / "bunny.ply"
    gwnrt.write_mesh(obj, mesh)
    gwnrt.write_mesh(str(ply), mesh)
    # OBJ: the shortest decimal text that reads back to the same float32.
    vertices, normals, faces = read_obj(obj)
    assert vertices.shape == mesh.vertices.shape and faces.shape == mesh.faces.shape
    np.testing.assert_array_equal(vertices.astype(np.float32), mesh.vertices)
    np.testing.assert_array_equal(normals.astype(np.float32), mesh.normals)
    np.testing.assert_array_equal(faces, mesh.faces)
    # PLY: the very floats.
    verts, faces = read_ply(ply)
    np.testing.assert_array_equal(np.column_stack([verts["x"], verts["y"], verts["z"]]), mesh.vertices)
    np.testing.assert_array_equal(np.column_stack([verts["nx"], verts["ny"], verts["nz"]]), mesh.normals)
    np.testing.assert_array_equal(faces, mesh.faces)
    # gwnrt reads both back.
    for path in (obj, ply):
        back = gwnrt.load(path, classify_sheets=False)
        assert (back.vertex_count, back.triangle_count) == (len(mesh.vertices), len(mesh.faces))
        np.testing.assert_array_equal(back.vertices, mesh.vertices)


def test_a_far_off_scan_is_loaded_recentred_and_written_back_where_it_lies(bunny, tmp_path):
    # The bunny at UTM coordinates (metres), written with every digit of the double sum.
    offset = np.array([512345.678, 4123456.789, 123.25])
    world = bunny.vertices.astype(np.float64) + offset
    path = tmp_path / "utm_bunny.obj"
    with open(path, "w") as fh:
        fh.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in world)
        fh.writelines(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in bunny.faces)
    with pytest.raises(ValueError, match="translate the mesh near the origin"):
        gwnrt.load(path)
    assert (bunny.origin == 0).all() and (gwnrt.Model(bunny.vertices, bunny.faces).origin == 0).all()
    far = gwnrt.load(path, recentre=True)
    assert (far.origin != 0).all()
    # float keeps the shape to its resolution about the origin (steps below 1e-6), not at 4e6 (0.25).
    np.testing.assert_allclose(far.vertices.astype(np.float64) + far.origin, world, rtol=0, atol=1e-6)

    # w at the same world points: the two models differ by float rounding (C++ measured 1.8e-7).
    rng = np.random.default_rng(3)
    lo, hi = bunny.bounds
    points = rng.uniform(lo - 1, hi + 1, (500, 3)).astype(np.float32)
    far_points = (points.astype(np.float64) + offset - far.origin).astype(np.float32)
    keep = bunny.unsigned_distance(points).distance >= 1e-2
    assert keep.sum() > 450
    np.testing.assert_allclose(far.winding_number(far_points, method="crossing")[keep],
                               bunny.winding_number(points, method="crossing")[keep], rtol=0, atol=1e-5)

    # The mesh of S written with the origin: doubles in PLY, at the near mesh's place + offset
    # (within 2e-3 cells, the tolerance of rounding differences, as in the C++ test).
    near_mesh, far_mesh = bunny.extract_surface(32), far.extract_surface(32)
    ply = tmp_path / "utm_surface.ply"
    gwnrt.write_mesh(ply, far_mesh, origin=far.origin)
    verts, faces = read_ply(ply)
    assert verts.dtype["x"] == np.float64
    xyz = np.column_stack([verts["x"], verts["y"], verts["z"]])
    assert xyz.shape == near_mesh.vertices.shape
    np.testing.assert_allclose(xyz, near_mesh.vertices.astype(np.float64) + offset, rtol=0,
                               atol=2e-3 * near_mesh.stats["cell_size"])
    with pytest.raises(ValueError, match="origin"):
        gwnrt.write_mesh(tmp_path / "bad.ply", far_mesh, origin=(0, float("nan"), 0))


def test_write_mesh_keeps_the_source_attributes_in_ply(bunny, tmp_path):
    mesh = bunny.extract_surface(32, attributes=["source"])
    path = tmp_path / "sourced.ply"
    gwnrt.write_mesh(path, mesh)
    verts, faces = read_ply(path)
    np.testing.assert_array_equal(verts["source_triangle"], mesh.source_triangles)
    np.testing.assert_array_equal(np.column_stack([verts["source_u"], verts["source_v"]]), mesh.source_barycentrics)
    np.testing.assert_array_equal(faces, mesh.faces)
    n = len(mesh.vertices)
    with pytest.raises(ValueError, match=r"source_triangles entry 0 has triangle index -1, outside \[0, 4294967296\)"):
        gwnrt.write_mesh(path, mesh.vertices, mesh.faces, source_triangles=-np.ones(n, np.int64))
    too_big = np.zeros(n, np.uint64)
    too_big[3] = 2**64 - 1  # unsigned: read as itself, not wrapped to -1
    with pytest.raises(ValueError, match="source_triangles entry 3 has triangle index 18446744073709551615"):
        gwnrt.write_mesh(path, mesh.vertices, mesh.faces, source_triangles=too_big)
    with pytest.raises(ValueError, match=r"source_triangles must have shape \(m,\), got \(%d, 1\)" % n):
        gwnrt.write_mesh(path, mesh.vertices, mesh.faces, source_triangles=np.zeros((n, 1), np.int32))
    with pytest.raises(ValueError, match="source_triangles must be an integer array of shape \\(m,\\), got dtype"):
        gwnrt.write_mesh(path, mesh.vertices, mesh.faces, source_triangles=np.zeros(n))


def test_write_mesh_arrays_and_format(tmp_path, octahedron):
    v, f = octahedron
    path = tmp_path / "no_extension"
    gwnrt.write_mesh(path, v, f, format="obj")
    vertices, normals, faces = read_obj(path)
    np.testing.assert_array_equal(vertices, v)
    np.testing.assert_array_equal(faces, f)
    assert normals.size == 0
    gwnrt.write_mesh(tmp_path / "octahedron.PLY", octahedron)  # an object with .vertices and .faces
    verts, faces = read_ply(tmp_path / "octahedron.PLY")
    assert verts.dtype.names == ("x", "y", "z")
    np.testing.assert_array_equal(faces, f)


def test_write_mesh_errors(tmp_path, octahedron):
    v, f = octahedron
    with pytest.raises(ValueError, match="format must be 'auto', 'ply', 'obj' or 'stl', got 'off'"):
        gwnrt.write_mesh(tmp_path / "x.obj", v, f, format="off")
    with pytest.raises(ValueError, match="extension"):
        gwnrt.write_mesh(tmp_path / "x.off", v, f)
    bad = f.copy()
    bad[5, 2] = len(v)
    with pytest.raises(ValueError, match=r"face 5 has vertex index 6, outside \[0, 6\)"):
        gwnrt.write_mesh(tmp_path / "x.obj", v, bad)
    bad[5, 2] = -2
    with pytest.raises(ValueError, match="face 5 has vertex index -2"):
        gwnrt.write_mesh(tmp_path / "x.obj", v, bad)
    with pytest.raises(ValueError, match="faces must be an integer array"):
        gwnrt.write_mesh(tmp_path / "x.obj", v, f.astype(np.float64))
    with pytest.raises(OSError):
        gwnrt.write_mesh(tmp_path / "missing_dir" / "x.obj", v, f)
    assert not os.path.exists(tmp_path / "x.obj")
