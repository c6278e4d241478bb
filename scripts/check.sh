#!/usr/bin/env bash
# The checks CI runs besides the Release suite (scripts/test.sh), each callable on its own:
#   bash scripts/check.sh format       clang-format --dry-run -Werror over every C++/CUDA file
#   bash scripts/check.sh layers       every #include follows the folders' layering
#                                      (scripts/check_layers.py)
#   bash scripts/check.sh sanitize     ASan + UBSan build of the whole suite, run
#   bash scripts/check.sh tsan         ThreadSanitizer build of the plugin tests and the core's
#                                      thread tests (tests/threads), run
#   bash scripts/check.sh downstream   install the Release build (build/), build and run
#                                      tests/downstream against the installed package, and
#                                      import the installed Python package
#   bash scripts/check.sh configs      the other build configurations: Embree and CUDA off (the
#                                      tests and the programs whose code depends on Embree built,
#                                      their Embree-dependent tests run), and the library alone (no
#                                      programs, no tests)
#   bash scripts/check.sh optional     an optional baseline found broken is left out, not fatal:
#                                      configures with OpenVDB half-installed (no
#                                      libboost-iostreams-dev), then whole; installs them (apt)
#   bash scripts/check.sh all          all seven, in that order
# The TSan build is RelWithDebInfo: its suppressions name frames inside TBB's headers, which only
# debug information keeps once they are inlined (without it the model build's TBB hand-overs are
# reported as races: docs/design.md §10).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs="$(nproc)"

check_format() {
  mapfile -t files < <(git ls-files '*.h' '*.cpp' '*.cu' '*.cuh')
  clang-format --dry-run -Werror "${files[@]}"
  echo "check format: ${#files[@]} files formatted"
}

check_layers() {
  python3 scripts/check_layers.py
}

check_sanitize() {
  # -O1 -g1: half the build time of RelWithDebInfo's -O2 -g, the suite as fast (docs/performance.md);
  # line tables are all ASan's and UBSan's reports need. A unity build: the instrumented inline
  # kernels are compiled once per batch of 8 sources rather than per source (a sixth less time).
  # Without UBSan's vptr check: it guards calls through the wrong dynamic type, and the libraries'
  # class hierarchies it instruments (CLI11, JSON, GoogleTest) were a third of a program's build.
  cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1" \
    -DGWNRT_SANITIZE=address,undefined -DGWNRT_SANITIZE_EXCLUDE=vptr -DGWNRT_WITH_CUDA=OFF \
    -DGWNRT_WITH_PYTHON=OFF -DGWNRT_WERROR=ON -DCMAKE_UNITY_BUILD=ON
  # The tests and every program they run (tests/apps/test_fuzz_inputs.cpp runs them all on hostile input).
  cmake --build build-asan --parallel "$jobs" --target gwnrt_tests gwnrt_thread_tests gwnrt_embree_tests \
    gwnrt_render_tests gwnrt-query gwnrt-render gwnrt-sdf-study gwnrt-mesh gwnrt-trace gwnrt-bench-trace \
    gwnrt-bench-query gwnrt-bench-mesh gwnrt-consistency gwnrt-library-example gwnrt-engine-example \
    gwnrt-embree-example
  # Any UBSan report fails its test (no recovery); leaks are reported at exit.
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    ctest --test-dir build-asan --output-on-failure --parallel "$jobs"
}

check_tsan() {
  # tsan.supp hides only what TSan cannot see in Debian's uninstrumented TBB and Embree: the model
  # build's TBB hand-overs, not races (none is reported, unsuppressed, against a TBB built with
  # TSan: docs/design.md §10). It matches frames inlined from TBB's headers, so
  # GWNRT_SANITIZE=thread adds -g whatever the build type (a Release build passes too).
  cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DGWNRT_SANITIZE=thread \
    -DGWNRT_WITH_CUDA=OFF -DGWNRT_WITH_PYTHON=OFF -DGWNRT_BUILD_PROGRAMS=OFF -DGWNRT_WERROR=ON
  cmake --build build-tsan --parallel "$jobs" --target gwnrt_embree_tests gwnrt_thread_tests
  # history_size=7 (the most): a TBB worker reads a parallel_for's task_group_context on the
  # caller's stack, whose slot the caller reuses after the join TSan cannot see; with the default
  # history the worker's stack was lost ("failed to restore the stack", 1 run in 2 of
  # gwnrt_thread_tests) and the suppression, which needs its TBB frames, could not match.
  local options="suppressions=$PWD/tests/plugin/tsan.supp halt_on_error=1 history_size=7"
  TSAN_OPTIONS="$options" build-tsan/tests/gwnrt_thread_tests
  # The plugin tests in 6 processes, one after another: in one process each test ran several
  # times slower than alone, TSan's costs growing with every Embree device's and TBB arena's
  # threads (243 s against 70 s). Not side by side: contention lost a worker's stack from TSan's
  # history and the suppression could not match it.
  local shard shards=6
  for ((shard = 0; shard < shards; ++shard)); do
    GTEST_TOTAL_SHARDS=$shards GTEST_SHARD_INDEX=$shard TSAN_OPTIONS="$options" build-tsan/tests/gwnrt_embree_tests
  done
}

