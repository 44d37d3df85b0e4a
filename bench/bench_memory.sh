#!/usr/bin/env bash
# Peak resident memory and run time of `oitsim run` against the trace's
# length: the particles scene at 1280x720 with 3 M and 30 M fragments (and
# 100 M with --full: a 3.2 GB trace and much longer runs),
# streamed from trace files on disk, for bounded algorithms in functional and
# timing mode. Peak RSS is /usr/bin/time's maximum resident set; the
# estimate is the pre-check's (report.json sim.memory); cpu s is user + system
# time, which a shared machine's load changes less than the wall clock. Then a 16384 x 16384
# A-buffer frame, which must be refused before any work or run within the
# budget. Results: bench/RESULTS-memory.md.
#   bench/bench_memory.sh [--full | --sizes 3M,30M,100M] [--no-huge] [WORKDIR]
#   (default 3M and 30M; --full all three; --no-huge skips the 16384^2 frame;
#   WORKDIR default /tmp/oitsim-bench-memory, needs ~4.5 GB with 100M)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
want="3M 30M"
huge=1
while [ $# -gt 0 ]; do
  case $1 in
    --full) want="3M 30M 100M"; shift ;;
    --sizes) want=${2//,/ }; shift 2 ;;
    --no-huge) huge=0; shift ;;
    *) break ;;
  esac
done
work=${1:-/tmp/oitsim-bench-memory}
oitsim=${OITSIM:-$root/build/apps/oitsim}
[ -x "$oitsim" ] || { echo "bench_memory.sh: build first (scripts/build.sh): no $oitsim" >&2; exit 1; }
command -v /usr/bin/time >/dev/null || { echo "bench_memory.sh: needs /usr/bin/time (Debian package time)" >&2; exit 1; }
mkdir -p "$work"
export SYSTEMC_DISABLE_COPYRIGHT_MESSAGE=1

# particles: 3.04 M fragments at density 1; the density scales the quads.
sizes=()
for w in $want; do
  case $w in
    3M) sizes+=("3M 1") ;; 30M) sizes+=("30M 10") ;; 100M) sizes+=("100M 33") ;;
    *) echo "bench_memory.sh: --sizes: expected 3M, 30M or 100M, got '$w'" >&2; exit 2 ;;
  esac
done
for s in "${sizes[@]}"; do
  set -- $s
  t="$work/particles-$1.oitt"
  [ -f "$t" ] || "$oitsim" gen particles --density "$2" -q -o "$t"
done

# The first configuration of each size (functional alpha) builds the exact
# A-buffer reference in bands, the phase that holds the most memory on a long
# trace; the others compare with that run's reference.pfm (--reference FILE:
# the same image, read instead of built again), which keeps a 100 M run to its
# own render. OITSIM_BENCH_EXACT_EACH=1 builds the reference in every run.
printf '%-6s %-10s %-22s %12s %12s %10s %10s %10s %12s %8s %s\n' trace mode config fragments "peak RSS" estimate seconds "cpu s" \
  "ns/fragment" bands reference
for s in "${sizes[@]}"; do
  set -- $s
  size=$1
  t="$work/particles-$size.oitt"
  ref="$work/reference-$size.pfm"
  first=1
  for cfg in "functional --algo alpha" "functional --algo mlab --layers 4" "functional --algo wboit" \
             "functional --algo adaptive --layers 8" "timing --algo mlab --layers 4 --set sim.engine=approximate" \
             "timing --algo mlab --layers 4"; do
    read -r mode rest <<<"$cfg"
    out="$work/run"
    reference=abuffer
    [ $first -eq 0 ] && [ "${OITSIM_BENCH_EXACT_EACH:-0}" != 1 ] && reference=$ref
    /usr/bin/time -o "$work/time.txt" -f "%M %e %U %S" "$oitsim" run -q --trace "$t" --out "$out" --mode $mode $rest \
      --reference "$reference"
    [ $first -eq 1 ] && cp "$out/reference.pfm" "$ref"
    first=0
    read -r kib secs usr sys <"$work/time.txt"
    python3 - "$out/report.json" "$size" "$mode" "$rest" "$kib" "$secs" "$usr" "$sys" "$reference" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
trace, mode, cfg, kib, secs = sys.argv[2], sys.argv[3], sys.argv[4], int(sys.argv[5]), float(sys.argv[6])
cpu = float(sys.argv[7]) + float(sys.argv[8])
ref = "exact" if sys.argv[9] == "abuffer" else "file"
m = j["sim"]["memory"]
frags = j["trace"]["fragments"]
short = cfg.replace("--algo ", "").replace("--layers ", "k").replace("--set sim.engine=approximate", "approx")
print(f"{trace:<6} {mode:<10} {short:<22} {frags:>12} {kib/1024:>9.1f} MiB {m['estimate_bytes']/2**20:>6.1f} MiB "
      f"{secs:>10.1f} {cpu:>10.1f} {cpu*1e9/frags:>12.1f} {m['reference_bands']:>7} {ref}", flush=True)
PY
  done
done

# A 16384 x 16384 frame with one fragment, A-buffer under test: refused
# before any work with the default budget on a machine with less than ~27 GiB
# for it; with --reference none (state + image, 32 B per pixel) it runs where
# 8 GiB fit the budget.
[ $huge -eq 1 ] || exit 0
big="$work/huge.csv"
printf '# width 16384\n# height 16384\ndraw,prim,x,y,z,r,g,b,a,opaque\n0,0,1,1,0.5,1,0,0,0.5,0\n' >"$big"
for ref in abuffer none; do
  set +e
  /usr/bin/time -o "$work/time.txt" -f "%M %e" "$oitsim" run -q --trace "$big" --out "$work/huge" --algo abuffer \
    --mode functional --reference $ref 2>"$work/err.txt"
  rc=$?
  set -e
  read -r kib secs <"$work/time.txt"
  printf '16384x16384 abuffer --reference %-7s exit %d, %.2f s, peak RSS %d MiB: %s\n' "$ref" "$rc" "$secs" \
    "$((kib / 1024))" "$(head -c 300 "$work/err.txt" | tr '\n' ' ')"
done
