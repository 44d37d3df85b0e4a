#!/usr/bin/env bash
# Cycle and byte error of coarser quanta (sim.quantum_cycles: partitions run up
# to that many cycles apart and book the shared l2's ports and DRAM in call
# order) against lockstep partitions (quantum 1): the default (16), the former
# default (200, until session 22) and 1000,
# every algorithm on three 320x180 scenes, igpu (= iris-pro-5200) preset, idle
# skipping on; twice: the preset as it is (the 6 MiB l2 holds these frames,
# DRAM moves nothing) and without its l2 and l3 (l2.size_bytes=0,
# l3.size_bytes=0: every ROP-cache miss and write-back goes to DRAM, the booking
# this page first measured). Prints a Markdown table per configuration
# (results.md).
#   reports/repro/quantum-error/run.sh [OITSIM=build/apps/oitsim] [WORKDIR=out/repro/quantum-error]
set -euo pipefail
oitsim=${1:-build/apps/oitsim}
work=${2:-out/repro/quantum-error}
algos="mlab hybrid kbuffer adaptive mlcb slab stochastic wboit alpha abuffer"
quanta="1 16 200 1000"
mkdir -p "$work"
for t in particles glass demo; do
  "$oitsim" gen "$t" -o "$work/$t.oitt" --width 320 --height 180 --backdrop -q >/dev/null
  for a in $algos; do
    for q in $quanta; do
      "$oitsim" run -t "$work/$t.oitt" -a "$a" -o "$work/${t}_${a}_q$q" -q --set sim.quantum_cycles=$q >/dev/null
      "$oitsim" run -t "$work/$t.oitt" -a "$a" -o "$work/${t}_${a}_nol2_q$q" -q --set sim.quantum_cycles=$q \
        --set l2.size_bytes=0 --set l3.size_bytes=0 >/dev/null
    done
  done
done
python3 - "$work" "$quanta" $algos <<'PY'
import json, sys
work, algos = sys.argv[1], sys.argv[3:]
quanta = [int(q) for q in sys.argv[2].split()]
ref, others = quanta[0], quanta[1:]


def below_rop(m):
    """Bytes between the ROP caches and the level below them: the l2 when there is one, else DRAM."""
    levels = m.get("levels", [])
    if len(levels) > 1:
        return levels[1]["read_bytes"] + levels[1]["write_bytes"]
    return m["dram_read_bytes"]["total"] + m["dram_write_bytes"]["total"]


def err(new, base):
    return "0 B" if base == 0 and new == 0 else (f"{new - base:+,} B" if base == 0 else f"{100 * (new - base) / base:+.3f} %")


for suffix, title, what in [("", "iris-pro-5200 as it is", "l2 bytes"),
                            ("_nol2", "iris-pro-5200 without l2 and l3", "DRAM bytes")]:
    print(f"**{title}** (bytes: between the ROP caches and the {'l2' if not suffix else 'DRAM'}; "
          "bound by: the quantum-1 run's `timing.bound_by`)")
    print()
    print(f"| scene | algorithm | bound by | cycles, quantum {ref} |"
          + "".join(f" quantum {q}: cycles | error | {what} error |" for q in others))
    print("| --- | --- | --- | --- |" + " --- | --- | --- |" * len(others))
    worst = {q: (0.0, "") for q in others}
    for t in ["particles", "glass", "demo"]:
        for a in algos:
            r = {}
            for q in quanta:
                s = json.load(open(f"{work}/{t}_{a}{suffix}_q{q}/report.json"))
                r[q] = (s["timing"]["cycles"], below_rop(s["memory"]), s["timing"]["bound_by"])
            b = r[ref][2]
            row = f"| {t} | {a} | {b['resource']} {100 * b['share']:.0f} % | {r[ref][0]:,} |"
            for q in others:
                ce = 100 * (r[q][0] - r[ref][0]) / r[ref][0]
                if abs(ce) > worst[q][0]:
                    worst[q] = (abs(ce), f"{t} {a}")
                row += f" {r[q][0]:,} | {ce:+.2f} % | {err(r[q][1], r[ref][1])} |"
            print(row.replace(",", " "))
    print()
    print("Largest cycle error: " + ", ".join(f"quantum {q} {worst[q][0]:.2f} % ({worst[q][1]})" for q in others) + ".")
    print()
PY
