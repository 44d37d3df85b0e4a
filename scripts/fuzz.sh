#!/usr/bin/env bash
# Runs each libFuzzer harness of tests/fuzz for SECONDS (default 60) and fails
# on any crash, sanitizer report, leak, input slower than 10 s (-timeout) or
# process above 2 GiB (-rss_limit_mb). Builds them first (build-sanitize/).
#   scripts/fuzz.sh [SECONDS] [HARNESS...]     harnesses: binary_trace csv_trace config sweep_spec
# Each starts from its committed seeds (tests/fuzz/corpus/<harness>, read only)
# and its dictionary (tests/fuzz/<harness>.dict); new inputs go to
# build-sanitize/fuzz/corpus/<harness>, crashing ones to build-sanitize/fuzz/
# (crash-*, leak-*, timeout-*, oom-*). Prints each harness's executions.
# OITSIM_JOBS harnesses run at once (default: the number of cores).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${OITSIM_SANITIZE_BUILD_DIR:-$root/build-sanitize}
seconds=${1:-60}
shift || true
case $seconds in '' | *[!0-9]*) echo "fuzz.sh: SECONDS must be a whole number, got '$seconds'" >&2; exit 2 ;; esac
harnesses=("$@")
[ ${#harnesses[@]} -gt 0 ] || harnesses=(binary_trace csv_trace config sweep_spec)
"$root/scripts/setup.sh" >/dev/null
# Only the harnesses asked for (the tests in the same build folder are scripts/sanitize.sh's).
targets=""
for h in "${harnesses[@]}"; do
  case $h in
    binary_trace | csv_trace | config | sweep_spec) targets+=" fuzz_$h" ;;
    *) echo "fuzz.sh: no harness '$h' (expected binary_trace, csv_trace, config or sweep_spec)" >&2; exit 2 ;;
  esac
done
OITSIM_SANITIZE_TARGETS="${targets# }" "$root/scripts/build-sanitize.sh"
export SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
work="$build/fuzz"
# The harnesses run side by side, OITSIM_JOBS (default: the cores) at a time:
# each is one single-threaded process, and CI waits for them.
parallel=${OITSIM_JOBS:-$(nproc)}
run_one() {
  local h=$1 exe="$build/tests/fuzz/fuzz_$1" rc
  mkdir -p "$work/corpus/$h"
  set +e
  "$exe" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=4096 -print_final_stats=1 \
    -dict="$root/tests/fuzz/$h.dict" -artifact_prefix="$work/$h-" \
    "$work/corpus/$h" "$root/tests/fuzz/corpus/$h" >"$work/$h.log" 2>&1
  rc=$?
  set -e
  echo $rc >"$work/$h.rc"
}
for h in "${harnesses[@]}"; do
  [ -x "$build/tests/fuzz/fuzz_$h" ] || { echo "fuzz.sh: no harness '$h' ($build/tests/fuzz/fuzz_$h)" >&2; exit 2; }
done
mkdir -p "$work"
echo "== ${harnesses[*]}: ${seconds}s each, $parallel at a time"
for h in "${harnesses[@]}"; do
  while [ "$(jobs -rp | wc -l)" -ge "$parallel" ]; do wait -n || true; done
  rm -f "$work/$h.rc"
  run_one "$h" &
done
wait
failed=()
for h in "${harnesses[@]}"; do
  log="$work/$h.log"
  rc=$(cat "$work/$h.rc" 2>/dev/null || echo 1)
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -n1)
  echo "== fuzz_$h: executions: ${runs:-?}, corpus: $(ls "$work/corpus/$h" | wc -l) inputs, exit code $rc"
  if [ "$rc" -ne 0 ]; then
    failed+=("$h")
    grep -E "ERROR|SUMMARY|Test unit written" "$log" | head -n 20 || true
    echo "   (full log: $log)"
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz.sh: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "fuzz.sh: all ${#harnesses[@]} harnesses ran ${seconds}s without a finding"
