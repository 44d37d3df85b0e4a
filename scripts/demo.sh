#!/usr/bin/env bash
# The README's main command: set up, build, make the default scene, replay it,
# print a summary and where the report is.
#   scripts/demo.sh [extra options for `oitsim run`, e.g. --algo hybrid --layers 8]
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
echo "== 1. default scene: opaque backdrop + transparent Stanford bunny + particles (1280x720)"
"$oitsim" gen demo --backdrop -o "$out/demo.oitt"
echo
echo "== 2. the trace"
"$oitsim" info "$out/demo.oitt"
echo
echo "== 3. replay through the OIT model"
"$oitsim" run --trace "$out/demo.oitt" --out "$out/run" "$@"
echo
echo "report: $out/run/report.json (images beside it: image.png, reference.pfm, diff.png)"
