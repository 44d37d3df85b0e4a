#!/usr/bin/env bash
# Frame cycles of the approximate engine against the cycle engine (the
# reference) on configurations covering every parameter of the memory
# hierarchy (issue 21) and the earlier ones (DESIGN.md, "Approximate
# engine"). Each configuration runs bench_timing's synthetic particles
# (320x240, 2,500 quads, mlab k=4 rgba8t8z32 unless the line says otherwise)
# once per engine. Prints `name|cycle|approximate|error %`, then the worst and
# the median error.
#
#   bench/approximate_agreement.sh [BENCH_TIMING=build/bench/bench_timing] [WORKDIR]
set -euo pipefail
bench=${1:-build/bench/bench_timing}
work=${2:-$(mktemp -d)}
[ -x "$bench" ] || { echo "$0: $bench is not an executable" >&2; exit 2; }
mkdir -p "$work"
export SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1
while IFS='|' read -r name opts; do
  [ -z "$name" ] && continue
  for e in cycle approximate; do
    # shellcheck disable=SC2086  # the options are words
    "$bench" --mode timing --reps 1 --width 320 --height 240 --quads 2500 $opts --set sim.engine=$e \
      --stats "$work/$name.$e.json" >/dev/null 2>"$work/$name.$e.err" || { echo "$name $e failed:" >&2; cat "$work/$name.$e.err" >&2; exit 1; }
  done
  echo "$name"
done <<'CFG' | python3 -c '
import json, statistics, sys
work = sys.argv[1]
errs = []
for name in sys.stdin.read().split():
    c = json.load(open(f"{work}/{name}.cycle.json"))["timing"]["cycles"]
    a = json.load(open(f"{work}/{name}.approximate.json"))["timing"]["cycles"]
    e = 100.0 * (a - c) / c
    errs.append((abs(e), e, name))
    print(f"{name}|{c}|{a}|{e:+.2f}")
worst = max(errs)
print(f"worst {worst[1]:+.2f} % ({worst[2]}), median |error| {statistics.median(x[0] for x in errs):.2f} % over {len(errs)} configurations")
' "$work"
default|
dram-only|--set l2.size_bytes=0 --set l3.size_bytes=0
titan-x-maxwell|--preset titan-x-maxwell
navi21|--preset navi21
row-major|--set memory.array_layout=row_major
lines-128|--set cache.line_bytes=128 --set l2.line_bytes=128 --set l3.line_bytes=128
sectors-16|--set cache.sector_bytes=16
lines-32|--set cache.line_bytes=32
rop-8KiB|--set cache.size_bytes=8KiB
l2-256KiB-2-slices|--set l2.size_bytes=256KiB --set l2.slices=2 --set l2.ways=16 --set l3.size_bytes=0
l2-victim-only|--set l3.size_bytes=0 --set l2.victim_only=true
l3-not-victim|--set l3.victim_only=false
l2-4B-per-clock|--set l2.bytes_per_clock=4
l2-latency-200|--set l2.hit_latency=200
l2-sectors-32|--set l2.sector_bytes=32 --set l3.sector_bytes=32
adaptive-fp32-4-partitions|--algo adaptive --format fp32 --set partitions.count=4
abuffer|--algo abuffer
quad-end-of-shader|--set lock.granularity=quad --set lock.release=end_of_shader
1-partition-capacity-32|--set partitions.count=1 --set lock.capacity=32
skips-off|--set skip.early_depth=false --set skip.fast_clear=false --set skip.lazy_merge=false --set skip.idle_cycles=false
wboit-fp16-no-hiz|--algo wboit --format fp16 --set early_depth.hierarchical=false --set alu.blends_per_clock=1 --set input.fragments_per_clock=3
fixed-latency-tile-lock|--set input.latency_model=fixed --set lock.granularity=tile
3-partitions|--set partitions.count=3
kbuffer-row-major|--algo kbuffer --set memory.array_layout=row_major
fp32-16KiB-mq2|--format fp32 --set cache.size_bytes=16KiB --set cache.miss_queue=2 --set l2.size_bytes=0 --set l3.size_bytes=0
old-dgpu-k2|--k 2 --preset dgpu --set l2.size_bytes=0 --set partitions.count=4 --set clock.core_mhz=1216 --set cache.size_bytes=512KiB --set cache.hit_latency=80 --set dram.channels=4 --set cache.line_bytes=64 --set cache.sector_bytes=0
CFG
