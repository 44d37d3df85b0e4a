#!/usr/bin/env bash
# Configures (once) and builds oitsim in build/ (Release by default).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${OITSIM_BUILD_DIR:-$root/build}
jobs=${OITSIM_JOBS:-$(nproc)}
if [ ! -f "$build/build.ninja" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE="${OITSIM_BUILD_TYPE:-Release}"
fi
cmake --build "$build" -j "$jobs"
