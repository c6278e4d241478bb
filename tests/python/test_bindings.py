"""The Python bindings' handling of inputs (dtypes, layouts, shapes, bad values, meshes, files),
threads (Python threads sharing a model, the threads= argument), memory (no copy of float32
C-contiguous points) and the device= argument. The values themselves are checked against numpy
references in test_queries.py, test_trace.py and test_meshing_py.py."""

import contextlib
import gc
import re
import threading
import time
import tracemalloc

import numpy as np
import pytest

import gwnrt
import reference_np as ref

ALL_FIELDS = ["w", "gradient", "hessian", "unsigned_distance", "boundary_distance", "signed_distance",
              "pseudo_distance", "sheet_distance", "projection", "harnack_bound"]

# The columns each field returns, with their dtype and trailing shape.
COLUMNS = {
    "w": (np.float32, ()), "gradient": (np.float32, (3,)), "hessian": (np.float32, (3, 3)),
    "distance": (np.float32, ()), "triangle": (np.int32, ()), "barycentrics": (np.float32, (2,)),
    "boundary_distance": (np.float32, ()), "boundary_segment": (np.int32, ()),
    "sdf": (np.float32, ()), "piece": (np.uint8, ()), "sdf1": (np.float32, ()), "sdf2": (np.float32, ()),
    "sheet_distance": (np.float32, ()), "sheet_triangle": (np.int32, ()),
    "projection": (np.float32, (3,)), "iterations": (np.uint32, ()), "converged": (np.bool_, ()),
    "residual": (np.float32, ()), "harnack_bound": (np.float32, ()),
}


@pytest.fixture(scope="module")
def model(open_cube):
    return gwnrt.Model(open_cube)


@pytest.fixture(scope="module")
def points32(open_cube):
    return ref.points_around(open_cube.vertices, 400, 1, pad=0.3).astype(np.float32)


def assert_same_results(a, b):
    assert a.keys() == b.keys()
    for key in a:
        assert a[key].dtype == b[key].dtype and a[key].shape == b[key].shape, key
        np.testing.assert_array_equal(a[key], b[key], err_msg=key)  # NaNs compare equal here


# -- points: dtypes, layouts, shapes, values --------------------------------------------------------

def test_query_columns_shapes_and_dtypes(model, points32):
    r = model.query(points32, ALL_FIELDS)
    assert r.keys() == COLUMNS.keys()
    for key, (dtype, trailing) in COLUMNS.items():
        assert r[key].dtype == dtype and r[key].shape == (len(points32),) + trailing, key
        assert r[key].flags.c_contiguous and r[key].flags.writeable, key


@pytest.mark.parametrize("convert", [
    lambda p: p.astype(np.float64),
    lambda p: p.tolist(),
    lambda p: p.astype(np.float64).tolist(),
    lambda p: p.astype(">f4"),  # big-endian
    lambda p: p.astype(np.float16),
], ids=["float64", "list", "float64_list", "big_endian", "float16"])
def test_point_dtypes_give_the_float32_result(model, points32, convert):
    converted = convert(points32)
    expected = model.query(np.ascontiguousarray(np.asarray(converted), dtype=np.float32), ALL_FIELDS)
    assert_same_results(model.query(converted, ALL_FIELDS), expected)


def test_integer_points(model):
    ints = [[0, 0, 0], [1, 2, 3], [2, 0, 1]]
    expected = model.query(np.array(ints, dtype=np.float32), ALL_FIELDS)
    assert_same_results(model.query(ints, ALL_FIELDS), expected)
    for dtype in (np.int32, np.int64, np.uint8):
        assert_same_results(model.query(np.array(ints, dtype=dtype), ALL_FIELDS), expected)


