#!/usr/bin/env bash
# Installs dependencies, builds, and queries w, ∇w and distances on the bundled bunny with holes.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build --parallel --target gwnrt-query
mkdir -p out
./build/examples/gwnrt-query examples/data/bunny_holes.obj --points examples/data/bunny_probe_points.txt \
  --fields w,grad,udist,bdist -o out/bunny_holes_query.csv
echo "wrote out/bunny_holes_query.csv"
head -n 5 out/bunny_holes_query.csv
