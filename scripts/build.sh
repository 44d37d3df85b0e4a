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
# OITSIM_NATIVE=ON|OFF sets the CMake option of that name (-march=native),
# also in a build folder configured before.
opts=()
[ -n "${OITSIM_NATIVE:-}" ] && opts+=(-DOITSIM_NATIVE="$OITSIM_NATIVE")
if [ ! -f "$build/build.ninja" ]; then
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE="${OITSIM_BUILD_TYPE:-Release}" "${opts[@]}"
elif [ ${#opts[@]} -gt 0 ]; then
  cmake -S "$root" -B "$build" "${opts[@]}" >/dev/null
fi
cmake --build "$build" -j "$jobs"
