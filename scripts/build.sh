#!/usr/bin/env bash
# Configures (once) and builds oitsim in build/ (Release by default;
# OITSIM_BUILD_DIR, OITSIM_BUILD_TYPE, OITSIM_JOBS, OITSIM_NATIVE and
# OITSIM_UNITY change it).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${OITSIM_BUILD_DIR:-$root/build}
jobs=${OITSIM_JOBS:-$(nproc)}
case ${OITSIM_NATIVE:-} in
  '' | ON | OFF) ;;
  *) echo "build.sh: OITSIM_NATIVE=$OITSIM_NATIVE: expected ON or OFF" >&2; exit 2 ;;
esac
# OITSIM_NATIVE=ON|OFF sets the CMake option of that name (-march=native),
# also in a build folder configured before.
case ${OITSIM_UNITY:-} in
  '' | ON | OFF) ;;
  *) echo "build.sh: OITSIM_UNITY=$OITSIM_UNITY: expected ON or OFF" >&2; exit 2 ;;
esac
# OITSIM_UNITY=ON|OFF sets CMAKE_UNITY_BUILD (each target's sources compiled
# together in batches of 8: 52 build steps instead of 211, each header compiled
# once per batch; an edit to one file recompiles its batch; tests/README.md has
# what CI takes). A new build folder is a unity build: the README's
# commands build once; OITSIM_UNITY=OFF for a folder you edit and rebuild often.
opts=()
[ -n "${OITSIM_NATIVE:-}" ] && opts+=(-DOITSIM_NATIVE="$OITSIM_NATIVE")
[ -n "${OITSIM_UNITY:-}" ] && opts+=(-DCMAKE_UNITY_BUILD="$OITSIM_UNITY")
if [ ! -f "$build/build.ninja" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE="${OITSIM_BUILD_TYPE:-Release}" \
    -DCMAKE_UNITY_BUILD="${OITSIM_UNITY:-ON}" "${opts[@]}"
elif [ ${#opts[@]} -gt 0 ]; then
  cmake -S "$root" -B "$build" "${opts[@]}" >/dev/null
fi
cmake --build "$build" -j "$jobs"
