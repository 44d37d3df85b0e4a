#!/usr/bin/env bash
# Cycle and DRAM-byte error of coarser quanta (sim.quantum_cycles: partitions
# run up to that many cycles apart and book DRAM in call order) against
# lockstep partitions (quantum 1): the default (200) and 1000, every algorithm
# on three 320x180 scenes, igpu preset, idle skipping on. Prints a Markdown
# table (results.md).
#   reports/repro/quantum-error/run.sh [OITSIM=build/apps/oitsim] [WORKDIR=out/repro/quantum-error]
set -euo pipefail
oitsim=${1:-build/apps/oitsim}
work=${2:-out/repro/quantum-error}
algos="mlab hybrid kbuffer adaptive mlcb slab stochastic wboit alpha abuffer"
quanta="1 200 1000"
mkdir -p "$work"
for t in particles glass demo; do
  "$oitsim" gen "$t" -o "$work/$t.oitt" --width 320 --height 180 --backdrop -q >/dev/null
  for a in $algos; do
    for q in $quanta; do
      "$oitsim" run -t "$work/$t.oitt" -a "$a" -o "$work/${t}_${a}_q$q" -q --set sim.quantum_cycles=$q >/dev/null
    done
  done
done
python3 - "$work" $algos <<'PY'
import json, sys
work, algos = sys.argv[1], sys.argv[2:]
print("| scene | algorithm | cycles, quantum 1 | quantum 200: cycles | error | DRAM bytes error "
      "| quantum 1000: cycles | error | DRAM bytes error |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
worst = {200: 0.0, 1000: 0.0}
for t in ["particles", "glass", "demo"]:
    for a in algos:
        r = {}
        for q in (1, 200, 1000):
            s = json.load(open(f"{work}/{t}_{a}_q{q}/report.json"))
            m = s["memory"]
            r[q] = (s["timing"]["cycles"], m["dram_read_bytes"]["total"] + m["dram_write_bytes"]["total"])
        row = f"| {t} | {a} | {r[1][0]:,} |"
        for q in (200, 1000):
            ce = 100 * (r[q][0] - r[1][0]) / r[1][0]
            be = 100 * (r[q][1] - r[1][1]) / r[1][1]
            worst[q] = max(worst[q], abs(ce))
            row += f" {r[q][0]:,} | {ce:+.2f} % | {be:+.3f} % |"
        print(row.replace(",", " "))
print()
print(f"Largest cycle error: quantum 200 {worst[200]:.2f} %, quantum 1000 {worst[1000]:.2f} %.")
PY
