#!/usr/bin/env bash
# Regenerates one committed reproduction: its sweep (spec in reports/sweep/),
# its report, and the files committed under reports/repro/NAME/; then prints
# the Markdown table of reports/repro/README.md made from them (tables.py).
#   reports/repro/regenerate.sh NAME [OITSIM=build/apps/oitsim] [WORKDIR=out/repro]
# NAME: error-vs-k, hardware-pareto, table1-memory or speed-modes. Run from the
# top of the repository with a Release build (scripts/build.sh). --force: every
# point runs again even if out/repro/NAME holds it from an earlier run.
set -euo pipefail
name=${1:?usage: reports/repro/regenerate.sh error-vs-k|hardware-pareto|table1-memory|speed-modes [OITSIM] [WORKDIR]}
oitsim=${2:-build/apps/oitsim}
work=${3:-out/repro}
here=$(cd "$(dirname "$0")" && pwd)
case "$name" in
  error-vs-k) spec=reports/sweep/error-vs-k.yaml; jobs=2; files="results.csv report.html" ;;
  hardware-pareto) spec=reports/sweep/hardware-pareto.json; jobs=2; files="results.csv report.html" ;;
  table1-memory) spec=reports/sweep/table1-memory.json; jobs=2; files="results.csv" ;;
  # One point at a time: its wall clocks are the measurement.
  speed-modes) spec=reports/sweep/speed-modes.json; jobs=1; files="results.csv speed.json" ;;
  *) echo "regenerate.sh: unknown reproduction '$name' (expected error-vs-k, hardware-pareto, table1-memory or speed-modes)" >&2
     exit 1 ;;
esac
"$oitsim" sweep "$spec" --out "$work/$name" --jobs "$jobs" --force
"$oitsim" report "$work/$name"
mkdir -p "$here/$name"
for f in $files; do cp "$work/$name/$f" "$here/$name/$f"; done
case "$name" in
  error-vs-k|hardware-pareto|speed-modes) /usr/bin/python3 "$here/tables.py" "$name" ;;
esac
