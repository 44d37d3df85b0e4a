#!/usr/bin/env bash
# Cycle and DRAM-byte error of the default quantum (sim.quantum_cycles=1000:
# partitions run up to 1000 cycles apart and book DRAM in call order) against
# lockstep partitions (quantum 1), every algorithm on three 320x180 scenes, igpu
# preset, idle skipping on in both. Prints a Markdown table (results.md).
#   reports/repro/quantum-error/run.sh [OITSIM=build/apps/oitsim] [WORKDIR=out/repro/quantum-error]
set -euo pipefail
oitsim=${1:-build/apps/oitsim}
work=${2:-out/repro/quantum-error}
algos="mlab hybrid kbuffer adaptive mlcb slab stochastic wboit alpha abuffer"
mkdir -p "$work"
for t in particles glass demo; do
  "$oitsim" gen "$t" -o "$work/$t.oitt" --width 320 --height 180 --backdrop -q >/dev/null
  for a in $algos; do
    for q in 1 1000; do
      "$oitsim" run -t "$work/$t.oitt" -a "$a" -o "$work/${t}_${a}_q$q" -q --set sim.quantum_cycles=$q >/dev/null
    done
  done
done
python3 - "$work" $algos <<'PY'
import json, sys
work, algos = sys.argv[1], sys.argv[2:]
print("| scene | algorithm | cycles, quantum 1 | cycles, quantum 1000 | cycle error | DRAM bytes error |")
print("| --- | --- | --- | --- | --- | --- |")
for t in ["particles", "glass", "demo"]:
    for a in algos:
        r = {}
        for q in (1, 1000):
            s = json.load(open(f"{work}/{t}_{a}_q{q}/report.json"))
            m = s["memory"]
            r[q] = (s["timing"]["cycles"], m["dram_read_bytes"]["total"] + m["dram_write_bytes"]["total"])
        ce = 100 * (r[1000][0] - r[1][0]) / r[1][0]
        be = 100 * (r[1000][1] - r[1][1]) / r[1][1]
        print(f"| {t} | {a} | {r[1][0]:,} | {r[1000][0]:,} | {ce:+.2f} % | {be:+.3f} % |".replace(",", " "))
PY
