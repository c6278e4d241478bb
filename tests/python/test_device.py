"""device="cuda" against the CPU (skipped without a usable GPU, as the C++ CUDA tests are)."""

import os

import numpy as np
import pytest

import gwnrt

DATA = os.environ.get("GWNRT_DATA_DIR", os.path.join(os.path.dirname(__file__), "..", "..", "data"))

pytestmark = pytest.mark.skipif(not gwnrt.device_available(), reason=f"no GPU: {gwnrt.device_status()}")


def test_queries_traces_and_meshes_agree_with_the_cpu():
    model = gwnrt.load(os.path.join(DATA, "bunny_holes.obj"))
    lo, hi = model.bounds
    points = np.random.default_rng(5).uniform(lo, hi, (20000, 3)).astype(np.float32)
    for fields in (["w", "gradient"], ["unsigned_distance"], ["signed_distance"]):
        cpu = model.query(points, fields, device="cpu")
        gpu = model.query(points, fields, device="cuda")
        for key in cpu:
            # tests/cuda's tolerances: float rounding of one code path compiled twice.
            np.testing.assert_allclose(gpu[key].astype(np.float64), cpu[key].astype(np.float64), rtol=1e-4,
                                       atol=1e-4, err_msg=key)
    origins = np.broadcast_to((lo + hi) / 2 + np.array([0, 0, 20], np.float32), (1000, 3))
    directions = points[:1000] - origins
    cpu, gpu = model.trace(origins, directions), model.trace(origins, directions, device="cuda")
    assert np.mean(cpu.hit == gpu.hit) >= 0.999
    cpu_mesh, gpu_mesh = model.extract_surface(64), model.extract_surface(64, device="cuda")
    assert cpu_mesh.faces.shape == gpu_mesh.faces.shape
