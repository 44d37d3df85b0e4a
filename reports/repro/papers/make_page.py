#!/usr/bin/env python3
"""The papers' relative results against the model (issue 22): writes
results.md (the paper's figure beside the model's for every claim, what
bounds each point) and frame-time-vs-k.png from the results.csv of the two
sweeps reports/repro/papers/run.sh makes.

    python3 reports/repro/papers/make_page.py MLAB_SWEEP_DIR CONTINUUM_SWEEP_DIR [PAGE_DIR]

The analysis beside the numbers (which is wrong where model and paper
disagree, and why) is README.md in the same folder, written by hand from
these tables; this script never edits it.
"""
import csv
import os
import sys

# The papers' figures (text of ../shared/papers).
PAPER_ABUFFER_OVER_MLAB = "more than 10x (MLAB paper, 'generally more than an order of magnitude slower')"
PAPER_ABUFFER_OVER_AT = "5x to 40x (AT paper: 'five to forty times faster than real-time A-buffer implementations')"
PAPER_HT_VS_MLAB = "'virtually identical' (MLAB paper, Figure 2 text)"
# Wyman 2016, Table 3, Foliage Map column (ms, Titan X, 2560x1440, k = 4, 8 samples, b = 32).
TABLE3_FOLIAGE = {"slab-b32": 89.2, "stochastic-s8": 162.0, "hybrid": 175.9, "mlcb-b32": 168.1, "mlab": 346.1}
TABLE3_NAMES = {"slab-b32": "SLAB (b = 32)", "stochastic-s8": "stochastic (8 samples)", "hybrid": "hybrid (HT)",
                "mlcb-b32": "MLCB (b = 32)", "mlab": "MLAB"}


def rows(sweep):
    path = os.path.join(sweep, "results.csv")
    with open(path, newline="") as f:
        return [r for r in csv.DictReader(f) if r.get("status") == "ok"]


def num(r, key):
    v = r.get(key, "")
    try:
        return float(v)
    except ValueError:
        return None


def causes(r, top=3):
    """The largest root causes of a point as 'cause share' text."""
    cs = {k[len("timing.root_cause_cycles."):]: float(v) for k, v in r.items()
          if k.startswith("timing.root_cause_cycles.") and v not in ("", None)}
    total = sum(cs.values())
    if not total:
        return ""
    best = sorted(cs.items(), key=lambda kv: -kv[1])[:top]
    return ", ".join(f"{k} {100 * v / total:.0f} %" for k, v in best if v > 0)


def fit(ks, ys):
    """Least-squares line y = a + b k and its R^2."""
    n = len(ks)
    mk, my = sum(ks) / n, sum(ys) / n
    sxx = sum((k - mk) ** 2 for k in ks)
    b = sum((k - mk) * (y - my) for k, y in zip(ks, ys)) / sxx
    a = my - b * mk
    ss_res = sum((y - (a + b * k)) ** 2 for k, y in zip(ks, ys))
    ss_tot = sum((y - my) ** 2 for y in ys)
    return a, b, (1 - ss_res / ss_tot) if ss_tot > 0 else 1.0