check_downstream() {
  [ -d build ] || { echo "check downstream: run scripts/test.sh first (it makes build/)"; exit 1; }
  local prefix="$PWD/build-downstream/install"
  rm -rf build-downstream
  # The Python package's place: relative (under the prefix) unless it was configured to be an
  # interpreter's site-packages outside any prefix, which a check must not write into.
  local site module python
  site="$(sed -n 's/^GWNRT_PYTHON_INSTALL_DIR:[A-Z]*=//p' build/CMakeCache.txt)"
  if [[ "$site" == /* ]]; then
    echo "check downstream: the Python package installs outside the prefix ($site): not installed nor checked"
    cmake --install build --prefix "$prefix" --component Unspecified
    site=""
  else
    cmake --install build --prefix "$prefix"
  fi
  cmake -S tests/downstream -B build-downstream/app -G Ninja -DCMAKE_PREFIX_PATH="$prefix"
  cmake --build build-downstream/app --parallel "$jobs"
  build-downstream/app/library_example data/bunny.obj
  build-downstream/app/engine_example data/bunny.obj
  [ -x build-downstream/app/embree_example ] && build-downstream/app/embree_example data/bunny_holes.obj
  [ -x build-downstream/app/cuda_example ] && build-downstream/app/cuda_example data/bunny.obj
  # The Python package, when built: installed under the prefix and importable from there alone.
  if [ -n "$site" ] && compgen -G "build/python/gwnrt/_gwnrt*.so" > /dev/null; then
    module="$(find "$prefix" -name '_gwnrt*.so' -print -quit)"
    [ -n "$module" ] || { echo "check downstream: the Python module was built but not installed under $prefix"; exit 1; }
    python="$(sed -n 's/^Python_EXECUTABLE:[A-Z]*=//p' build/CMakeCache.txt)"
    (cd build-downstream && PYTHONPATH="$(dirname "$(dirname "$module")")" "$python" -c \
      "import gwnrt, sys; m = gwnrt.load(sys.argv[1]); assert gwnrt.__file__.startswith(sys.argv[2]); \
print('check downstream: installed gwnrt package:', m, 'w =', m.winding_number([[0, 5, 0]])[0])" \
      "$PWD/../data/bunny.obj" "$prefix")
  fi
  echo "check downstream: find_package(gwnrt) and every installed target linked"
}

check_configs() {
  # Only tests/trace/test_surface_trace.cpp and bench_trace.cpp compile differently without Embree
  # (GWNRT_HAVE_EMBREE: the tracer against Embree's own triangle test); the rest is the Release
  # build's code. The configuration itself checks the CMake logic.
  cmake -S . -B build-noembree -G Ninja -DGWNRT_WITH_EMBREE=OFF -DGWNRT_WITH_CUDA=OFF -DGWNRT_WERROR=ON
  cmake --build build-noembree --parallel "$jobs" --target gwnrt_tests gwnrt-bench-trace
  ctest --test-dir build-noembree --output-on-failure --parallel "$jobs" -R '^TraceWatertight'
  cmake -S . -B build-library -G Ninja -DGWNRT_BUILD_PROGRAMS=OFF -DGWNRT_BUILD_TESTS=OFF -DGWNRT_WITH_CUDA=OFF \
    -DGWNRT_WITH_PYTHON=OFF \
    -DGWNRT_WERROR=ON
  cmake --build build-library --parallel "$jobs"
  echo "check configs: Embree off (tests built, the tracer's Embree-dependent tests run) and the library alone built"
}

check_optional() {
  # Configuration only (no tests, no programs but the benchmarks'), each time in a fresh folder.
  configure() {
    rm -rf build-optional
    cmake -S . -B build-optional -G Ninja -DGWNRT_BUILD_TESTS=OFF -DGWNRT_WITH_CUDA=OFF -DGWNRT_WITH_PYTHON=OFF \
      -DGWNRT_WITH_EMBREE=OFF >build-optional.log 2>&1 || { cat build-optional.log; echo "check optional: $1: configure failed"; exit 1; }
    grep "gwnrt-bench-mesh" build-optional.log || true
  }
  bash scripts/install-deps.sh --packages libopenvdb-dev libboost-dev
  if compgen -G "/usr/lib/*/cmake/boost_iostreams-*" >/dev/null; then
    echo "check optional: Boost's iostreams is installed here: OpenVDB half-installed is not checked"
  else
    configure "OpenVDB without Boost's iostreams"
    grep -q "OpenVDB's find module .* fails on this system" build-optional.log ||
      { echo "check optional: OpenVDB's broken find module was not noticed"; exit 1; }
  fi
  bash scripts/install-deps.sh --packages libopenvdb-dev libboost-dev libboost-iostreams-dev
  configure "OpenVDB whole"
  grep -q "gwnrt-bench-mesh with OpenVDB" build-optional.log || { echo "check optional: OpenVDB installed but not found"; exit 1; }
  rm -rf build-optional build-optional.log
  echo "check optional: OpenVDB half-installed and whole both configure"
}

case "${1:-all}" in
  format) check_format ;;
  layers) check_layers ;;
  optional) check_optional ;;
  sanitize) check_sanitize ;;
  tsan) check_tsan ;;
  downstream) check_downstream ;;
  configs) check_configs ;;
  all) check_format; check_layers; check_sanitize; check_tsan; check_downstream; check_configs; check_optional ;;
  *) echo "usage: $0 format|layers|sanitize|tsan|downstream|configs|optional|all"; exit 2 ;;
esac
