#!/usr/bin/env bash
# Alternates builds of `oitsim capture --apitrace` on one frame, as
# bench/RESULTS-capture-apitrace.md measured them: per run, the capture's own time
# (its final line), the CPU of the command and its children (perf stat task-clock:
# Xvfb, xkbcomp, glretrace, llvmpipe's threads) and the wall time.
#   bench/capture_apitrace_ab.sh TRACE FRAME ROUNDS NAME=OITSIM [NAME=OITSIM ...]
# Each OITSIM is an oitsim executable with its liboitsim_interposer.so beside it;
# the outputs are written to NAME.oitt in the current folder (compare them with cmp).
set -euo pipefail
trace=$1 frame=$2 rounds=$3
shift 3
for _ in $(seq "$rounds"); do
  for spec in "$@"; do
    name=${spec%%=*} bin=${spec#*=}
    out=$(perf stat -x, -e task-clock,duration_time -o "perf.$name.txt" \
      "$bin" capture --apitrace "$trace" --frames "$frame" -o "$name.oitt")
    own=$(echo "$out" | tail -1 | sed -E 's/.* in ([0-9.]+) s.*/\1/')
    cpu=$(awk -F, '/task-clock/ {printf "%.3f", $1 / 1000}' "perf.$name.txt")
    wall=$(awk -F, '/duration_time/ {printf "%.3f", $1 / 1e9}' "perf.$name.txt")
    echo "$name own=${own}s cpu=${cpu}s wall=${wall}s"
  done
done
