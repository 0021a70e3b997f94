#!/usr/bin/env bash
# Installs aia's Debian packages (when missing) and builds build/aia and the
# tests. Safe to run again: it only does what is not done yet.
set -euo pipefail
cd "$(dirname "$0")/.."

PACKAGES=(
  build-essential cmake ninja-build pkg-config clang
  libeigen3-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  libmujoco-dev libmujoco-samples libqhull-dev
  libosmesa6-dev libopencv-dev ffmpeg
  libgtest-dev libgmock-dev libbenchmark-dev
  libtorch-dev libjemalloc-dev libsqlite3-dev zlib1g-dev
  libopenmpi-dev openmpi-bin
  python3-matplotlib python3-numpy python3-torch
  python3-dev pybind11-dev python3-pytest
)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[bootstrap] installing: ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

BUILD_DIR=${AIA_BUILD_DIR:-build}
JOBS=${AIA_JOBS:-$(nproc)}
if [ ! -f "$BUILD_DIR/build.ninja" ]; then
  cmake -S . -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release
fi
cmake --build "$BUILD_DIR" -j "$JOBS"
