#!/usr/bin/env bash
# One frame of a real application through `oitsim capture --apitrace` (issue 26):
# glmark2's jellyfish scene (Debian package glmark2: a transparent jellyfish blended
# SRC_ALPHA, ONE_MINUS_SRC_ALPHA over a full-screen background), 1280x720, traced
# with apitrace under Xvfb, frame 2 captured and checked against GL's own blend
# (--verify), described (`oitsim info`), then replayed by a few algorithms
# (functional sweep) into an exploration report. The whole chain from apt-get:
#   reports/repro/apitrace-glmark2/run.sh [OITSIM=build/apps/oitsim] [WORKDIR=out/repro/apitrace-glmark2] [PAGE=reports/repro/apitrace-glmark2]
# Writes PAGE/capture.txt, PAGE/verify.txt, PAGE/info.txt, PAGE/results.csv and PAGE/report.html.
set -euo pipefail
oitsim=${1:-build/apps/oitsim}
work=${2:-out/repro/apitrace-glmark2}
page=${3:-reports/repro/apitrace-glmark2}
top=$(cd "$(dirname "$0")/../../.." && pwd)
"$top/scripts/setup.sh"  # apitrace, apitrace-tracers, xvfb and the rest
if ! dpkg-query -W -f='${Status}' glmark2 2>/dev/null | grep -q "install ok installed"; then
  sudo=(); [ "$(id -u)" -eq 0 ] || sudo=(sudo)
  "${sudo[@]}" apt-get update -qq
  "${sudo[@]}" apt-get install -y -qq --no-install-recommends glmark2
fi
mkdir -p "$work" "$page"
work=$(cd "$work" && pwd)
# Four frames of the scene (glmark2 draws its own frames; nframes makes it stop).
xvfb-run -a -s "-screen 0 1280x720x24" apitrace trace -o "$work/jellyfish.trace" \
  glmark2 -s 1280x720 -b jellyfish:nframes=4 >"$work/glmark2.log" 2>&1
# Captured with the check against GL's own blend (--verify: traces/CAPTURE.md);
# its line is also kept alone in verify.txt.
"$oitsim" capture --apitrace "$work/jellyfish.trace" --frames 2 -o "$work/jellyfish.oitt" --verify \
  | sed "s|$work/||g" | tee "$page/capture.txt"
grep "verify frame" "$page/capture.txt" >"$page/verify.txt"
"$oitsim" info "$work/jellyfish.oitt" | sed "s|$work/||g" | tee "$page/info.txt"
cat >"$work/sweep.yaml" <<YAML
# The captured glmark2 frame, replayed by the exact A-buffer's neighbours.
traces:
  - {path: jellyfish.oitt, name: jellyfish}
base: {mode: functional, format: fp32}
axes:
  algo: [alpha, mlab, wboit]
  layers: [2, 4]
YAML
"$oitsim" sweep "$work/sweep.yaml" --out "$work/sweep" --jobs 2 --force
"$oitsim" report "$work/sweep"
cp "$work/sweep/results.csv" "$work/sweep/report.html" "$page/"
