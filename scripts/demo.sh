#!/usr/bin/env bash
# The README's main command: set up, build, make the default scene, replay it,
# print a summary and where the report is.
#   scripts/demo.sh [options for `oitsim run` that override the defaults, e.g. --algo hybrid --layers 8 --preset navi21]
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${OITSIM_BUILD_DIR:-$root/build}
out=${OITSIM_DEMO_DIR:-$root/out/demo}

"$root/scripts/setup.sh"
"$root/scripts/build.sh"
export SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1
oitsim="$build/apps/oitsim"
mkdir -p "$out"

echo
echo "== 1. default scene, captured through Mesa's OpenGL: the transparent Stanford bunny over an opaque backdrop (1280x720)"
"$oitsim" capture --mesh bunny --backdrop --width 1280 --height 720 --verify -o "$out/demo.oitt"
echo
echo "== 2. the trace"
"$oitsim" info "$out/demo.oitt"
echo
if [ $# -eq 0 ]; then
  echo "== 3. replay through the SystemC ROP model: MLAB, 4 rows of the paper's 8-byte format, integrated-GPU preset"
else  # the options given override these defaults (the summary below names what ran)
  echo "== 3. replay through the SystemC ROP model: MLAB k=4 rgba8t8z32 on iris-pro-5200, overridden by: $*"
fi
"$oitsim" run --trace "$out/demo.oitt" --out "$out/run" --mode timing --preset iris-pro-5200 \
  --algo mlab --layers 4 --format rgba8t8z32 "$@"
echo
echo "report: $out/run/report.json (images beside it: image.png, reference.pfm, diff.png)"
