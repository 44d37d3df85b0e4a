#!/usr/bin/env bash
# The tests under AddressSanitizer + UndefinedBehaviorSanitizer: a clang build
# of everything in build-sanitize/ (-fsanitize=address,undefined, errors abort;
# the libFuzzer harnesses of tests/fuzz are built there too), then every test
# through ctest except those labelled systemc-process-exception (see
# tests/CMakeLists.txt for why ASan cannot check them).
#   scripts/sanitize.sh [ctest options, e.g. -R Csv]   (what CI runs, without options)
#   scripts/sanitize.sh --quick   (test_model and test_traces only, and the fuzz
#     harnesses' build: a few minutes, while iterating on those folders)
# OITSIM_SANITIZE_BUILD_DIR and OITSIM_JOBS change the folder and parallelism.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${OITSIM_SANITIZE_BUILD_DIR:-$root/build-sanitize}
jobs=${OITSIM_JOBS:-$(nproc)}
"$root/scripts/setup.sh" >/dev/null
quick=0
if [ "${1:-}" = --quick ]; then
  quick=1
  shift
  export OITSIM_SANITIZE_TARGETS="test_model test_traces fuzz_binary_trace fuzz_csv_trace fuzz_config fuzz_sweep_spec"
fi
"$root/scripts/build-sanitize.sh"
export SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1
# Leaks are errors too; a report stops the process with a non-zero exit.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:abort_on_error=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
cd "$build"
if [ $quick = 1 ]; then
  for t in test_model test_traces; do
    echo "== $t under ASan+UBSan"
    "$build/tests/$t" --gtest_brief=1
  done
  exit 0
fi
ctest --output-on-failure -j "$jobs" -LE systemc-process-exception "$@"
