#!/usr/bin/env bash
# Distance throughput of this build against the code before the closest-point work (commit
# 01f2272), the two run in turn on the same machine, mesh, points and seed:
#   bash scripts/bench-distance.sh [MESH ...]       (default: data/bunny_holes.obj)
# Needs build/ (scripts/test.sh). Builds 01f2272's gwnrt-bench-query once in build-baseline/ (a git
# worktree), then per mesh runs ROUNDS times (default 3) the baseline and then this build's
# benchmark (--only distance, --baseline-json the baseline run just before it), so that a drift of
# the machine's speed reaches both alike. The baseline's program has no --json: its table (mode in
# the first 30 columns, then points and queries/s) is read into the rows that --baseline-json takes.
# Each round's table has a column "x baseline"; JSON files go to OUT (default build/bench-distance).
set -euo pipefail
cd "$(dirname "$0")/.."
baseline_commit=01f2272
rounds="${ROUNDS:-3}"
points="${POINTS:-1000000}"
out="${OUT:-build/bench-distance}"
[ -x build/bin/gwnrt-bench-query ] || { echo "bench-distance: run scripts/test.sh first (it makes build/)"; exit 1; }
if [ ! -x build-baseline/build/examples/gwnrt-bench-query ]; then
  [ -d build-baseline/src ] || git worktree add --detach build-baseline/src "$baseline_commit"
  cmake -S build-baseline/src -B build-baseline/build -G Ninja -DCMAKE_BUILD_TYPE=Release -DGWNRT_WITH_CUDA=OFF
  cmake --build build-baseline/build --target gwnrt-bench-query
fi
mkdir -p "$out"
meshes=("$@")
[ ${#meshes[@]} -gt 0 ] || meshes=(data/bunny_holes.obj)
for mesh in "${meshes[@]}"; do
  name="$(basename "$mesh")"
  for round in $(seq 1 "$rounds"); do
    base_json="$out/${name}.baseline.${round}.json"
    build-baseline/build/examples/gwnrt-bench-query "$mesh" --points "$points" --brute-seconds 0.2 |
      awk 'BEGIN { printf "{\"rows\": [" }
           length($0) > 30 {
             mode = substr($0, 1, 30); sub(/ +$/, "", mode); rest = substr($0, 31); split(rest, f, " ");
             if (f[1] ~ /^[0-9]+$/ && f[2] ~ /^[0-9.e+-]+$/) {
               printf "%s{\"mode\": \"%s\", \"queries_per_second\": %s}", sep, mode, f[2]; sep = ", "
             }
           }
           END { print "]}" }' >"$base_json"
    echo "== $name, round $round"
    build/bin/gwnrt-bench-query "$mesh" --points "$points" --brute-seconds 0.2 --only distance \
      --baseline-json "$base_json" --json "$out/${name}.${round}.json" | sed -n '/^mode /,/^$/p'
  done
done
