"""The Python examples (examples/python) and the Python benchmark (bench/) run end to end on small
inputs."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

import gwnrt

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
EXAMPLES = os.path.join(ROOT, "examples", "python")
BENCH = os.path.join(ROOT, "bench")
DATA = os.environ.get("GWNRT_DATA_DIR", os.path.join(ROOT, "data"))
BUNNY_HOLES = os.path.join(DATA, "bunny_holes.obj")


def run(script, *args, folder=EXAMPLES):
    done = subprocess.run([sys.executable, os.path.join(folder, script), *map(str, args)], capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_soup_grid_matches_the_library(tmp_path):
    grid, mesh = tmp_path / "w.npy", tmp_path / "s.ply"
    out = run("soup_grid.py", BUNNY_HOLES, "--grid", 20, "--resolution", 32, "--save-grid", grid, "-o", mesh)
    assert "closed and manifold" in out
    model = gwnrt.load(BUNNY_HOLES)
    w = np.load(grid)
    # Its grid, indexed [z, y, x] over the box grown by 5%: corner and far corner checked
    # against the library on the same points.
    lo, hi = model.bounds
    pad = 0.05 * (hi - lo)
    corners = np.array([lo - pad, hi + pad], dtype=np.float32)
    np.testing.assert_allclose([w[0, 0, 0], w[-1, -1, -1]], model.winding_number(corners), atol=1e-6)
    assert gwnrt.load(mesh).triangle_count > 0


def test_dask_grid_on_a_local_cluster(tmp_path):
    grid = tmp_path / "w.npy"
    out = run("dask_grid.py", BUNNY_HOLES, "--grid", 24, "--chunk", 3000, "--save-grid", grid)
    assert "2 workers" in out and "inside" in out
    w = np.load(grid)
    assert w.shape == (24, 24, 24)
    model = gwnrt.load(BUNNY_HOLES)
    lo, hi = model.bounds
    pad = 0.05 * (hi - lo)
    step = (hi - lo + 2 * pad) / 23
    z, y, x = 5, 11, 17
    point = (lo - pad + step * np.array([x, y, z])).astype(np.float32)[None]
    np.testing.assert_allclose(w[z, y, x], model.winding_number(point)[0], atol=1e-6)


def test_benchmark_writes_its_table_and_json(tmp_path):
    report = tmp_path / "bench.json"
    out = run("bench_python.py", "--mesh", BUNNY_HOLES, "--points", 20000, "--dask-points", 40000, "--chunks",
              10000, "--repeats", 1, "--json", report, folder=BENCH)
    assert "Python/C++" in out and "/in-process" in out
    figures = json.loads(report.read_text())
    assert [r["query"] for r in figures["python_vs_cxx"]] == ["w", "sdf"]
    assert all(r["ratio"] > 0 for r in figures["python_vs_cxx"])
    assert figures["dask"]["rows"][0]["chunks"] == 4


def readme_block(source, name):
    """The lines between '# [readme-NAME-begin]' and '# [readme-NAME-end]', dedented, each
    indented by four spaces (a Markdown code block)."""
    lines = source.splitlines()
    begin = next(i for i, line in enumerate(lines) if f"# [readme-{name}-begin]" in line)
    end = next(i for i, line in enumerate(lines) if f"# [readme-{name}-end]" in line)
    body = lines[begin + 1:end]
    indent = min(len(line) - len(line.lstrip()) for line in body if line.strip())
    return "\n".join(("    " + line[indent:]) if line.strip() else "" for line in body) + "\n"


def test_readme_shows_the_example_that_runs():
    with open(os.path.join(EXAMPLES, "readme_example.py")) as f:
        source = f.read()
    with open(os.path.join(ROOT, "README.md")) as f:
        readme = f.read()
    for name in ("python", "dask"):
        block = readme_block(source, name)
        assert block in readme, f"README.md does not show readme_example.py's readme-{name} block as it is:\n{block}"
    out = run("readme_example.py", BUNNY_HOLES, "--dask")
    assert "ray hit True" in out and "dask:" in out
