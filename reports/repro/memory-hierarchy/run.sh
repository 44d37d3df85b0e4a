#!/usr/bin/env bash
# The memory hierarchy's page (issue 21): bytes per level against the
# compulsory traffic on the captured bunny and generated particles at
# 1280x720 (MLAB k=4 rgba8t8z32) for every preset and without the shared
# levels, the ROP cache and l2 size sweeps, the line size and array layout
# sweep, and the DRAM controller's closed page and scheduler. Captures the
# bunny through Mesa (as scripts/demo.sh does), runs the four sweeps and
# prints the page (results.md).
#   reports/repro/memory-hierarchy/run.sh [OITSIM=build/apps/oitsim] > reports/repro/memory-hierarchy/results.md
# Run from the top of the repository (the sweep specs name the bunny at
# out/repro/memory-hierarchy/bunny.oitt).
set -euo pipefail
oitsim=${1:-build/apps/oitsim}
work=out/repro/memory-hierarchy
mkdir -p "$work"
[ -f "$work/bunny.oitt" ] ||
  "$oitsim" capture --mesh bunny --backdrop --width 1280 --height 720 -o "$work/bunny.oitt" -q >&2
for s in memory-levels memory-cache-size memory-line-size memory-dram; do
  "$oitsim" sweep "reports/sweep/$s.json" --out "$work/$s" --jobs 2 --quiet >&2
done
python3 "$(dirname "$0")/make_page.py" "$work"
