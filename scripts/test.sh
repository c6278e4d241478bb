#!/usr/bin/env bash
# Installs dependencies, builds everything (CUDA too when nvcc is found) and runs the test suite.
# GWNRT_WERROR=ON (as CI sets it) makes warnings errors.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/install-deps.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DGWNRT_WERROR="${GWNRT_WERROR:-OFF}"
cmake --build build --parallel
ctest --test-dir build --output-on-failure --parallel "$(nproc)"