def verdict(ok):
    return "holds" if ok else "**does not hold**"


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    mlab_dir, cont_dir = sys.argv[1], sys.argv[2]
    page = sys.argv[3] if len(sys.argv) > 3 else os.path.dirname(os.path.abspath(__file__))
    out = []
    w = out.append
    w("# The papers' relative results against the model (generated)")
    w("")
    w("Made by `reports/repro/papers/run.sh` (sweeps `reports/sweep/papers-mlab.yaml` and "
      "`reports/sweep/papers-continuum.yaml`, then `make_page.py`); the analysis is README.md. "
      "Frame times are the model's (`timing.frame_time_us`); *bound by* is `timing.bound_by` with its share "
      "of the partition-cycles, *root causes* the three largest of `timing.root_cause_cycles`.")
    w("")

    pts = rows(mlab_dir)
    by = {}
    for r in pts:
        algo = r["axis.algo"]
        k = int(r["axis.layers"]) if algo != "abuffer" else 0
        by[(r["trace"], algo, k)] = r
    traces = sorted({r["trace"] for r in pts})

    w("## MLAB and AT papers, 1280x720, Iris Pro 5200 (`iris-pro-5200`)")
    w("")
    w("| scene | A-buffer (us) | MLAB k=4 (us) | HT k=4 (us) | AT k=4 (us) | A-buffer / MLAB 4 | A-buffer / AT 4 | HT 4 / MLAB 4 |")
    w("| --- | --- | --- | --- | --- | --- | --- | --- |")
    claims = []
    for t in traces:
        a, m, h, at = (by.get((t, "abuffer", 0)), by.get((t, "mlab", 4)), by.get((t, "hybrid", 4)),
                       by.get((t, "adaptive", 4)))
        if not (a and m and h and at):
            continue
        ua, um, uh, uat = (num(x, "timing.frame_time_us") for x in (a, m, h, at))
        w(f"| {t} | {ua:,.0f} | {um:,.0f} | {uh:,.0f} | {uat:,.0f} | {ua / um:.2f}x | {ua / uat:.2f}x | "
          f"{100 * (uh / um - 1):+.1f} % |")
        if t in ("particles", "hair"):
            claims.append((f"{t}: A-buffer at least 3x slower than MLAB k=4", PAPER_ABUFFER_OVER_MLAB,
                           f"{ua / um:.2f}x", ua / um >= 3))
            claims.append((f"{t}: A-buffer slower than AT k=4", PAPER_ABUFFER_OVER_AT, f"{ua / uat:.2f}x", ua > uat))
            claims.append((f"{t}: HT within 10 % of MLAB at equal memory (k=4, 32 B/pixel)", PAPER_HT_VS_MLAB,
                           f"{100 * (uh / um - 1):+.1f} %", abs(uh / um - 1) <= 0.10))
    w("")
    w("What bounds each point (k = 4; the A-buffer has no k):")
    w("")
    w("| scene | algorithm | frame (us) | bound by | root causes | DRAM utilisation | phases (cycles: opaque / transparent passes / resolve) |")
    w("| --- | --- | --- | --- | --- | --- | --- |")
    for t in traces:
        for algo, k in (("abuffer", 0), ("mlab", 4), ("hybrid", 4), ("adaptive", 4)):
            r = by.get((t, algo, k))
            if not r:
                continue
            share = num(r, "timing.bound_by.share")
            dram = num(r, "timing.utilization.dram_bus")
            w(f"| {t} | {algo}{'' if not k else f' k={k}'} | {num(r, 'timing.frame_time_us'):,.0f} | "
              f"{r.get('timing.bound_by.resource', '')} {100 * (share or 0):.0f} % | {causes(r)} | "
              f"{100 * (dram or 0):.0f} % | {r.get('timing.phase_cycles.opaque', '')} / "
              f"{r.get('timing.phase_cycles.transparent', '')} / {r.get('timing.phase_cycles.resolve', '')} |")
    w("")

    # Frame time against k: a line per scene and algorithm, fitted.
    w("## Frame time against k (MLAB paper: 'rendering times for MLAB and HT scale almost linearly with the number of layers' on simple shaders)")
    w("")
    w("| scene | algorithm | k = 2, 4, 6, 8 (us) | fit (us) | R^2 |")
    w("| --- | --- | --- | --- | --- |")
    series = []
    for t in traces:
        for algo in ("mlab", "hybrid", "adaptive"):
            ks = [k for k in (2, 4, 6, 8) if (t, algo, k) in by]
            if len(ks) < 3:
                continue
            ys = [num(by[(t, algo, k)], "timing.frame_time_us") for k in ks]
            a, b, r2 = fit(ks, ys)
            series.append((t, algo, ks, ys, a, b, r2))
            w(f"| {t} | {algo} | {', '.join(f'{y:,.0f}' for y in ys)} | {a:,.0f} + {b:,.1f} k | {r2:.3f} |")
            if t == "foliage" and algo in ("mlab", "hybrid"):
                claims.append((f"{t} (simple shading): {algo} frame time roughly linear in k",
                               "almost linear (MLAB paper, TEAPOTS and FOREST)", f"R^2 = {r2:.3f}, slope {b:,.1f} us per layer",
                               r2 >= 0.9 and b > 0))
    w("")
    w("![frame time against k](frame-time-vs-k.png)")
    w("")
    plot(series, os.path.join(page, "frame-time-vs-k.png"))

    # The continuum paper's Table 3.
    cpts = rows(cont_dir)
    cby = {r["axis.method"]: r for r in cpts}
    w("## Continuum paper, Table 3: Titan X (`titan-x-maxwell`), 2560x1440, every surface alpha 0.75")
    w("")
    w("| algorithm | paper, Foliage Map (ms) | paper rank | model (us) | model rank | bound by | root causes |")
    w("| --- | --- | --- | --- | --- | --- | --- |")
    paper_rank = {m: i + 1 for i, m in enumerate(sorted(TABLE3_FOLIAGE, key=TABLE3_FOLIAGE.get))}
    have = [m for m in TABLE3_FOLIAGE if m in cby]
    model_rank = {m: i + 1 for i, m in enumerate(sorted(have, key=lambda m: num(cby[m], "timing.frame_time_us")))}
    for m in sorted(TABLE3_FOLIAGE, key=TABLE3_FOLIAGE.get):
        if m not in cby:
            continue
        r = cby[m]
        share = num(r, "timing.bound_by.share")
        w(f"| {TABLE3_NAMES[m]} | {TABLE3_FOLIAGE[m]} | {paper_rank[m]} | {num(r, 'timing.frame_time_us'):,.0f} | "
          f"{model_rank[m]} | {r.get('timing.bound_by.resource', '')} {100 * (share or 0):.0f} % | {causes(r)} |")
    if len(have) == len(TABLE3_FOLIAGE):
        slowest = max(have, key=lambda m: num(cby[m], "timing.frame_time_us"))
        fastest = min(have, key=lambda m: num(cby[m], "timing.frame_time_us"))
        claims.append(("Table 3: MLAB slowest of the five", "MLAB 346.1 ms, slowest", TABLE3_NAMES[slowest], slowest == "mlab"))
        claims.append(("Table 3: SLAB fastest", "SLAB 89.2 ms, fastest", TABLE3_NAMES[fastest], fastest == "slab-b32"))
    w("")

    summary = ["## Claims", "", "| claim | paper | model | |", "| --- | --- | --- | --- |"]
    summary += [f"| {c} | {p} | {m} | {verdict(ok)} |" for c, p, m, ok in claims]
    summary.append("")
    text = "\n".join(out[:4] + summary + out[4:]) + "\n"
    with open(os.path.join(page, "results.md"), "w") as f:
        f.write(text)
    print(text)


def plot(series, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    traces = sorted({s[0] for s in series})
    if not traces:
        return
    fig, axes = plt.subplots(1, len(traces), figsize=(5 * len(traces), 4), squeeze=False)
    for ax, t in zip(axes[0], traces):
        for (tt, algo, ks, ys, a, b, r2) in series:
            if tt != t:
                continue
            line = ax.plot(ks, ys, "o", label=f"{algo}: {a:,.0f} + {b:,.1f} k (R^2 {r2:.3f})")[0]
            ax.plot([ks[0], ks[-1]], [a + b * ks[0], a + b * ks[-1]], "-", color=line.get_color(), alpha=0.6)
        ax.set_title(f"{t}, 1280x720, iris-pro-5200")
        ax.set_xlabel("k (layers / nodes)")
        ax.set_ylabel("modelled frame time (us)")
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=90)


if __name__ == "__main__":
    main()
