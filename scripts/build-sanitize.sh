#!/usr/bin/env bash
# Configures (once) and builds the sanitizer + fuzzer build in build-sanitize/:
# clang, -fsanitize=address,undefined, -O1 with line tables, the libFuzzer harnesses
# (OITSIM_FUZZ) and the tests, no benchmarks: one build of the libraries serves
# both (the fuzzers need every library instrumented for coverage anyway). -O1:
# the build is what CI waits for and
# ASan's checks cost more than the optimisation gains; NDEBUG as in Release, so
# the tests check the code that ships. Used by scripts/sanitize.sh and
# scripts/fuzz.sh. OITSIM_SANITIZE_BUILD_DIR and OITSIM_JOBS as there;
# OITSIM_SANITIZE_TARGETS (space-separated) builds only those targets. A new
# folder is a unity build (OITSIM_UNITY=OFF for one you edit often: see
# scripts/build.sh).
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${OITSIM_SANITIZE_BUILD_DIR:-$root/build-sanitize}
jobs=${OITSIM_JOBS:-$(nproc)}
cxx=$(command -v clang++-14 || command -v clang++ || true)
[ -n "$cxx" ] || { echo "build-sanitize.sh: needs clang++ (scripts/setup.sh installs clang-14)" >&2; exit 1; }
if [ ! -f "$build/build.ninja" ]; then
  opts=()
  command -v ccache >/dev/null && opts+=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_FLAGS_RELEASE="-O1 -DNDEBUG" \
    -DCMAKE_CXX_COMPILER="$cxx" \
    -DOITSIM_SANITIZE=address,undefined -DOITSIM_FUZZ=ON -DOITSIM_BUILD_BENCH=OFF \
    -DCMAKE_UNITY_BUILD="${OITSIM_UNITY:-ON}" "${opts[@]}" >/dev/null
fi
targets=()
for t in ${OITSIM_SANITIZE_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$build" -j "$jobs" "${targets[@]}"
