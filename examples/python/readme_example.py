#!/usr/bin/env python3
"""The README's Python examples, verbatim (tests/python/test_examples.py checks both)."""

import os
import sys
import tempfile


def library(path, out_dir):
    # [readme-python-begin]
    import numpy as np
    import gwnrt

    model = gwnrt.load(path)  # or gwnrt.Model(vertices, faces), or gwnrt.Model(trimesh_mesh)
    lo, hi = model.bounds
    points = np.random.default_rng(0).uniform(lo, hi, (100_000, 3)).astype(np.float32)

    w = model.winding_number(points)                # (k,) float32; method="auto" | "crossing" | "taylor" | "brute"
    sdf = model.signed_distance(points).sdf         # negative inside {w > 1/2}
    near = model.unsigned_distance(points)          # .distance, .triangle, .barycentrics
    hits = model.trace(lo - 1.0, (lo + hi) / 2 - (lo - 1.0))  # one ray: .hit, .t, .position, .normal, .kind

    mesh = model.extract_surface(resolution=128)    # .vertices, .faces, .normals: closed and manifold
    gwnrt.write_mesh(os.path.join(out_dir, "surface.ply"), mesh)
    # [readme-python-end]
    return w, sdf, near, hits, mesh


def on_dask(path):
    # [readme-dask-begin]
    import dask.array as da
    from distributed import Client
    import gwnrt.dask

    client = Client(n_workers=2, threads_per_worker=1)  # or Client("tcp://scheduler:8786")
    points = da.random.uniform(-1, 1, size=(10_000_000, 3), chunks=(1_000_000, 3)).astype("float32")
    w = gwnrt.dask.winding_number(path, points)  # lazy; each worker builds the model once
    inside = (w > 0.5).mean().compute()
    # [readme-dask-end]
    client.close()
    return inside


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..", "data",
                                                                 "bunny_holes.obj")
    with tempfile.TemporaryDirectory() as out_dir:
        w, sdf, near, hits, mesh = library(path, out_dir)
        print(f"w: {len(w)} values, sdf < 0 at {(sdf < 0).mean():.1%}, ray hit {bool(hits.hit[0])}, "
              f"mesh {len(mesh.faces)} triangles")
    if "--dask" in sys.argv:
        print(f"dask: {on_dask(os.path.abspath(path)):.1%} of the points inside")
    return 0


if __name__ == "__main__":
    sys.exit(main())
