#!/usr/bin/env bash
# The README's test command: set up, build, run every test through ctest.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${OITSIM_BUILD_DIR:-$root/build}
"$root/scripts/setup.sh"
"$root/scripts/build.sh"
export SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1
cd "$build"
ctest --output-on-failure -j "$(nproc)" "$@"
