#!/usr/bin/env bash
# The GPU check. On a machine with an NVIDIA GPU, nvcc, cmake and ninja but none
# of the project's Debian packages and no network, it builds the CUDA tests, gwnrt-consistency,
# gwnrt-bench-query and gwnrt-mesh (Embree and OpenImageIO off) against TBB, GLM, GoogleTest,
# CLI11 and nlohmann-json unpacked from Debian's .debs, runs them, and writes every log and JSON
# into OUTDIR, with summary.txt listing each step's exit status.
#
#   bash scripts/gpu-check.sh --fetch-deps   # on Debian 12 with network: fills .gpu-deps/ (11 MB;
#                                            # git-ignored; and the 871k dragon, 8 MB gzipped, when ../shared has it)
#   bash scripts/gpu-check.sh OUTDIR         # on the GPU machine, .gpu-deps/ carried along
#
# Steps go on when one fails (each has its own log), so that one run says as much as it can.
set -uo pipefail
cd "$(dirname "$0")/.."
deps="$PWD/.gpu-deps"
root="$deps/root"

if [ "${1:-}" = "--fetch-deps" ]; then
  rm -rf "$deps"
  mkdir -p "$deps/debs" "$root"
  # libtbbbind and libhwloc: TBB's CMake config refuses to load when a library it names is missing.
  (cd "$deps/debs" && apt-get download libtbb-dev libtbb12 libtbbmalloc2 libtbbbind-2-5 libhwloc15 libglm-dev \
    libgtest-dev libcli11-dev nlohmann-json3-dev) || exit 1
  for deb in "$deps"/debs/*.deb; do dpkg -x "$deb" "$root" || exit 1; done
  rm -rf "$deps/debs"
  if [ -f ../shared/meshes/dragon_vrip.ply.gz ]; then
    mkdir -p "$deps/meshes"
    cp ../shared/meshes/dragon_vrip.ply.gz "$deps/meshes/"
  fi
  du -sh "$deps"
  exit 0
fi

out="${1:?usage: bash scripts/gpu-check.sh OUTDIR | --fetch-deps}"
mkdir -p "$out"
out="$(cd "$out" && pwd)"
if [ ! -d "$root/usr" ]; then
  echo "gpu-check: $root/usr is missing: run 'bash scripts/gpu-check.sh --fetch-deps' on a Debian 12 machine" \
    "and carry .gpu-deps along" | tee "$out/summary.txt"
  exit 1
fi
export LD_LIBRARY_PATH="$root/usr/lib/x86_64-linux-gnu${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
[ -x /usr/local/cuda/bin/nvcc ] && export PATH="/usr/local/cuda/bin:$PATH"
start=$SECONDS
summary="$out/summary.txt"
: >"$summary"

# step NAME COMMAND...: runs COMMAND with its output in OUTDIR/NAME.log, notes the status. A step
# that hangs is stopped after STEP_LIMIT seconds (exit 124), so that the rest still runs.
step() {
  local name="$1"
  shift
  local t0=$SECONDS
  timeout "${STEP_LIMIT:-240}" "$@" >"$out/$name.log" 2>&1
  local rc=$?
  printf '%-28s exit %3d  %4d s  (at %d s)\n' "$name" "$rc" "$((SECONDS - t0))" "$((SECONDS - start))" | tee -a "$summary"
  return $rc
}

step nvidia-smi nvidia-smi
# sm_90 alone (H100/H200): the default "80 90" doubles nvcc's time. No Python module.
step configure cmake -S . -B build-gpu -G Ninja -DCMAKE_BUILD_TYPE=Release -DGWNRT_WITH_EMBREE=OFF \
  -DGWNRT_WITH_CUDA=ON -DGWNRT_WITH_PYTHON=OFF -DCMAKE_CUDA_ARCHITECTURES="${CUDA_ARCHITECTURES:-90}" \
  -DCMAKE_PREFIX_PATH="$root/usr" || exit 1
STEP_LIMIT=420 step build cmake --build build-gpu --parallel "$(nproc)" --target gwnrt_cuda_tests \
  gwnrt-consistency gwnrt-bench-query gwnrt-mesh || exit 1

bin=build-gpu/bin
# One process a suite: a device fault (an illegal address) is sticky and would fail every later test.
for suite in CudaBackend CudaQueries CudaTrace CudaMeshing CudaMeshingErrors; do
  step "cuda-tests-$suite" build-gpu/tests/gwnrt_cuda_tests --gtest_filter="*$suite.*" \
    --gtest_output="json:$out/cuda-tests-$suite.json"
done
# Anything in no suite above (a suite added later).
step cuda-tests-rest build-gpu/tests/gwnrt_cuda_tests \
  --gtest_filter="-*CudaBackend.*:*CudaQueries.*:*CudaTrace.*:*CudaMeshing.*:*CudaMeshingErrors.*" \
  --gtest_output="json:$out/cuda-tests-rest.json"
# Every quantity on the bundled meshes, with gwnrt-render's first hit at 1920x1080 (its frames/s:
# the target is >= 60 on bunny_holes; gwnrt-render itself needs Embree and OpenImageIO).
step consistency "$bin/gwnrt-consistency" --json "$out/consistency.json"

dragon=""
if [ -f "$deps/meshes/dragon_vrip.ply.gz" ]; then
  # Unpacked into the build folder, not beside the .gz: .gpu-deps/ travels to the GPU machine, and
  # the 33 MB mesh would take it past half of what a run may carry (64 MiB with the tree).
  dragon="build-gpu/dragon_vrip.ply"
  [ -f "$dragon" ] || { gunzip -c "$deps/meshes/dragon_vrip.ply.gz" >"$dragon.part" && mv "$dragon.part" "$dragon"; }
  step consistency-dragon "$bin/gwnrt-consistency" --mesh "$dragon" --count 1000000 --resolution 256 \
    --json "$out/consistency-dragon.json"
fi

# Query throughput, 1M points: the CPU's run, then the GPU's with it as the baseline (its ratio
# column is GPU over CPU). The targets: Taylor order-2 w >= 2e8/s and crossing w >= 5e8/s
# on the 871k dragon.
for mesh in data/bunny_holes.obj $dragon; do
  name="$(basename "$mesh" .ply)"
  name="${name%.obj}"
  step "bench-query-$name-cpu" "$bin/gwnrt-bench-query" "$mesh" --points 1000000 --brute-seconds 1 \
    --json "$out/bench-query-$name-cpu.json"
  step "bench-query-$name-cuda" "$bin/gwnrt-bench-query" "$mesh" --points 1000000 --brute-seconds 1 \
    --device cuda --baseline-json "$out/bench-query-$name-cpu.json" --json "$out/bench-query-$name-cuda.json"
done

# Meshing the closed bunny at 512^3 (target: <= 50 ms after the upload), and the CPU for the ratio.
# Every kernel loaded up front (CUDA loads them lazily, on first launch, by default): the meshing's
# time is then the meshing's.
for device in cuda cpu; do
  step "mesh-bunny-512-$device" env CUDA_MODULE_LOADING=EAGER "$bin/gwnrt-mesh" data/bunny.obj \
    -o "$out/bunny-512-$device.ply" --resolution 512 --device "$device" -v
done
rm -f "$out"/bunny-512-*.ply

echo "gpu-check: done in $((SECONDS - start)) s; logs and JSON in $out" | tee -a "$summary"
