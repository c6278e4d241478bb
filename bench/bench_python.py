#!/usr/bin/env python3
"""Benchmark of the Python module against its baselines, measured in the same run:

1. the Python batch (model.winding_number / model.signed_distance on a numpy array: conversion
   checks, output arrays, the GIL released) against the C++ batch as a C++ program calls it
   (gwnrt::evaluate_points into a PointResult array allocated once), interleaved, medians;
2. gwnrt.dask on a LocalCluster (n workers, one thread each, processes) against the in-process
   call on the same points (sent from the client: dask.array.from_array, the results gathered
   back), for several chunk sizes.

Prints a table; --json FILE writes the figures.

    PYTHONPATH=build/python python3 bench/bench_python.py --mesh data/bunny_holes.obj
"""

import argparse
import json
import os
import statistics
import sys
import time

import numpy as np

import gwnrt

HERE = os.path.dirname(os.path.abspath(__file__))


def box_points(model, count, seed):
    lo, hi = model.bounds
    pad = 0.1 * (hi - lo)
    return np.random.default_rng(seed).uniform(lo - pad, hi + pad, (count, 3)).astype(np.float32)


def timed(fn):
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def python_vs_cxx(model, points, repeats, threads):
    rows = []
    for name, fields, call in (
            ("w", ["w"], lambda: model.winding_number(points, threads=threads)),
            ("sdf", ["signed_distance"], lambda: model.signed_distance(points, threads=threads))):
        call()  # builds the parts the query reads, warms the caches
        python, cxx = [], []
        for _ in range(repeats):
            python.append(timed(call))
            cxx += gwnrt._gwnrt._cxx_batch_seconds(model._native, points, fields, repeats=1, threads=threads)
        p, c = statistics.median(python), statistics.median(cxx)
        rows.append({"query": name, "points": len(points), "python_per_s": len(points) / p,
                     "cxx_per_s": len(points) / c, "ratio": c / p, "python_s": python, "cxx_s": cxx})
    return rows


def dask_vs_in_process(mesh, model, count, chunk_sizes, workers, repeats):
    import dask.array as da
    from distributed import Client, LocalCluster

    import gwnrt.dask as gd

    points = box_points(model, count, 2)
    lo, hi = model.bounds
    in_process = statistics.median(timed(lambda: model.winding_number(points)) for _ in range(repeats))
    rows = []
    with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                      silence_logs=40) as cluster, Client(cluster) as client:
        client.run(lambda: None)
        for chunk in chunk_sizes:
            array = da.from_array(points, chunks=(chunk, 3))
            gd.winding_number(mesh, array[:workers * chunk]).compute()  # every worker builds its model
            seconds = statistics.median(timed(lambda: gd.winding_number(mesh, array).compute())
                                        for _ in range(repeats))
            rows.append({"chunk": chunk, "chunks": array.npartitions, "seconds": seconds, "per_s": count / seconds,
                         "ratio": in_process / seconds})
    return {"in_process_s": in_process, "in_process_per_s": count / in_process, "rows": rows}


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--mesh", default=os.path.join(HERE, "..", "..", "data", "bunny_holes.obj"))
    parser.add_argument("--points", type=float, default=1e6, help="points of the Python/C++ comparison")
    parser.add_argument("--dask-points", type=float, default=1e7, help="points of the Dask comparison (0: skip)")
    parser.add_argument("--chunks", default="100000,250000,1000000,2500000", help="Dask chunk sizes (rows)")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--threads", type=int, default=None, help="TBB threads of the in-process batches")
    parser.add_argument("--json", help="write the figures to this file")
    args = parser.parse_args()

    model = gwnrt.load(args.mesh)
    print(f"mesh {args.mesh}: {model.triangle_count} triangles, {os.cpu_count()} cores")
    report = {"mesh": args.mesh, "triangles": model.triangle_count, "cores": os.cpu_count()}

    report["python_vs_cxx"] = python_vs_cxx(model, box_points(model, int(args.points), 1), args.repeats, args.threads)
    print(f"\n{'query':6} {'points':>9} {'Python /s':>12} {'C++ /s':>12} {'Python/C++':>11}")
    for r in report["python_vs_cxx"]:
        print(f"{r['query']:6} {r['points']:9d} {r['python_per_s']:12.4g} {r['cxx_per_s']:12.4g} {r['ratio']:11.3f}")

    if args.dask_points > 0:
        chunks = [int(c) for c in args.chunks.split(",")]
        d = dask_vs_in_process(args.mesh, model, int(args.dask_points), chunks, args.workers, args.repeats)
        report["dask"] = d
        print(f"\nw on {int(args.dask_points)} points: in-process {d['in_process_per_s']:.4g}/s; "
              f"Dask, {args.workers} worker processes of 1 thread:")
        print(f"{'chunk':>9} {'chunks':>7} {'seconds':>8} {'per s':>11} {'/in-process':>12}")
        for r in d["rows"]:
            print(f"{r['chunk']:9d} {r['chunks']:7d} {r['seconds']:8.3f} {r['per_s']:11.4g} {r['ratio']:12.3f}")

    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=2)
    return 0


if __name__ == "__main__":
    sys.exit(main())
