"""gwnrt.dask on a distributed cluster of 2 worker processes: the same values as the in-process
call, the model built once per worker, and meshing several files with one broken."""

import os
import shutil

import numpy as np
import pytest

import gwnrt

dask_array = pytest.importorskip("dask.array")
distributed = pytest.importorskip("distributed")
gd = pytest.importorskip("gwnrt.dask")

DATA = os.environ.get("GWNRT_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "data"))
BUNNY_HOLES = os.path.join(DATA, "bunny_holes.obj")


@pytest.fixture(scope="module")
def client():
    # Connected by the scheduler's address, as to a cluster on other machines.
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                  silence_logs=40) as cluster:
        with distributed.Client(cluster.scheduler_address) as c:
            yield c


def points_in_box(model, count, seed):
    lo, hi = model.bounds
    pad = 0.1 * (hi - lo)
    return np.random.default_rng(seed).uniform(lo - pad, hi + pad, (count, 3)).astype(np.float32)


def stats(client):
    return client.run(gd.worker_stats)


def deltas(before, after):
    return {w: {k: after[w][k] - before[w][k] for k in ("models_built", "chunks", "points")} for w in after}


def check_built_once_per_worker(before, after, chunks, points):
    d = deltas(before, after)
    assert sum(v["chunks"] for v in d.values()) == chunks
    assert sum(v["points"] for v in d.values()) == points
    for worker, v in d.items():
        # Every worker that evaluated a chunk built the model once; none built it twice.
        assert v["models_built"] == (1 if v["chunks"] else 0), (worker, v)


def test_winding_number_from_path_equals_in_process(client):
    model = gwnrt.load(BUNNY_HOLES)
    points = points_in_box(model, 10**6, 1)
    expected = model.winding_number(points)
    before = stats(client)
    w = gd.winding_number(BUNNY_HOLES, dask_array.from_array(points, chunks=(125000, 3)))
    assert w.shape == (10**6,) and w.dtype == np.float32 and w.npartitions == 8
    got = w.compute()
    np.testing.assert_array_equal(got, expected)  # the same code on the same floats
    check_built_once_per_worker(before, stats(client), chunks=8, points=10**6)
    # A second computation reuses the workers' models.
    before = stats(client)
    np.testing.assert_array_equal(w.compute(), expected)
    assert all(v["models_built"] == 0 for v in deltas(before, stats(client)).values())


def test_arrays_scattered_once_and_several_fields(client):
    model = gwnrt.load(BUNNY_HOLES)
    source = gd.ModelSource(model.vertices, model.faces)
    points = points_in_box(model, 200000, 2)
    before = stats(client)
    x = dask_array.from_array(points, chunks=(25000, 3))
    sdf = gd.signed_distance(source, x)
    dist = gd.unsigned_distance(source, x)
    grad = gd.gradient(source, x)
    got_sdf, got_piece, got_distance, got_bary, got_grad = __import__("dask").compute(
        sdf.sdf, sdf.piece, dist.distance, dist.barycentrics, grad)
    expected_sdf = model.signed_distance(points)
    expected_dist = model.unsigned_distance(points)
    np.testing.assert_array_equal(got_sdf, expected_sdf.sdf)
    np.testing.assert_array_equal(got_piece, expected_sdf.piece)
    np.testing.assert_array_equal(got_distance, expected_dist.distance)
    np.testing.assert_array_equal(got_bary, expected_dist.barycentrics)
    np.testing.assert_array_equal(got_grad, model.gradient(points))
    assert got_grad.shape == (200000, 3) and got_bary.shape == (200000, 2)
    d = deltas(before, stats(client))
    for worker, v in d.items():
        assert v["models_built"] <= 1, (worker, v)  # one model for the three queries
    assert sum(v["models_built"] for v in d.values()) >= 1


def test_a_scattered_source(client):
    model = gwnrt.load(BUNNY_HOLES)
    future = client.scatter(gd.ModelSource(model.vertices, model.faces, level=0.5), broadcast=True)
    points = points_in_box(model, 100000, 4)
    w = gd.winding_number(future, dask_array.from_array(points, chunks=(25000, 3))).compute()
    np.testing.assert_array_equal(w, model.winding_number(points))


def test_a_rewritten_file_is_built_again(client, tmp_path):
    path = tmp_path / "mesh.obj"
    shutil.copy(BUNNY_HOLES, path)
    points = points_in_box(gwnrt.load(BUNNY_HOLES), 20000, 5)
    x = dask_array.from_array(points, chunks=(5000, 3))
    before = gd.winding_number(path, x).compute()
    path.write_text("v -9 -9 -9\nv -8 -9 -9\nv -9 -8 -9\nf 1 2 3\n")  # far from the points
    after = gd.winding_number(path, x).compute()
    np.testing.assert_array_equal(after, gwnrt.load(path).winding_number(points))
    assert not np.array_equal(after, before)


