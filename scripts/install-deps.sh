#!/usr/bin/env bash
# Installs the Debian 12 packages gwnrt builds against (skips apt when all are present): the
# Python module's too (pybind11, Python's headers; numpy, pytest, Dask for its tests).
# --baselines adds what gwnrt-bench-mesh's OpenVDB column needs (OpenVDB, and Boost for its
# headers): a benchmark's baseline only, left out of CI, where compiling OpenVDB's mesher into
# each build configuration would cost minutes.
# --ci adds ccache, with which CI's Release build and other configurations share objects.
# --packages P... installs just those (check.sh optional: OpenVDB half-installed, then whole).
set -euo pipefail
packages=(cmake ninja-build g++ pkg-config
          libtbb-dev libglm-dev libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev
          libembree-dev libopenimageio-dev nlohmann-json3-dev clang-format libassimp-dev
          pybind11-dev python3-dev python3-numpy python3-pytest python3-dask python3-distributed)
case "${1:-}" in
  --baselines) packages+=(libopenvdb-dev libboost-dev libboost-iostreams-dev) ;;
  --ci) packages+=(ccache) ;;
  --packages) shift; packages=("$@") ;;
esac
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi
sudo=""
[ "$(id -u)" -ne 0 ] && sudo="sudo"
echo "install-deps: installing ${missing[*]}"
$sudo apt-get update -qq
DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
