#!/usr/bin/env bash
# Checks that a speed change of the timing model changed nothing it computes:
# runs two bench_timing binaries (before / after) on the same traces and
# configurations and compares every stats section (cycles, stalls, bytes, lock,
# cache, time series ...) byte for byte; each run also checks its timing image
# bit for bit against the functional one.
#
#   bench/check_identity.sh BEFORE/bench_timing AFTER/bench_timing [--quick] [--engine E]
#   bench/check_identity.sh --base REV AFTER/bench_timing [--quick] [--engine E]
#
# --base REV builds BEFORE itself: a detached git worktree of REV in
# ${TMPDIR:-/tmp}/oitsim-base-<commit> and bench_timing in it (Release; kept, so a
# second run with the same REV does not rebuild; `git worktree remove` it when done).
# --quick: only the small trace (about 30 s instead of 1 minute).
# --engine E: every configuration with --set sim.engine=E (cycle, the default,
# or approximate); a configuration's own sim.engine would be overridden.
set -euo pipefail
if [ $# -lt 2 ]; then
  echo "usage: $0 BEFORE_BENCH_TIMING AFTER_BENCH_TIMING [--quick] [--engine cycle|approximate]" >&2
  echo "       $0 --base REV AFTER_BENCH_TIMING [--quick] [--engine cycle|approximate]" >&2
  exit 2
fi
if [ "$1" = --base ]; then
  [ $# -ge 3 ] || { echo "$0: --base needs REV and AFTER_BENCH_TIMING" >&2; exit 2; }
  repo=$(cd "$(dirname "$0")/.." && pwd)
  commit=$(git -C "$repo" rev-parse --verify "$2^{commit}") || { echo "$0: --base $2: not a commit" >&2; exit 2; }
  tree=${TMPDIR:-/tmp}/oitsim-base-${commit:0:12}
  if [ ! -x "$tree/build/bench/bench_timing" ]; then
    [ -d "$tree" ] || git -C "$repo" worktree add --detach "$tree" "$commit" >/dev/null
    cmake -S "$tree" -B "$tree/build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
    cmake --build "$tree/build" --target bench_timing >/dev/null
  fi
  shift 2
  set -- "$tree/build/bench/bench_timing" "$@"
fi
before=$1 after=$2 quick= engine=
shift 2
while [ $# -gt 0 ]; do
  case $1 in
    --quick) quick=--quick; shift ;;
    --engine)
      [ $# -ge 2 ] || { echo "$0: --engine needs a value (cycle or approximate)" >&2; exit 2; }
      case $2 in cycle | approximate) engine=$2 ;; *) echo "$0: --engine $2: expected cycle or approximate" >&2; exit 2 ;; esac
      shift 2 ;;
    *) echo "$0: unknown option $1 (expected --quick or --engine E)" >&2; exit 2 ;;
  esac
done
for b in "$before" "$after"; do
  [ -x "$b" ] || { echo "$0: $b is not an executable" >&2; exit 2; }
done
export SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

small=(--width 320 --height 240 --quads 2500)
# name | trace options | model options
configs=(
  "defaults|small|"
  "skips-off|small|--set skip.early_depth=false --set skip.fast_clear=false --set skip.lazy_merge=false --set skip.idle_cycles=false"
  "dgpu|small|--preset dgpu"
  "eos-quad-unordered|small|--set lock.release=end_of_shader --set lock.granularity=quad --set lock.mode=unordered"
  "fixed-1part-tile|small|--set input.latency_model=fixed --set partitions.count=1 --set lock.granularity=tile"
  "abuffer|small|--algo abuffer"
  "fp32-smallcache|small|--format fp32 --set cache.size_bytes=16384 --set cache.miss_queue=2 --set lock.capacity=64"
  "adaptive-4part|small|--algo adaptive --format fp32 --set partitions.count=4 --set sim.quantum_cycles=100 --set input.fragments_per_clock=0.5"
  "wboit-fp16-nohiz|small|--algo wboit --format fp16 --set early_depth.hierarchical=false"
  "mlab-fp16-k8|small|--format fp16 --k 8"
  "kbuffer-k2|small|--algo kbuffer --k 2"
  "hybrid|small|--algo hybrid --k 3"
  "alpha|small|--algo alpha"
  "wsum|small|--algo wsum --format fp16"
  "wavg|small|--algo wavg --format fp32"
  "slab|small|--algo slab --format fp32"
  "stochastic|small|--algo stochastic --format fp32"
  "mlcb|small|--algo mlcb --format fp32"
  "1part-noidle|small|--set partitions.count=1 --set skip.idle_cycles=false"
)
[ "$quick" = --quick ] || configs+=("full-defaults|full|" "full-dgpu|full|--preset dgpu")

fail=0
for c in "${configs[@]}"; do
  IFS='|' read -r name trace opts <<<"$c"
  targs=()
  [ "$trace" = small ] && targs=("${small[@]}")
  [ -n "$engine" ] && opts="$opts --set sim.engine=$engine"
  # shellcheck disable=SC2086  # opts is a list of options
  for side in before after; do
    bin=$before
    [ $side = after ] && bin=$after
    if ! "$bin" --mode both --reps 1 "${targs[@]}" $opts --stats "$work/$name.$side.json" >"$work/$name.$side.log" 2>&1; then
      echo "FAIL $name: $side run failed:"; tail -3 "$work/$name.$side.log"; fail=1; continue 2
    fi
  done
  t_before=$(grep -o 'timing:     best [0-9.]* s' "$work/$name.before.log" | awk '{print $3}')
  t_after=$(grep -o 'timing:     best [0-9.]* s' "$work/$name.after.log" | awk '{print $3}')
  if cmp -s "$work/$name.before.json" "$work/$name.after.json"; then
    echo "same  $name (timing ${t_before} s -> ${t_after} s)"
  else
    echo "DIFF  $name:"; diff <(tr ',' '\n' <"$work/$name.before.json") <(tr ',' '\n' <"$work/$name.after.json") | head -10 || true
    fail=1
  fi
done
exit $fail
