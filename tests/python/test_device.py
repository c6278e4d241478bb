"""device="cuda" against the CPU (skipped without a usable GPU, as the C++ CUDA tests are)."""

import os

import numpy as np
import pytest

import gwnrt

DATA = os.environ.get("GWNRT_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "data"))

pytestmark = pytest.mark.skipif(not gwnrt.device_available(), reason=f"no GPU: {gwnrt.device_status()}")


# Columns that name a triangle or segment (and the barycentrics on it): where a point is nearest to
# an edge or vertex that several triangles share, they tie exactly and rounding picks either, so
# they are not compared; the distances they come with are.
TIE_COLUMNS = {"triangle", "barycentrics", "sheet_triangle", "boundary_segment"}


def compare_queries(cpu, gpu, diagonal):
    """tests/cuda's tolerances: float rounding of one code path compiled twice."""
    same_piece = np.ones(len(cpu[next(iter(cpu))]), bool)
    if "piece" in cpu:
        # Which part of S is nearest may go either way near a tie (as in tests/cuda: <= 0.5%).
        same_piece = cpu["piece"] == gpu["piece"]
        assert np.mean(same_piece) >= 0.995
    for key in cpu:
        if key in TIE_COLUMNS or key == "piece":
            continue
        a, b = cpu[key].astype(np.float64), gpu[key].astype(np.float64)
        if key in ("sdf", "sdf1", "sdf2"):
            # Where the pieces agree; sdf1, sdf2 are NaN where the sdf did not need them.
            a, b = a[same_piece], b[same_piece]
            np.testing.assert_allclose(b, a, rtol=1e-4, atol=1e-4 * diagonal, err_msg=key)
        else:
            np.testing.assert_allclose(b, a, rtol=1e-4, atol=1e-4, err_msg=key)


def test_queries_traces_and_meshes_agree_with_the_cpu():
    model = gwnrt.load(os.path.join(DATA, "bunny_holes.obj"))
    lo, hi = model.bounds
    diagonal = float(np.linalg.norm(np.asarray(hi) - np.asarray(lo)))
    points = np.random.default_rng(5).uniform(lo, hi, (20000, 3)).astype(np.float32)
    for fields in (["w", "gradient"], ["unsigned_distance"], ["signed_distance"]):
        compare_queries(model.query(points, fields, device="cpu"), model.query(points, fields, device="cuda"),
                        diagonal)
    origins = np.broadcast_to((lo + hi) / 2 + np.array([0, 0, 20], np.float32), (1000, 3))
    directions = points[:1000] - origins
    cpu, gpu = model.trace(origins, directions), model.trace(origins, directions, device="cuda")
    assert np.mean(cpu.hit == gpu.hit) >= 0.999
    cpu_mesh, gpu_mesh = model.extract_surface(64), model.extract_surface(64, device="cuda")
    assert cpu_mesh.faces.shape == gpu_mesh.faces.shape