@pytest.mark.parametrize("view", [
    lambda p: p[::2],
    lambda p: np.asfortranarray(p),
    lambda p: p[::-1],
    lambda p: np.column_stack([p, p[:, :1]])[:, :3],  # rows padded to 4 floats
    lambda p: np.ascontiguousarray(p.T).T,
    lambda p: p.astype(np.float64)[1::3],
], ids=["every_other", "fortran", "reversed", "row_stride", "transposed", "float64_strided"])
def test_non_contiguous_views_equal_their_copy(model, points32, view):
    v = view(points32)
    assert not v.flags.c_contiguous or v.dtype != np.float32
    copy = np.ascontiguousarray(v, dtype=np.float32)
    assert_same_results(model.query(v, ALL_FIELDS), model.query(copy, ALL_FIELDS))
    t = model.trace(v, [0.0, 0.0, 1.0])
    u = model.trace(copy, [0.0, 0.0, 1.0])
    for a, b in zip(t, u):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("empty", [np.empty((0, 3)), np.empty((0, 3), dtype=np.float32), []],
                         ids=["float64", "float32", "list"])
def test_empty_points(model, empty):
    r = model.query(empty, ALL_FIELDS)
    for key, (dtype, trailing) in COLUMNS.items():
        assert r[key].dtype == dtype and r[key].shape == (0,) + trailing, key
    assert model.winding_number(empty).shape == (0,)
    assert model.gradient(empty).shape == (0, 3)
    assert model.hessian(empty).shape == (0, 3, 3)
    d = model.unsigned_distance(empty)
    assert d.distance.shape == (0,) and d.triangle.shape == (0,) and d.barycentrics.shape == (0, 2)
    assert model.signed_distance(empty).sdf.shape == (0,)
    assert model.project(empty).point.shape == (0, 3)
    assert model.harnack_bound(empty).shape == (0,)
    t = model.trace(empty, np.empty((0, 3)))
    assert t.hit.shape == (0,) and t.position.shape == (0, 3) and t.normal.shape == (0, 3)


@pytest.mark.parametrize("points, shape", [
    (np.zeros((4, 2)), "(4, 2)"),
    (np.zeros((4, 4)), "(4, 4)"),
    (np.zeros(3), "(3,)"),
    (np.zeros((2, 2, 3)), "(2, 2, 3)"),
    ([[1.0, 2.0]], "(1, 2)"),
])
def test_wrong_point_shapes(model, points, shape):
    for call in (model.winding_number, model.unsigned_distance, model.signed_distance, model.harnack_bound):
        with pytest.raises(ValueError, match=r"points must have shape \(k, 3\), got " + re.escape(shape)):
            call(points)
    if np.ndim(points) != 1:  # trace takes a (3,) origin as one row for every ray
        with pytest.raises(ValueError, match=r"origins must have shape \(k, 3\), got " + re.escape(shape)):
            model.trace(points, [0.0, 0.0, 1.0])


@pytest.mark.parametrize("points", [np.empty((5, 0)), np.empty((0, 2)), np.empty((0, 3, 3))],
                         ids=["5x0", "0x2", "0x3x3"])
def test_empty_points_of_the_wrong_shape(model, points):
    with pytest.raises(ValueError, match="shape"):
        model.winding_number(points)


@pytest.mark.parametrize("points", ["abc", [[1, 2, 3], [4, 5]], np.zeros((2, 3), dtype=complex),
                                    np.array([[1, 2, 3]], dtype=object)],
                         ids=["string", "ragged", "complex", "object"])
def test_points_not_real_numbers(model, points):
    with pytest.raises(ValueError, match="points must"):
        model.winding_number(points)


@pytest.mark.parametrize("value, index", [(np.nan, 6), (np.inf, 3), (-np.inf, 0), (1e30, 9)])
def test_non_finite_points_name_the_point(model, value, index):
    points = np.zeros((10, 3))
    points[index, 1] = value
    for call in (model.winding_number, model.gradient, model.unsigned_distance, model.boundary_distance,
                 model.signed_distance, model.project, model.harnack_bound):
        with pytest.raises(ValueError, match=f"point {index} "):
            call(points)
    with pytest.raises(ValueError, match=f"point {index} "):
        model.query(points.astype(np.float32), ["w"])


