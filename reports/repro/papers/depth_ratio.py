#!/usr/bin/env python3
"""The A-buffer against MLAB k=4 as the depth complexity grows (issue 22 s4):
reads the report.json of `oitsim run` points named SCENE-DENSITY-ALGO in a
folder (README.md, "A-buffer against MLAB k=4 against depth complexity", has
the commands), prints the table and writes abuffer-vs-depth.png.

    python3 reports/repro/papers/depth_ratio.py RUNS_DIR [PAGE_DIR]
"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main():
    runs = sys.argv[1]
    page = sys.argv[2] if len(sys.argv) > 2 else os.path.dirname(os.path.abspath(__file__))
    points = {}
    for name in sorted(os.listdir(runs)):
        path = os.path.join(runs, name, "report.json")
        if not os.path.isfile(path) or name.count("-") != 2:
            continue
        scene, density, algo = name.split("-")
        with open(path) as f:
            r = json.load(f)
        points.setdefault((scene, float(density)), {})[algo] = r
    print("| scene | density | fragments | per pixel | A-buffer (us) | MLAB k=4 (us) | ratio | A-buffer resolve / insert (M cycles) |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    series = {}
    engines = set()
    for (scene, density), p in sorted(points.items()):
        if "abuffer" not in p or "mlab" not in p:
            continue
        a, m = p["abuffer"], p["mlab"]
        n = a["fragments"]["in"]
        per_pixel = n / (a["trace"]["width"] * a["trace"]["height"])
        engines.update(r["config"]["rop"]["sim"]["engine"] for r in (a, m))
        fa, fm = a["timing"]["frame_time_us"], m["timing"]["frame_time_us"]
        ph = a["timing"]["phase_cycles"]
        print(f"| {scene} | {density:g} | {n:,} | {per_pixel:.1f} | {fa:,.0f} | {fm:,.0f} | {fa / fm:.2f}x | "
              f"{ph['resolve'] / 1e6:.1f} / {sum(ph['transparent']) / 1e6:.1f} |")
        series.setdefault(scene, []).append((per_pixel, fa / fm))
    if len(engines) != 1:
        sys.exit(f"depth_ratio.py: points from more than one engine: {sorted(engines)}")
    engine = engines.pop()
    fig, ax = plt.subplots(figsize=(6, 4))
    for scene, pts in sorted(series.items()):
        pts.sort()
        ax.plot([x for x, _ in pts], [y for _, y in pts], "o-", label=scene)
    ax.axhline(3.0, color="grey", ls="--", lw=1, label="issue 22: >= 3x")
    ax.set_xlabel("fragments per pixel")
    ax.set_ylabel("A-buffer / MLAB k=4 frame time")
    ax.set_ylim(bottom=0)
    ax.legend()
    ax.set_title(f"A-buffer against MLAB k=4, iris-pro-5200, {engine} engine")
    fig.tight_layout()
    fig.savefig(os.path.join(page, "abuffer-vs-depth.png"), dpi=100, metadata={"Software": None})


if __name__ == "__main__":
    main()
