#!/usr/bin/env python3
"""The grid query on Dask: w on an n^3 grid over a mesh's box, the points made lazily chunk by
chunk on the workers, each worker building the model once.

    # a local cluster of 2 worker processes
    PYTHONPATH=build/python python3 examples/python/dask_grid.py data/bunny_holes.obj --grid 256
    # a running cluster (dask-scheduler / dask-worker started elsewhere), unchanged
    PYTHONPATH=build/python python3 examples/python/dask_grid.py data/bunny_holes.obj --scheduler tcp://host:8786

The workers read the mesh from its path, so on a real cluster it must be readable there under
the same path (or pass the arrays: gwnrt.dask.ModelSource(vertices, faces)).
"""

import argparse
import os
import sys
import time

import dask.array as da
import numpy as np
from distributed import Client, LocalCluster

import gwnrt
import gwnrt.dask as gd

HERE = os.path.dirname(os.path.abspath(__file__))


def grid_rows(index, lo, step, n):
    """The grid points of flat indices `index` (x fastest) as float32 rows."""
    x, y, z = index % n, (index // n) % n, index // (n * n)
    return (lo + step * np.stack([x, y, z], axis=1)).astype(np.float32)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mesh", nargs="?", default=os.path.join(HERE, "..", "..", "data", "bunny_holes.obj"))
    parser.add_argument("--grid", type=int, default=128, help="grid points per side")
    parser.add_argument("--chunk", type=int, default=1 << 20, help="points per task")
    parser.add_argument("--workers", type=int, default=2, help="local cluster: worker processes")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    parser.add_argument("--save-grid", help="write w, shape (n, n, n) indexed [z, y, x], as .npy")
    args = parser.parse_args()

    mesh = os.path.abspath(args.mesh)
    bounds = gwnrt.load(mesh, classify_sheets=False).bounds  # the workers build their own models
    pad = 0.05 * (bounds[1] - bounds[0])
    lo, step, n = bounds[0] - pad, (bounds[1] - bounds[0] + 2 * pad) / max(args.grid - 1, 1), args.grid

    if args.scheduler:
        client, cluster = Client(args.scheduler), None
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        index = da.arange(n ** 3, chunks=args.chunk)
        points = index.map_blocks(grid_rows, lo, step, n, new_axis=1, chunks=(index.chunks[0], (3,)),
                                  dtype=np.float32)
        w = gd.winding_number(mesh, points)
        start = time.perf_counter()
        if args.save_grid:
            values = w.compute()
            np.save(args.save_grid, values.reshape(n, n, n))
            inside = float(np.mean(values > 0.5))
        else:  # reduced on the workers: only a number comes back
            inside = float((w > 0.5).mean().compute())
        seconds = time.perf_counter() - start
        stats = client.run(gd.worker_stats)
        built = sum(s["models_built"] for s in stats.values())
        print(f"w on {n ** 3} grid points in {seconds:.3f} s ({n ** 3 / seconds:.3g}/s) on {len(stats)} workers "
              f"({built} model builds, {w.npartitions} chunks): {inside:.1%} inside")
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
