#!/usr/bin/env bash
# The quantum's error on every preset: frames at lockstep partitions
# (sim.quantum_cycles=1), the default quantum (16), the former default (200) and larger ones, against
# lockstep, with both engines. Partitions up to a quantum apart share the l2,
# the l3, the DRAM controller and the A-buffer's node counter; a frame whose
# error grows with the quantum without bound, or moves by more than the
# documented interleave error (oit_rop/DESIGN.md, "Structure (SystemC)"), is a
# suspect: a partition behind waiting for a time only in another's future
# (the artefact b367be4 removed: +52 % at 100000 on particles adaptive4).
#
#   bench/quantum_check.sh [OITSIM=build/apps/oitsim] [WORKDIR=out/bench/quantum-check]
#
# Environment: QUANTA (default "1 16 200 5000 100000"; the first is the
# reference), PRESETS (default "iris-pro-5200 titan-x-maxwell navi21"; the
# aliases igpu and dgpu name the first two), ALGOS (default "mlab adaptive
# abuffer wboit", k=4), ENGINES (default "cycle approximate"), JOBS (runs at a
# time, default 2), WIDTH x HEIGHT (default 640 x 360). Each configuration
# runs twice: the preset as it is, and DRAM-bound (l2.size_bytes=0,
# l3.size_bytes=0). The trace: `oitsim gen particles` at that size. Prints a
# Markdown table (bench/RESULTS-quantum.md); runs already in WORKDIR with a
# report.json are not run again (delete WORKDIR after changing the model).
set -euo pipefail
oitsim=$(realpath "${1:-build/apps/oitsim}")
work=${2:-out/bench/quantum-check}
quanta=${QUANTA:-1 16 200 5000 100000}
presets=${PRESETS:-iris-pro-5200 titan-x-maxwell navi21}
algos=${ALGOS:-mlab adaptive abuffer wboit}
engines=${ENGINES:-cycle approximate}
jobs=${JOBS:-2}
width=${WIDTH:-640} height=${HEIGHT:-360}
[ -x "$oitsim" ] || { echo "$0: $oitsim: not an executable" >&2; exit 1; }
mkdir -p "$work"
trace=$work/particles-${width}x$height.oitt
[ -s "$trace" ] || "$oitsim" gen particles --width "$width" --height "$height" -o "$trace" -q >&2
# One line per run: its folder, then its options.
list=$work/runs.txt
: >"$list"
for e in $engines; do
  for p in $presets; do
    for mem in onchip dram; do
      extra=
      [ $mem = dram ] && extra="--set l2.size_bytes=0 --set l3.size_bytes=0"
      for a in $algos; do
        for q in $quanta; do
          dir=$work/$e-$p-$mem-$a-q$q
          [ -s "$dir/report.json" ] && continue
          # (no trailing blank: xargs -L would join the next line)
          echo "$dir -t $trace -a $a -k 4 --preset $p --reference none -q --set sim.engine=$e --set sim.quantum_cycles=$q${extra:+ $extra}" >>"$list"
        done
      done
    done
  done
done
echo "quantum_check: $(wc -l <"$list") runs, $jobs at a time" >&2
# shellcheck disable=SC2016
# (Nothing to run: xargs would still start one sh, without a folder.)
if [ -s "$list" ]; then
  xargs -P "$jobs" -L 1 sh -c 'd=$1; shift; "$0" run -o "$d" "$@" >/dev/null || echo "failed: $d" >&2' "$oitsim" <"$list"
fi
python3 - "$work" "$quanta" "$presets" "$algos" "$engines" <<'PY'
import json, sys
work, quanta, presets, algos, engines = sys.argv[1], *[s.split() for s in sys.argv[2:]]
quanta = [int(q) for q in quanta]
ref, others = quanta[0], quanta[1:]


def load(e, p, mem, a, q):
    return json.load(open(f"{work}/{e}-{p}-{mem}-{a}-q{q}/report.json"))


def below(m, mem):
    """Bytes to DRAM (DRAM-bound) or between the ROP caches and the l2."""
    if mem == "dram" or len(m.get("levels", [])) < 2:
        return m["dram_read_bytes"]["total"] + m["dram_write_bytes"]["total"]
    return m["levels"][1]["read_bytes"] + m["levels"][1]["write_bytes"]


def pct(new, base):
    return f"{100 * (new - base) / base:+.2f} %" if base else ("0" if new == base else f"{new - base:+,}")


head = " | ".join(f"q={q}: error (bytes)" for q in others)
print(f"| engine | preset | memory | algorithm | bound by (q={ref}) | cycles, q={ref} | {head} |")
print("| --- " * (6 + len(others)) + "|")
worst = {}
for e in engines:
    for p in presets:
        for mem in ("onchip", "dram"):
            for a in algos:
                r = load(e, p, mem, a, ref)
                c0, b0 = r["timing"]["cycles"], below(r["memory"], mem)
                bound = r["timing"]["bound_by"]
                cells = []
                for q in others:
                    s = load(e, p, mem, a, q)
                    c, b = s["timing"]["cycles"], below(s["memory"], mem)
                    err = 100 * (c - c0) / c0
                    key = (e, mem, q)
                    if abs(err) > abs(worst.get(key, (0, ""))[0]):
                        worst[key] = (err, f"{p} {a}")
                    cells.append(f"{err:+.2f} % ({pct(b, b0)})")
                mem_name = "no l2/l3" if mem == "dram" else "as is"
                print(f"| {e} | {p} | {mem_name} | {a} | {bound['resource']} {100 * bound['share']:.0f} % "
                      f"| {c0:,} | " + " | ".join(cells) + " |")
print()
for (e, mem, q), (err, what) in sorted(worst.items()):
    print(f"- {e}, {'no l2/l3' if mem == 'dram' else 'as is'}, q={q}: largest cycle error {err:+.2f} % ({what})")
PY
