#!/usr/bin/env python3
"""Load a triangle soup (or any mesh), query w on a grid over its box, and mesh its surface.

    PYTHONPATH=build/python python3 examples/python/soup_grid.py data/bunny_holes.obj --grid 64 -o out/bunny.ply

Prints the share of the grid inside (w > 1/2), writes the grid of w as .npy when asked, meshes
S = boundary of {w > 1/2} and says whether the result is closed and manifold.
"""

import argparse
import os
import sys
import time

import numpy as np

import gwnrt

HERE = os.path.dirname(os.path.abspath(__file__))


def grid_points(bounds, n):
    """n^3 points filling the box grown by 5% (x fastest), as float32 rows."""
    lo, hi = bounds
    pad = 0.05 * (hi - lo)
    axes = [np.linspace(lo[a] - pad[a], hi[a] + pad[a], n, dtype=np.float32) for a in range(3)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    return np.stack([x.ravel(), y.ravel(), z.ravel()], axis=1)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("mesh", nargs="?", default=os.path.join(HERE, "..", "..", "data", "bunny_holes.obj"))
    parser.add_argument("--grid", type=int, default=64, help="grid points per side")
    parser.add_argument("--resolution", type=int, default=128, help="meshing cells along the longest side")
    parser.add_argument("--save-grid", help="write w on the grid, shape (n, n, n) indexed [z, y, x], as .npy")
    parser.add_argument("-o", "--output", default="out/soup_grid.ply", help="the mesh of S (.ply or .obj)")
    args = parser.parse_args()

    model = gwnrt.load(args.mesh)
    print(f"{args.mesh}: {model.triangle_count} triangles, {model.boundary_segment_count} boundary edges")

    points = grid_points(model.bounds, args.grid)
    start = time.perf_counter()
    w = model.winding_number(points)
    seconds = time.perf_counter() - start
    print(f"w on {len(points)} grid points in {seconds:.3f} s ({len(points) / seconds:.3g}/s): "
          f"{np.mean(w > 0.5):.1%} inside, w in [{w.min():.3f}, {w.max():.3f}]")
    if args.save_grid:
        np.save(args.save_grid, w.reshape(args.grid, args.grid, args.grid))

    mesh = model.extract_surface(args.resolution)
    topology = gwnrt.mesh_topology(mesh)
    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    gwnrt.write_mesh(args.output, mesh)
    print(f"mesh of S: {len(mesh.vertices)} vertices, {len(mesh.faces)} triangles in {mesh.stats['seconds']:.3f} s, "
          f"{'closed and manifold' if topology['closed_manifold'] else 'NOT closed and manifold'} -> {args.output}")
    return 0 if topology["closed_manifold"] else 1


if __name__ == "__main__":
    sys.exit(main())
