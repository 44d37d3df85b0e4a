#!/usr/bin/env bash
# The price of order (issue 23): the per-pixel interlock ordered (ROV,
# PixelSync), unordered (mutual exclusion only) and none (racing
# read-modify-writes), on particles and hair at 640x360, MLAB k = 2, each run
# with 8 shader-latency seeds (oitsim run --seeds 8: input.seed 1..8), in three
# configurations: igpu with the paper's 8-byte rgba8t8z32 rows, igpu with fp32
# rows, dgpu with rgba8t8z32 rows. Prints a Markdown table (results.md) and
# copies into PAGE/images seed 0's image.png of the rgba8t8z32 runs (ordered:
# igpu only, it is the same image on dgpu; none) and their flicker.png
# (unordered, none).
#   reports/repro/ordering/run.sh [OITSIM=build/apps/oitsim] [WORKDIR=out/repro/ordering] [PAGE=reports/repro/ordering]
set -euo pipefail
oitsim=${1:-build/apps/oitsim}
work=${2:-out/repro/ordering}
page=${3:-reports/repro/ordering}
scenes="particles hair"
configs="igpu:rgba8t8z32 igpu:fp32 dgpu:rgba8t8z32"
modes="ordered unordered none"
mkdir -p "$work" "$page/images"
for t in $scenes; do
  "$oitsim" gen "$t" -o "$work/$t.oitt" --width 640 --height 360 -q >/dev/null
  for c in $configs; do
    preset=${c%%:*} format=${c##*:}
    for m in $modes; do
      out="$work/${t}_${preset}_${format}_$m"
      "$oitsim" run -t "$work/$t.oitt" -a mlab -k 2 --format "$format" --preset "$preset" --seeds 8 \
        --set lock.mode=$m -o "$out" -q
      if [ "$format" = rgba8t8z32 ]; then
        if [ "$m" = none ] || { [ "$m" = ordered ] && [ "$preset" = igpu ]; }; then
          cp "$out/image.png" "$page/images/${t}_${preset}_$m.png"
        fi
        [ "$m" = ordered ] || cp "$out/flicker.png" "$page/images/${t}_${preset}_${m}_flicker.png"
      fi
    done
  done
done
python3 - "$work" "$configs" <<'PY'
import json, sys
work, configs = sys.argv[1], [c.split(":") for c in sys.argv[2].split()]
print("| scene | preset / rows | lock.mode | frame cycles, seed 0 (8 seeds: min - max) | lock conflicts | lock wait cycles "
      "| out-of-order entries | lost updates (8 seeds: mean) | RMSE vs A-buffer (8 seeds: mean / worst) "
      "| flicker: std mean / max (sRGB8 levels) | pixels differing between seeds |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for t in ["particles", "hair"]:
    for preset, f in configs:
        for m in ["ordered", "unordered", "none"]:
            r = json.load(open(f"{work}/{t}_{preset}_{f}_{m}/report.json"))
            fl = r["image"]["flicker"]
            lost = sum(s["lost_updates"] for s in fl["per_seed"]) / fl["seeds"]
            lk = r["lock"]
            print(f"| {t} | {preset} / {f} | {m} | {r['timing']['cycles']:,} ({fl['cycles_min']:,} - {fl['cycles_max']:,}) "
                  f"| {lk['conflicts']:,} | {lk['wait_cycles']:,} | {lk['out_of_order_entries']:,} | {lost:,.1f} "
                  f"| {fl['rmse_mean']:.6f} / {fl['rmse_worst']:.6f} | {fl['std_mean']:.4f} / {fl['std_max']:.2f} "
                  f"| {fl['differing_pixels']:,} ({100 * fl['differing_fraction']:.3f} %) |".replace(",", " "))
print()
frags = {t: json.load(open(f"{work}/{t}_igpu_fp32_ordered/report.json"))["fragments"]["in"] for t in ["particles", "hair"]}
print(f"Fragments: particles {frags['particles']:,}; hair {frags['hair']:,}.".replace(",", " "))
PY