def test_bad_options(model, points32):
    p = points32[:4]
    cases = [
        (dict(method="bogus"), "method must be 'auto', 'crossing', 'taylor' or 'brute', got 'bogus'"),
        (dict(method="taylor", order=3), "Taylor order must be 0, 1 or 2, got 3"),
        (dict(method="taylor", order=-1), "Taylor order must be 0, 1 or 2, got -1"),
        (dict(beta=0.0), "beta must be a finite number >= 1"),
        (dict(beta=-2.0), "beta must be a finite number >= 1"),
        (dict(beta=0.1), "beta must be a finite number >= 1"),  # gave w 0.35 where the exact is -0.019
        (dict(beta=0.999), "beta must be a finite number >= 1"),
        (dict(beta=float("nan")), "beta must be a finite number >= 1"),
        (dict(beta=float("inf")), "beta must be a finite number >= 1"),
    ]
    for kwargs, message in cases:
        with pytest.raises(ValueError, match=re.escape(message)):
            model.winding_number(p, **kwargs)
        with pytest.raises(ValueError, match=re.escape(message)):
            model.query(p, ["gradient", "signed_distance"], **kwargs)
    # The tracer and the mesher take the same range (beta 0.1 traced a smooth hit at t = 7.62
    # where the sheet is at 5.56).
    for call in (lambda: model.trace(p, [0.0, 0.0, 1.0], beta=0.5), lambda: model.extract_surface(8, beta=0.5)):
        with pytest.raises(ValueError, match=r"beta must be a finite number >= 1 \(.*\), got 0\.5"):
            call()
    with pytest.raises(ValueError, match="unknown field 'nope'"):
        model.query(p, ["w", "nope"])
    with pytest.raises(ValueError, match="fields must name at least one"):
        model.query(p, [])
    assert set(model.query(p, "gradient")) == {"gradient"}  # one name, not its letters
    with pytest.raises(ValueError, match="level w\\* must be a finite number"):
        model.project(p, level=float("nan"))
    with pytest.raises(ValueError, match="Newton options"):
        model.project(p, tolerance=-1.0)
    with pytest.raises(ValueError, match="classified for level 0.5"):
        model.signed_distance(p, level=0.3)  # the sheets are for 1/2
    with pytest.raises(ValueError, match="mode must be 'gwn'"):
        model.trace(p, [0.0, 0.0, 1.0], mode="bogus")
    with pytest.raises(ValueError, match="winding_method|method must be"):
        model.extract_surface(8, winding_method="bogus")
    # Integers out of their range are ValueErrors naming the argument, not pybind11's TypeErrors.
    for call, name in ((lambda: model.project(p, max_iterations=-1), "max_iterations"),
                       (lambda: model.trace(p, [0.0, 0.0, 1.0], max_steps=-1), "max_steps"),
                       (lambda: model.trace(p, [0.0, 0.0, 1.0], max_crossings=2**40), "max_crossings"),
                       (lambda: model.extract_surface(8, memory_budget=-1), "memory_budget"),
                       (lambda: model.extract_surface(2**40), "resolution"),
                       (lambda: model.winding_number(p, order=2**40), "order")):
        with pytest.raises(ValueError, match=name + ".* must lie in"):
            call()
    # Trace inputs of the wrong shapes.
    with pytest.raises(ValueError, match=r"origins must have shape \(k, 3\), got \(\)"):
        model.trace(1.0, [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="origins has 2 rows and directions 3"):
        model.trace(p[:2], p[:3])
    assert len(model.trace([0.0, 0.0, 0.0], np.empty((0, 3))).hit) == 0  # one origin, no rays


def test_inputs_that_cannot_be_converted_raise(model):
    # A conversion numpy cannot allocate (10^12 rows broadcast from one) is a MemoryError, not a crash.
    huge = np.broadcast_to(np.float64([0.0, 0.0, 0.0]), (10**12, 3))
    with pytest.raises(MemoryError):
        model.winding_number(huge)
    with pytest.raises(MemoryError):
        gwnrt.Model(np.eye(3), np.broadcast_to(np.int32([0, 1, 2]), (10**12, 3)))


def test_misaligned_float32_points_are_copied(model, points32):
    raw = np.zeros(points32.nbytes + 1, dtype=np.uint8)
    misaligned = np.frombuffer(raw.data, dtype=np.float32, count=points32.size, offset=1).reshape(-1, 3)
    misaligned[...] = points32  # frombuffer of a writable buffer is writable
    assert not misaligned.flags.aligned
    np.testing.assert_array_equal(model.winding_number(misaligned), model.winding_number(points32))


# -- meshes and files ------------------------------------------------------------------------------

def test_model_properties(tetrahedron):
    v, f = tetrahedron
    model = gwnrt.Model(v, f)
    np.testing.assert_array_equal(model.vertices, v.astype(np.float32))
    assert model.vertices.dtype == np.float32 and model.faces.dtype == np.int64
    np.testing.assert_array_equal(model.faces, f)
    assert (model.vertex_count, model.triangle_count) == (4, 4)
    np.testing.assert_array_equal(model.bounds, np.float32([v.min(axis=0), v.max(axis=0)]))
    assert model.sheet_level == 0.5 and model.boundary_segment_count == 0
    assert repr(model) == "gwnrt.Model(4 vertices, 4 triangles)"
    copy = model.vertices
    copy[:] = 0  # a copy: the model keeps its mesh
    assert model.vertices.any()


def test_model_without_sheets(open_cube):
    model = gwnrt.Model(open_cube, classify_sheets=False)
    assert model.sheet_level is None
    with pytest.raises(ValueError, match="built without them"):
        model.signed_distance([[0.0, 0.0, 0.0]])
    model.winding_number([[0.0, 0.0, 0.0]])  # w needs no sheets
    model.set_sheet_level(0.5)
    assert model.sheet_level == 0.5
    assert model.signed_distance([[0.0, 0.0, 0.0]]).sdf[0] < 0
    with pytest.raises(ValueError, match="finite"):
        model.set_sheet_level(float("nan"))


class TinyMesh:
    def __init__(self, vertices, faces):
        self.vertices, self.faces = vertices, faces


class TinyOpen3dMesh:  # open3d's TriangleMesh names its faces .triangles
    def __init__(self, vertices, faces):
        self.vertices, self.triangles = vertices, faces


def test_model_from_an_object_with_vertices_and_faces(open_cube, points32):
    v, f = open_cube
    expected = gwnrt.Model(v, f).query(points32, ["w", "signed_distance"])
    for mesh in (TinyMesh(v.tolist(), f.tolist()), TinyMesh(v, f), TinyOpen3dMesh(v, f.astype(np.int32))):
        model = gwnrt.Model(mesh)
        assert (model.vertex_count, model.triangle_count) == (8, 10)
        assert_same_results(model.query(points32, ["w", "signed_distance"]), expected)
    with pytest.raises(TypeError, match="got object"):
        gwnrt.Model(object())


@pytest.mark.parametrize("change, message", [
    (lambda v, f: (v, f.astype(np.float64)),
     "faces must be an integer array of shape \\(m, 3\\), got dtype float64"),
    (lambda v, f: (v, f.astype(np.float32)), "got dtype float32"),
    (lambda v, f: (v, f.astype(bool)), "got dtype bool"),
    (lambda v, f: (v, np.where(np.arange(f.size).reshape(f.shape) == 7, -1, f)),
     "face 2 has vertex index -1, outside \\[0, 4\\)"),
    (lambda v, f: (v, np.where(np.arange(f.size).reshape(f.shape) == 9, 4, f)),
     "face 3 has vertex index 4, outside \\[0, 4\\)"),
    (lambda v, f: (v, np.where(np.arange(f.size).reshape(f.shape) == 5, np.uint64(2**64 - 1), f.astype(np.uint64))),
     "face 1 has vertex index 18446744073709551615, outside \\[0, 4\\)"),
    (lambda v, f: (v, f[:, :2]), "faces must have shape \\(m, 3\\), got \\(4, 2\\)"),
    (lambda v, f: (v, f.ravel()), "faces must have shape \\(m, 3\\), got \\(12,\\)"),
    (lambda v, f: (v[:, :2], f), "vertices must have shape \\(k, 3\\), got \\(4, 2\\)"),
    (lambda v, f: (np.where(np.arange(v.size).reshape(v.shape) == 4, np.nan, v), f),
     "vertex 1 has a non-finite coordinate"),
    (lambda v, f: (v, np.empty((0, 3), dtype=np.int64)), "no triangles"),
])
def test_bad_meshes(tetrahedron, change, message):
    v, f = change(*tetrahedron)
    with pytest.raises(ValueError, match=message):
        gwnrt.Model(v, f)


def test_model_options(tetrahedron):
    v, f = tetrahedron
    with pytest.raises(ValueError, match="level must be a finite number"):
        gwnrt.Model(v, f, level=float("inf"))
    with pytest.raises(ValueError, match="sheet_method must be"):
        gwnrt.Model(v, f, sheet_method="brute")
    with pytest.raises(ValueError, match="got 'bogus'"):
        gwnrt.Model(v, f, sheet_method="bogus")
    assert gwnrt.Model(v, f, level=0.25, sheet_method="taylor").sheet_level == 0.25


def test_load(data_dir):
    import os
    import pathlib
    model = gwnrt.load(pathlib.Path(data_dir) / "bunny_holes.obj")
    assert (model.vertex_count, model.triangle_count) == (1839, 3524)
    assert model.boundary_segment_count > 0
    assert gwnrt.load(os.path.join(data_dir, "bunny.obj")).boundary_segment_count == 0
    dragon = gwnrt.load(os.path.join(data_dir, "dragon_vrip_res4.ply"), classify_sheets=False)
    assert dragon.triangle_count > 0


def test_load_stl_welds_and_reports(data_dir, tmp_path):
    import os
    stl = os.path.join(data_dir, "realworld", "kuka_kr10r1100sixx_visual_base_link.stl")
    model = gwnrt.load(stl)
    report = model.load_report
    assert report["format"] == "stl-binary"
    assert (report["file_vertices"], report["positions_used"]) == (35592, 5969)
    assert (report["boundary_edges"], report["boundary_loops"], report["tolerance_welded"]) == (182, 34, 0)
    assert model.boundary_segment_count == 182
    welded = gwnrt.load(stl, weld_tolerance=1e-6)
    assert welded.load_report["tolerance_welded"] > 0
    assert welded.load_report["boundary_edges"] == 0 and welded.boundary_segment_count == 0
    with pytest.raises(ValueError, match="weld tolerance"):
        gwnrt.load(stl, weld_tolerance=0.5)
    assert gwnrt.Model(model.vertices, model.faces).load_report is None
    # Written as STL and read back: the same triangles.
    mesh = model.extract_surface(resolution=24)
    gwnrt.write_mesh(tmp_path / "out.stl", mesh)
    back = gwnrt.load(tmp_path / "out.stl", classify_sheets=False)
    assert back.triangle_count == len(mesh.faces)
    np.testing.assert_array_equal(back.vertices[back.faces], mesh.vertices[mesh.faces])


def test_load_errors(tmp_path):
    with pytest.raises(OSError, match="cannot open"):
        gwnrt.load(tmp_path / "missing.obj")
    cases = {
        "face_past_end.obj": ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "vertex index 7 is out of range"),
        "bad_number.obj": ("v 0 0 zz\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "malformed number 'zz'"),
        "no_triangles.obj": ("v 0 0 0\n", "no triangles"),
        "no_x.ply": ("ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nend_header\n1\n",
                     "no 'x' property"),
        "mesh.xyz": ("v 0 0 0\n", "unsupported mesh file extension"),
        "cut.stl": ("solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n", "ends inside facet 0"),
    }
    for name, (text, message) in cases.items():
        (tmp_path / name).write_text(text)
        with pytest.raises(ValueError, match=message):
            gwnrt.load(tmp_path / name)


# -- threads ----------------------------------------------------------------------------------------

def run_threads(count, target):
    errors = []

    def guarded(i):
        try:
            target(i)
        except BaseException as e:  # reported in the main thread
            errors.append((i, e))

    threads = [threading.Thread(target=guarded, args=(i,)) for i in range(count)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(60)
    assert not any(t.is_alive() for t in threads), "a thread hung"
    return errors


def test_python_threads_share_a_model(bunny_holes):
    points = [ref.points_around(bunny_holes.vertices, 3000, 100 + i, pad=0.2).astype(np.float32)
              for i in range(8)]
    expected = [(bunny_holes.winding_number(p), bunny_holes.signed_distance(p).sdf) for p in points]
    mismatches = []

    def work(i):
        for _ in range(6):
            w = bunny_holes.winding_number(points[i])
            sdf = bunny_holes.signed_distance(points[i]).sdf
            if not (np.array_equal(w, expected[i][0]) and np.array_equal(sdf, expected[i][1])):
                mismatches.append(i)

    assert run_threads(8, work) == []
    assert mismatches == []


@contextlib.contextmanager
def levels_toggled(model):
    """A thread classifying the model's sheets for 0.3 and 0.5 in turn while the block runs."""
    stop = threading.Event()

    def toggle():
        k = 0
        while not stop.is_set():
            model.set_sheet_level(0.3 if k % 2 == 0 else 0.5)
            k += 1

    toggler = threading.Thread(target=toggle)
    toggler.start()
    try:
        yield
    finally:
        stop.set()
        toggler.join(60)


def test_set_sheet_level_while_querying(data_dir):
    model = gwnrt.load(f"{data_dir}/bunny_holes.obj")
    points = [ref.points_around(model.vertices, 500, 200 + i, pad=0.2).astype(np.float32) for i in range(7)]
    w_expected = [model.winding_number(p) for p in points]
    sdf_expected = {}
    for level in (0.3, 0.5):
        model.set_sheet_level(level)
        sdf_expected[level] = [model.signed_distance(p).sdf for p in points]
    assert not np.array_equal(sdf_expected[0.3][0], sdf_expected[0.5][0])
    results = {"sdf": 0}

    def query(i):
        for _ in range(30):
            np.testing.assert_array_equal(model.winding_number(points[i]), w_expected[i])
            sdf = model.signed_distance(points[i]).sdf  # at the sheets' level, read under the batch's lock
            # Whole batches at one level or the other: set_sheet_level waits for running queries.
            assert np.array_equal(sdf, sdf_expected[0.3][i]) or np.array_equal(sdf, sdf_expected[0.5][i])
            results["sdf"] += 1

    with levels_toggled(model):
        errors = run_threads(7, query)
    assert errors == []
    # The level is kept as a float32: 0.3 reads back as 0.30000001192092896.
    assert results["sdf"] > 0 and model.sheet_level in (float(np.float32(0.3)), 0.5)


def test_signed_distance_default_level_never_mismatches(data_dir):
    model = gwnrt.load(f"{data_dir}/bunny_holes.obj")
    points = ref.points_around(model.vertices, 4, 300, pad=0.2).astype(np.float32)
    deadline = time.monotonic() + 2.0

    def query(i):
        while time.monotonic() < deadline:
            model.signed_distance(points)  # level None: whatever the sheets are classified for

    with levels_toggled(model):
        errors = run_threads(4, query)
    assert errors == [], errors[0]


# -- memory: float32 C-contiguous points are used in place ----------------------------------------

def test_float32_points_are_not_copied(tetrahedron):
    # numpy reports its allocations to tracemalloc, so the peak traced during the call counts the
    # output (10^7 float32 w: 40 MB) and any converted copy of the input (10^7 x 3 float32: 120 MB).
    # Taylor order 0 on a 4-triangle mesh keeps the call ~2 s on 2 cores.
    model = gwnrt.Model(tetrahedron)
    count = 10**7
    points32 = np.random.default_rng(0).random((count, 3), dtype=np.float32)
    points64 = points32.astype(np.float64)
    input_mb = points32.nbytes / 1e6
    peaks = {}
    gc.collect()
    tracemalloc.start()
    try:
        for name, points in (("float32", points32), ("float64", points64)):
            tracemalloc.reset_peak()
            before = tracemalloc.get_traced_memory()[0]
            w = model.winding_number(points, method="taylor", order=0)
            peaks[name] = (tracemalloc.get_traced_memory()[1] - before) / 1e6
            assert w.shape == (count,)
            del w
    finally:
        tracemalloc.stop()
    assert input_mb == 120
    assert peaks["float32"] < input_mb / 2, peaks  # the 40 MB output, no copy of the input
    assert peaks["float64"] > input_mb, peaks  # the float32 conversion shows (the test can fail)
    # The input is left as it was, and the values are right.
    sample = points32[:200].astype(np.float64)
    v, f = model.vertices.astype(np.float64), model.faces
    np.testing.assert_allclose(model.winding_number(points32[:200]), ref.winding_number(v, f, sample),
                               atol=1e-5)


# -- threads= and device= ---------------------------------------------------------------------------

def test_threads_argument(bunny_holes):
    points = ref.points_around(bunny_holes.vertices, 4000, 400, pad=0.2).astype(np.float32)
    one = bunny_holes.query(points, ALL_FIELDS, threads=1)
    for threads in (2, 0, None):
        assert_same_results(bunny_holes.query(points, ALL_FIELDS, threads=threads), one)
    rays = (np.array([0.0, 5.0, 20.0]), points - [0.0, 5.0, 20.0])
    for a, b in zip(bunny_holes.trace(*rays, threads=1), bunny_holes.trace(*rays, threads=2)):
        np.testing.assert_array_equal(a, b)
    m1, m2 = bunny_holes.extract_surface(32, threads=1), bunny_holes.extract_surface(32, threads=2)
    np.testing.assert_array_equal(m1.vertices, m2.vertices)
    np.testing.assert_array_equal(m1.faces, m2.faces)
    message = r"threads must lie in \[0, 1024\], got -1"
    for call in (lambda: bunny_holes.winding_number(points, threads=-1),
                 lambda: bunny_holes.query(points, ["signed_distance"], threads=-1),
                 lambda: bunny_holes.trace(*rays, threads=-1),
                 lambda: bunny_holes.extract_surface(16, threads=-1),
                 lambda: gwnrt.Model(bunny_holes.vertices, bunny_holes.faces, threads=-1)):
        with pytest.raises(ValueError, match=message):
            call()
    # Beyond the cap: 2**31 - 1 crashed inside TBB and 10**6 took 570 MB before it was checked.
    for threads in (1025, 10**6, 2**31 - 1, 2**40):
        with pytest.raises(ValueError, match=rf"threads must lie in \[0, 1024\], got {threads}"):
            bunny_holes.winding_number(points, threads=threads)
    with pytest.raises(ValueError, match=r"threads must lie in \[0, 1024\], got 2147483647"):
        gwnrt.Model(bunny_holes.vertices, bunny_holes.faces, threads=2**31 - 1)
    np.testing.assert_array_equal(bunny_holes.winding_number(points, threads=1024),
                                  bunny_holes.winding_number(points, threads=1))


def test_device_argument(model, points32):
    calls = (lambda device: model.winding_number(points32, device=device),
             lambda device: model.signed_distance(points32, device=device),
             lambda device: model.trace(points32, [0.0, 0.0, 1.0], device=device),
             lambda device: model.extract_surface(8, device=device))
    for call in calls:
        with pytest.raises(ValueError, match="device must be 'cpu', 'cuda' or 'auto', got 'bogus'"):
            call("bogus")
    # 'auto' runs where it can: the CPU without a usable GPU.
    np.testing.assert_array_equal(model.winding_number(points32, device="auto"),
                                  model.winding_number(points32))


@pytest.mark.skipif(gwnrt.device_available(), reason="a usable GPU: device='cuda' runs")
def test_cuda_unavailable_raises_runtime_error(model, points32):
    why = gwnrt.device_status()
    assert why  # says why
    for call in (lambda: model.winding_number(points32, device="cuda"),
                 lambda: model.trace(points32, [0.0, 0.0, 1.0], device="cuda"),
                 lambda: model.extract_surface(8, device="cuda")):
        with pytest.raises(RuntimeError, match="device='cuda'"):
            call()