def test_bad_points_fail_with_the_libraries_message(client):
    points = np.zeros((1000, 3), dtype=np.float32)
    points[777] = np.nan
    w = gd.winding_number(BUNNY_HOLES, dask_array.from_array(points, chunks=(500, 3)))
    with pytest.raises(ValueError, match="point 277"):  # its index within its chunk
        w.compute()
    with pytest.raises(ValueError, match=r"shape \(k, 3\)"):
        gd.winding_number(BUNNY_HOLES, dask_array.zeros((10, 2)))
    assert set(gd.query(BUNNY_HOLES, points[:10], "w")) == {"w"}  # one field name, not its letters
    with pytest.raises(TypeError, match="ModelSource"):
        gd.winding_number(gwnrt.load(BUNNY_HOLES), points)


def test_extract_surfaces_reports_each_file(client, tmp_path):
    inputs = tmp_path / "in"
    inputs.mkdir()
    shutil.copy(os.path.join(DATA, "bunny.obj"), inputs / "bunny.obj")
    shutil.copy(BUNNY_HOLES, inputs / "holes.obj")
    broken = inputs / "broken.obj"
    broken.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n")  # a face past the vertices
    paths = [inputs / "bunny.obj", broken, inputs / "holes.obj"]
    reports = gd.extract_surfaces(paths, tmp_path / "out", resolution=48)
    assert [r["path"] for r in reports] == [os.fspath(p) for p in paths]
    # Inputs of one name (and one named like a renamed copy) get outputs of their own.
    (inputs / "again").mkdir()
    shutil.copy(inputs / "holes.obj", inputs / "again" / "holes.obj")
    shutil.copy(inputs / "holes.obj", inputs / "holes-2.obj")
    same_names = gd.extract_surfaces([inputs / "holes.obj", inputs / "again" / "holes.obj", inputs / "holes-2.obj"],
                                     tmp_path / "same", resolution=16)
    outputs = [r["output"] for r in same_names]
    assert len(set(outputs)) == 3 and all(os.path.exists(o) for o in outputs), outputs
    good = [reports[0], reports[2]]
    for r in good:
        assert r["error"] is None, r
        assert r["closed_manifold"] and r["watertight"] and r["manifold"]
        assert r["triangles"] > 1000 and r["seconds"] > 0
        written = gwnrt.load(r["output"], classify_sheets=False)  # readable, and what was reported
        assert written.triangle_count == r["triangles"]
    assert reports[1]["output"] is None
    assert "broken.obj" in reports[1]["error"] and reports[1]["error"].startswith("ValueError")


def test_extract_surfaces_never_overwrites_an_input(client, tmp_path):
    # Into the inputs' own folder in their format, or where another input has the output's name
    # (x.obj's output x.ply is the input x.ply): refused before any task, every input intact.
    shutil.copy(BUNNY_HOLES, tmp_path / "holes.obj")
    shutil.copy(BUNNY_HOLES, tmp_path / "x.obj")
    (tmp_path / "x.ply").write_bytes(b"not a mesh, but the user's file")
    before = {p.name: p.read_bytes() for p in tmp_path.iterdir()}
    for paths, fmt, clash in (([tmp_path / "holes.obj"], "obj", "holes.obj"),
                              ([tmp_path / "x.obj", tmp_path / "x.ply"], "ply", "x.ply")):
        with pytest.raises(ValueError, match=f"the output is the input .*{clash}"):
            gd.extract_surfaces(paths, tmp_path, format=fmt, resolution=16)
    assert {p.name: p.read_bytes() for p in tmp_path.iterdir()} == before
    # Elsewhere it writes.
    (report,) = gd.extract_surfaces([tmp_path / "holes.obj"], tmp_path / "out", format="obj", resolution=16)
    assert report["error"] is None and os.path.exists(report["output"])


def test_threaded_scheduler_without_a_client():
    # No distributed client in this test's scope: dask's default threaded scheduler.
    model = gwnrt.load(BUNNY_HOLES)
    points = points_in_box(model, 50000, 3)
    with __import__("dask").config.set(scheduler="threads"):
        w = gd.winding_number(gd.ModelSource(model.vertices, model.faces), points).compute()
        # Every other point query gives the in-process call's result, named alike.
        for name in ("hessian", "boundary_distance", "project", "harnack_bound"):
            (got,) = __import__("dask").compute(getattr(gd, name)(BUNNY_HOLES, points[:3000]))
            expected = getattr(model, name)(points[:3000])
            assert type(got) is type(expected), name
            for a, b in zip(got, expected) if isinstance(expected, tuple) else [(got, expected)]:
                np.testing.assert_array_equal(a, b, err_msg=name)
    np.testing.assert_array_equal(w, model.winding_number(points))
