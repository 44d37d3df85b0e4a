#!/usr/bin/env bash
# Counts the instructions one run executes (valgrind's callgrind): a speed
# figure that, unlike wall-clock time on a shared VM, is the same on every run
# of the same binary and input, so a change of a few per cent is visible at once.
# Only the run itself is counted (runTiming, or FunctionalRenderer::render),
# not the bench's trace generation; per record of the trace (opaque ones too).
#
#   bench/count_instructions.sh BENCH_TIMING [--mode timing|functional] [--engine cycle|approximate]
#                               [--scene small|bench] [-- MORE_BENCH_TIMING_OPTIONS]
#
# --scene small (default): 640x360, 5,000 quads, 1.51 M records, 4-16 s under
# valgrind; bench: the bench trace (1280x720, 6.17 M records), about 4x as long.
# Needs valgrind (Debian package valgrind).
set -euo pipefail
usage() {
  echo "usage: $0 BENCH_TIMING [--mode timing|functional] [--engine cycle|approximate] [--scene small|bench] [-- OPTIONS]" >&2
  exit 2
}
[ $# -ge 1 ] || usage
bin=$1
shift
[ -x "$bin" ] || { echo "$0: $bin is not an executable" >&2; exit 2; }
mode=timing engine=cycle scene=small extra=()
while [ $# -gt 0 ]; do
  case $1 in
    --mode | --engine | --scene)
      [ $# -ge 2 ] || { echo "$0: $1 needs a value" >&2; exit 2; }
      case "$1=$2" in
        --mode=timing | --mode=functional) mode=$2 ;;
        --engine=cycle | --engine=approximate) engine=$2 ;;
        --scene=small | --scene=bench) scene=$2 ;;
        *) echo "$0: $1 $2: not one of the values in the usage" >&2; usage ;;
      esac
      shift 2 ;;
    --) shift; extra=("$@"); break ;;
    *) echo "$0: unknown option $1" >&2; usage ;;
  esac
done
command -v valgrind >/dev/null || { echo "$0: valgrind not found (apt-get install valgrind)" >&2; exit 2; }

args=(--mode "$mode" --reps 1)
[ "$scene" = small ] && args+=(--width 640 --height 360 --quads 5000)
if [ "$mode" = timing ]; then
  args+=(--set "sim.engine=$engine")
  collect='oit::rop::runTiming*'
else
  collect='oit::model::FunctionalRenderer::render*'
fi
args+=("${extra[@]}")

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
export SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1
# The timing run happens in a forked child: --trace-children follows it, and
# --toggle-collect counts only inside the run's function in every process.
if ! valgrind --tool=callgrind --trace-children=yes --toggle-collect="$collect" --log-file="$work/valgrind.%p" \
  --callgrind-out-file="$work/cg.%p" "$bin" "${args[@]}" >"$work/bench.log" 2>"$work/bench.err"; then
  echo "$0: the run failed:" >&2
  cat "$work/bench.err" >&2
  exit 1
fi
records=$(grep -o '[0-9.]* M records' "$work/bench.log" | head -1 | awk '{print $1 * 1e6}')
total=0
for f in "$work"/cg.*; do
  n=$(grep -m1 '^totals:' "$f" | awk '{print $2}')
  total=$((total + ${n:-0}))
done
[ "$total" -gt 0 ] || { echo "$0: no instructions counted in $collect" >&2; exit 1; }
awk -v t="$total" -v r="$records" -v m="$mode" -v e="$engine" -v s="$scene" 'BEGIN {
  printf "%s%s, scene %s: %.0f instructions, %.1f per record (%.3f M records)\n",
         m, (m == "timing" ? " (" e ")" : ""), s, t, t / r, r / 1e6 }'
