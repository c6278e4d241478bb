#!/usr/bin/env bash
# Installs dependencies, builds, renders the bundled bunny with holes (its holes closed by the
# smooth pieces of S) and queries w, ∇w and distances at probe points on it.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build --parallel --target gwnrt-render gwnrt-query
mkdir -p out
./build/examples/gwnrt-render examples/data/bunny_holes.obj -o out/bunny_holes.png --width 800 --height 600
echo "wrote out/bunny_holes.png"
./build/examples/gwnrt-query examples/data/bunny_holes.obj --points examples/data/bunny_probe_points.txt \
  --fields w,grad,udist,bdist -o out/bunny_holes_query.csv
echo "wrote out/bunny_holes_query.csv"
head -n 5 out/bunny_holes_query.csv
