#!/usr/bin/env bash
# How far the approximate engine's root causes (timing.root_cause_cycles) agree
# with the cycle engine's, on the configurations of oit_rop/DESIGN.md's
# agreement table (bench_timing's synthetic scene at 320x240, 2,500 quads).
# Prints a Markdown table: each engine's bound_by and share, and the overlap of
# the two distributions (sum over causes of the smaller share: 100 % = the same).
#   bench/root_cause_agreement.sh [BENCH_TIMING=build/bench/bench_timing] [WORKDIR=out/bench/root-causes]
set -euo pipefail
bin=${1:-build/bench/bench_timing}
work=${2:-out/bench/root-causes}
mkdir -p "$work"
configs=(
  "default|"
  "skip.* all false|--set skip.early_depth=false --set skip.fast_clear=false --set skip.lazy_merge=false --set skip.idle_cycles=false"
  "--preset dgpu|--preset dgpu"
  "end of shader, quad lock|--set lock.release=end_of_shader --set lock.granularity=quad"
  "fixed latency, 1 partition, tile lock|--set input.latency_model=fixed --set partitions.count=1 --set lock.granularity=tile"
  "--algo abuffer|--algo abuffer"
  "fp32, 16 KiB cache, miss queue 2, capacity 64|--format fp32 --set cache.size_bytes=16384 --set cache.miss_queue=2 --set lock.capacity=64"
  "adaptive fp32, 4 partitions, quantum 100, input 0.5/clock|--algo adaptive --format fp32 --set partitions.count=4 --set sim.quantum_cycles=100 --set input.fragments_per_clock=0.5"
  "wboit fp16, no HiZ, ALU 1/clock, input 3/clock|--algo wboit --format fp16 --set early_depth.hierarchical=false --set alu.blends_per_clock=1 --set input.fragments_per_clock=3"
  "1 partition, no idle skip, capacity 32|--set partitions.count=1 --set skip.idle_cycles=false --set lock.capacity=32"
)
echo "| configuration | cycle: bound by | approximate: bound by | overlap of the root-cause shares |"
echo "| --- | --- | --- | --- |"
i=0
for c in "${configs[@]}"; do
  name=${c%%|*} opts=${c#*|}
  for e in cycle approximate; do
    # shellcheck disable=SC2086
    "$bin" --mode timing --reps 1 --width 320 --height 240 --quads 2500 $opts --set sim.engine=$e \
      --stats "$work/$i-$e.json" >/dev/null 2>&1
  done
  /usr/bin/python3 - "$name" "$work/$i-cycle.json" "$work/$i-approximate.json" <<'PY'
import json, sys
name, a, b = sys.argv[1], json.load(open(sys.argv[2]))["timing"], json.load(open(sys.argv[3]))["timing"]
def shares(t):
    rc = t["root_cause_cycles"]; tot = sum(rc.values()) or 1
    return {k: v / tot for k, v in rc.items()}
sa, sb = shares(a), shares(b)
overlap = sum(min(sa[k], sb.get(k, 0)) for k in sa)
def bb(t): return f"{t['bound_by']['resource']} {100 * t['bound_by']['share']:.1f} %"
print(f"| {name} | {bb(a)} | {bb(b)} | {100 * overlap:.1f} % |")
PY
  i=$((i + 1))
done
