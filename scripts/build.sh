#!/usr/bin/env bash
# Configures (once) and builds oitsim in build/ (Release by default;
# OITSIM_BUILD_DIR, OITSIM_BUILD_TYPE, OITSIM_JOBS and OITSIM_NATIVE change it).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${OITSIM_BUILD_DIR:-$root/build}
jobs=${OITSIM_JOBS:-$(nproc)}
case ${OITSIM_NATIVE:-} in
  '' | ON | OFF) ;;
  *) echo "build.sh: OITSIM_NATIVE=$OITSIM_NATIVE: expected ON or OFF" >&2; exit 2 ;;
esac
if [ ! -f "$build/build.ninja" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE="${OITSIM_BUILD_TYPE:-Release}"
fi
# OITSIM_NATIVE=ON|OFF (re)sets the CMake option of that name (-march=native).
if [ -n "${OITSIM_NATIVE:-}" ]; then
  cmake -S "$root" -B "$build" -DOITSIM_NATIVE="$OITSIM_NATIVE" >/dev/null
fi
cmake --build "$build" -j "$jobs"
