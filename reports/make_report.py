#!/usr/bin/env python3
"""Draws DIR/report.html for an `oitsim sweep` folder: one self-contained page
(every image and plot a base64 data URI, no script or style from elsewhere).

Called by `oitsim report DIR` after it has rebuilt DIR/results.json; needs
Debian's python3-matplotlib (and numpy, which it depends on). Sections: speed
modes of the simulator, then per trace the Pareto plots, the image strip, the
stall breakdown and lock waits, the depth-complexity heatmap; then the table of
every point. Also writes DIR/speed.json (the speed-mode figures) for scripts.
"""
import argparse
import base64
import html
import io
import json
import math
import os
import subprocess
import sys
import tempfile

import matplotlib

matplotlib.use("Agg")  # no display: render to PNG in memory
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

STALL_CAUSES = ["lock_wait", "scoreboard_full", "cache_miss_wait", "dram_bandwidth", "alu_busy", "input_starved"]
SPEED_KEYS = ("config.rop.sim.quantum_cycles", "config.rop.skip.idle_cycles")


def read_pfm(path):
    """Returns an HxWx3 float array, top row first."""
    with open(path, "rb") as f:
        kind = f.readline().strip()
        w, h = (int(v) for v in f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    ch = 3 if kind == b"PF" else 1
    img = data[: w * h * ch].reshape(h, w, ch)
    if ch == 1:
        img = np.repeat(img, 3, axis=2)
    return np.flipud(img)  # PFM is bottom row first


def srgb8(lin):
    c = np.clip(np.nan_to_num(lin), 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def png_uri_from_array(rgb8):
    buf = io.BytesIO()
    plt.imsave(buf, rgb8, format="png")
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def file_uri(path):
    with open(path, "rb") as f:
        return "data:image/png;base64," + base64.b64encode(f.read()).decode()


def fig_uri(fig):
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90, bbox_inches="tight")
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def num(m, key):
    v = m.get(key)
    return float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else None


def dram_bytes(m):
    r, w = num(m, "memory.dram_read_bytes.total"), num(m, "memory.dram_write_bytes.total")
    if r is not None and w is not None:
        return r + w
    return None


def footprint(m):
    keys = [k for k in m if k.startswith("memory.footprint.allocated.")]
    if keys:
        return sum(float(m[k]) for k in keys)
    return None


def state_traffic(m):
    r, w = num(m, "memory.state_read_bytes"), num(m, "memory.state_write_bytes")
    return r + w if r is not None and w is not None else None


NO_K = ("abuffer", "alpha", "wboit", "wsum", "wavg", "stochastic")  # algorithms without layers (k)


def label(p):
    m = p["metrics"]
    algo = m.get("config.algorithm", "?")
    k = m.get("config.layers")
    return f"{algo} k={k}" if algo not in NO_K else algo


def pareto_front(xs, ys):
    """Indices of points no other point beats on both axes (both minimised)."""
    idx = sorted(range(len(xs)), key=lambda i: (xs[i], ys[i]))
    front, best = [], math.inf
    for i in idx:
        if ys[i] < best:
            front.append(i)
            best = ys[i]
    return front


def pareto_plots(points, trace):
    """2 x 3 grid: frame time, DRAM bytes, footprint against RMSE and 1-SSIM."""
    # With timing points, plot the timing model's figures only; without any, the
    # functional model's state traffic and state bytes stand in (never mixed).
    timing = any(num(p["metrics"], "timing.cycles") is not None for p in points)
    ys = [
        ("modelled frame time (us)", lambda m: num(m, "timing.frame_time_us")),
        ("DRAM bytes read + written" if timing else "state traffic bytes (functional model)",
         (lambda m: dram_bytes(m)) if timing else state_traffic),
        ("footprint allocated (MiB)" if timing else "state bytes (MiB, functional model)",
         (lambda m: footprint(m) / 2**20 if footprint(m) is not None else None) if timing
         else (lambda m: num(m, "memory.state_bytes") / 2**20)),
    ]
    xs = [("RMSE", lambda m: num(m, "image.metrics.rmse")), ("1 - SSIM", lambda m: 1.0 - (num(m, "image.metrics.ssim") or 0))]
    fig, axes = plt.subplots(2, 3, figsize=(15, 8))
    legend_done = False
    algos = sorted({p["metrics"].get("config.algorithm", "?") for p in points})
    colours = {a: plt.cm.tab10(i % 10) for i, a in enumerate(algos)}
    for r, (xname, xf) in enumerate(xs):
        for c, (yname, yf) in enumerate(ys):
            ax = axes[r][c]
            pts = [(xf(p["metrics"]), yf(p["metrics"]), p) for p in points]
            pts = [(x, y, p) for x, y, p in pts if x is not None and y is not None]
            if not pts:
                ax.text(0.5, 0.5, "frame time needs\ntiming-mode points", ha="center", va="center", transform=ax.transAxes)
                ax.set_axis_off()
                continue
            for a in algos:
                sel = [(x, y, p) for x, y, p in pts if p["metrics"].get("config.algorithm") == a]
                if sel:
                    ax.scatter([s[0] for s in sel], [s[1] for s in sel], color=colours[a], label=a, s=36, zorder=3)
                    # k only where the algorithm has one; coincident points get one label.
                    at = {}
                    for x, y, p in sel:
                        if a not in NO_K:
                            at.setdefault((x, y), []).append(f"k{p['metrics'].get('config.layers')}")
                    for (x, y), ks in at.items():
                        ax.annotate("/".join(dict.fromkeys(ks)), (x, y), fontsize=7, xytext=(3, 3),
                                    textcoords="offset points")
            front = pareto_front([x for x, _, _ in pts], [y for _, y, _ in pts])
            fx, fy = [pts[i][0] for i in front], [pts[i][1] for i in front]
            ax.step(fx, fy, where="post", color="grey", linestyle="--", linewidth=1, label="Pareto front", zorder=2)
            # Errors and costs are never negative: no axis below 0 (all-zero errors once
            # gave an RMSE axis from -0.04).
            ax.set_xlim(left=0)
            ax.set_ylim(bottom=0)
            ax.set_xlabel(xname + " vs A-buffer")
            ax.set_ylabel(yname)
            ax.grid(alpha=0.3)
            if not legend_done:  # on the first plot that has points
                ax.legend(fontsize=8)
                legend_done = True
    fig.suptitle(f"{trace}: cost against image error (lower left is better)")
    return fig_uri(fig)


def stall_plot(points, trace):
    timing = [p for p in points if num(p["metrics"], "timing.cycles") is not None]
    if not timing:
        return None
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(15, 4.5), gridspec_kw={"width_ratios": [3, 2]})
    names = [f"{label(p)}\n{p['id'][:4]}" for p in timing]
    bottom = np.zeros(len(timing))
    for cause in STALL_CAUSES:
        vals = np.array([
            sum(float(v) for k, v in p["metrics"].items()
                if k.startswith("timing.stages.") and k.endswith(".stalls." + cause))
            for p in timing])
        ax.bar(names, vals, bottom=bottom, label=cause)
        bottom += vals
    ax.set_ylabel("stall cycles, all stages and partitions")
    ax.set_title(f"{trace}: stalls by cause")
    ax.legend(fontsize=7)
    ax.tick_params(axis="x", labelsize=6, rotation=90)
    # Lock waits: the summed wait cycles per point, and the waiters over time of the worst point.
    waits = [num(p["metrics"], "lock.wait_cycles") or 0 for p in timing]
    worst = timing[int(np.argmax(waits))]
    series = load_timeseries(worst)
    if series:
        ax2.plot([s.get("cycle", 0) for s in series], [s.get("lock_waiters", 0) for s in series], label="lock waiters")
        ax2.plot([s.get("cycle", 0) for s in series], [s.get("scoreboard_occupancy", 0) for s in series],
                 label="scoreboard occupancy", alpha=0.7)
        ax2.set_xlabel("cycle")
        ax2.legend(fontsize=7)
    ax2.set_title(f"lock waits over time: {label(worst)} ({int(max(waits))} wait cycles in all)")
    return fig_uri(fig)


def load_timeseries(p):
    try:
        with open(os.path.join(p["_dir"], "report.json")) as f:
            ts = json.load(f).get("timeseries", {})
        s = ts.get("samples", ts) if isinstance(ts, dict) else ts
        return s if isinstance(s, list) else []
    except (OSError, ValueError):
        return []


def heatmap(trace_path, oitsim):
    if not trace_path or not os.path.exists(trace_path) or not oitsim:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        pfm = os.path.join(tmp, "depth.pfm")
        r = subprocess.run([oitsim, "info", trace_path, "--heatmap", pfm, "--json"], capture_output=True)
        if r.returncode != 0 or not os.path.exists(pfm):
            return None
        counts = read_pfm(pfm)[:, :, 0]
    fig, ax = plt.subplots(figsize=(7, 7 * counts.shape[0] / max(counts.shape[1], 1) + 0.8))
    im = ax.imshow(counts, cmap="inferno", interpolation="nearest")
    fig.colorbar(im, ax=ax, label="transparent fragments per pixel", fraction=0.046)
    ax.set_title(f"depth complexity (max {int(counts.max())}, mean over covered "
                 f"{counts[counts > 0].mean() if (counts > 0).any() else 0:.1f})")
    ax.set_axis_off()
    return fig_uri(fig)


def image_strip(points):
    """Reference, then one image per algorithm (its middle k), its x4 difference beneath."""
    if not points:
        return ""
    by_algo = {}
    for p in points:
        by_algo.setdefault(p["metrics"].get("config.algorithm", "?"), []).append(p)
    cells_top, cells_bottom = [], []
    ref = os.path.join(points[0]["_dir"], "reference.pfm")
    if os.path.exists(ref):
        cells_top.append(("reference (abuffer)", png_uri_from_array(srgb8(read_pfm(ref)))))
        cells_bottom.append(("", None))
    for algo in sorted(by_algo):
        ps = sorted(by_algo[algo], key=lambda p: (p["metrics"].get("config.layers", 0), p["id"]))
        p = ps[len(ps) // 2]
        m = p["metrics"]
        cap = f"{label(p)}: RMSE {m.get('image.metrics.rmse', 0):.4f}, SSIM {m.get('image.metrics.ssim', 0):.4f}"
        cells_top.append((cap, file_uri(os.path.join(p["_dir"], "image.png"))))
        cells_bottom.append((f"|{algo} - reference| x4", file_uri(os.path.join(p["_dir"], "diff.png"))))
    out = ['<div class="strip">']
    for row in (cells_top, cells_bottom):
        out.append('<div class="row">')
        for cap, uri in row:
            if uri:
                out.append(f'<figure><img class="frame" src="{uri}" alt="{html.escape(cap)}">'
                           f'<figcaption>{html.escape(cap)}</figcaption></figure>')
            else:
                out.append('<figure class="empty"></figure>')
        out.append("</div>")
    out.append("</div>")
    return "\n".join(out)


def speed_modes(points):
    """Speed modes of the simulator against the cycle-by-cycle reference
    (quantum 1, no idle skipping) of the same trace and hardware settings."""
    def mode_of(m):
        if m.get("config.mode") == "functional":
            return "functional"
        q, s = m.get(SPEED_KEYS[0]), m.get(SPEED_KEYS[1])
        return f"timing q={q} skip={'on' if s else 'off'}"

    def base_key(p):
        m = p["metrics"]
        return (p["trace"], m.get("config.algorithm"), m.get("config.layers"), m.get("config.format"))

    def hardware(p):
        # Every ROP parameter but the speed settings: points that differ in any
        # other (cache.ways, a preset ...) model different hardware and are
        # never compared with each other (audit: a cache.ways axis was measured
        # against the other ways' reference, 15.9 % "error").
        m = p["metrics"]
        return tuple(sorted((k, json.dumps(v)) for k, v in m.items()
                            if k.startswith("config.rop.") and k not in SPEED_KEYS))

    # Timing points group by trace, algorithm, k, format and every other ROP
    # parameter; a functional point (no ROP configuration) joins every group of
    # its trace and algorithm.
    groups = {}
    for p in points:
        if p["metrics"].get("config.mode") == "timing":
            groups.setdefault((base_key(p), hardware(p)), []).append(p)
    for p in points:
        if p["metrics"].get("config.mode") == "functional":
            for key, ps in groups.items():
                if key[0] == base_key(p):
                    ps.append(p)
    # Name the hardware settings that tell groups of one configuration apart.
    varying = {}
    for (base, hw) in groups:
        for k, v in hw:
            varying.setdefault((base, k), set()).add(v)
    rows = []
    for key, ps in sorted(groups.items(), key=lambda kv: str(kv[0])):
        refs = [p for p in ps if p["metrics"].get(SPEED_KEYS[0]) == 1 and p["metrics"].get(SPEED_KEYS[1]) is False]
        if not refs:
            continue
        ref = refs[0]["metrics"]
        base, hw = key
        config = f"{base[1]} k={base[2]} {base[3]}"
        extra = [f"{k[len('config.rop.'):]}={json.loads(v)}" for k, v in hw if len(varying[(base, k)]) > 1]
        if extra:
            config += " " + " ".join(extra)
        for p in ps:
            m = p["metrics"]
            row = {"trace": base[0], "config": config, "mode": mode_of(m), "id": p["id"],
                   "wall_s": num(m, "sim.wall_seconds"), "process_wall_s": p.get("wall_seconds")}
            row["speedup"] = (num(ref, "sim.wall_seconds") / row["wall_s"]) if row["wall_s"] else None
            if num(m, "timing.cycles") is not None:
                row["cycles"] = int(m["timing.cycles"])
                # Signed: (mode - reference) / reference (the goal takes |error|).
                row["cycle_err_pct"] = 100.0 * (m["timing.cycles"] - ref["timing.cycles"]) / ref["timing.cycles"]
                rb, b = dram_bytes(ref), dram_bytes(m)
                row["dram_bytes_err_pct"] = 100.0 * (b - rb) / rb if rb else 0.0
                rg, g = num(ref, "memory.mean_gbps"), num(m, "memory.mean_gbps")
                row["mean_gbps_err_pct"] = 100.0 * (g - rg) / rg if rg else 0.0
                rp, pk = num(ref, "memory.peak_gbps"), num(m, "memory.peak_gbps")
                row["peak_gbps_err_pct"] = 100.0 * (pk - rp) / rp if rp else 0.0
            rows.append(row)
    goal = "a timing mode within 1% of cycle-by-cycle cycles at >= 10x its speed"
    if not rows:
        # Still a JSON object (scripts read speed.json): no group had its reference point.
        return {"rows": [], "modes": {}, "goal": goal, "goal_met": False,
                "note": "no speed-mode group: each needs a cycle-by-cycle timing point (sim.quantum_cycles=1, "
                        "skip.idle_cycles=false) of the same trace, algorithm, k, format and other ROP parameters"}
    # The goal: a timing mode (not functional, not the reference) within 1 % of
    # the cycle-by-cycle cycles in every group, at >= 10x its speed in every group.
    verdicts = {}
    for r in rows:
        if r["mode"] == "functional" or r["mode"].startswith("timing q=1 skip=off"):
            continue
        v = verdicts.setdefault(r["mode"], {"max_cycle_err_pct": 0.0, "max_mean_gbps_err_pct": 0.0,
                                            "min_speedup": math.inf, "groups": 0})
        v["groups"] += 1
        v["max_cycle_err_pct"] = max(v["max_cycle_err_pct"], abs(r.get("cycle_err_pct", math.inf)))
        v["max_mean_gbps_err_pct"] = max(v["max_mean_gbps_err_pct"], abs(r.get("mean_gbps_err_pct", math.inf)))
        v["min_speedup"] = min(v["min_speedup"], r["speedup"] or 0.0)
    for v in verdicts.values():
        v["goal_met"] = v["max_cycle_err_pct"] <= 1.0 and v["min_speedup"] >= 10.0
    return {"rows": rows, "modes": verdicts, "goal": goal, "goal_met": any(v["goal_met"] for v in verdicts.values())}


def speed_plot(speed):
    fig, ax = plt.subplots(figsize=(8, 4.5))
    modes = sorted({r["mode"] for r in speed["rows"]})
    for i, mode in enumerate(modes):
        sel = [r for r in speed["rows"] if r["mode"] == mode and r["wall_s"]]
        ax.scatter([r["wall_s"] for r in sel], [max(abs(r.get("cycle_err_pct", 100.0)), 1e-4) for r in sel],
                   label=mode + (" (no cycles: plotted at 100 %)" if mode == "functional" else
                                 " (the reference: plotted at 1e-4 %)" if mode.startswith("timing q=1 ") else ""),
                   color=plt.cm.tab10(i), s=40)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(1.0, color="grey", linestyle="--", linewidth=1, label="1 % goal")
    ax.set_xlabel("simulator wall-clock seconds (sim.wall_seconds)")
    ax.set_ylabel("|cycles - cycle-by-cycle| / cycle-by-cycle (%)")
    ax.set_title("simulator speed modes: wall-clock against cycle error")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")
    return fig_uri(fig)


def fmt(v, digits=4):
    if v is None:
        return ""
    if isinstance(v, float):
        if math.isinf(v):
            return "inf"
        return f"{v:.{digits}g}"
    return html.escape(str(v))


def table(headers, rows):
    out = ["<table><tr>" + "".join(f"<th>{html.escape(h)}</th>" for h in headers) + "</tr>"]
    for r in rows:
        out.append("<tr>" + "".join(f"<td>{c}</td>" for c in r) + "</tr>")
    out.append("</table>")
    return "\n".join(out)


CSS = """
body{font-family:sans-serif;margin:16px;color:#222}
table{border-collapse:collapse;font-size:12px;margin:8px 0}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:right}
th{background:#eee}
td:first-child,td:nth-child(2){text-align:left}
img.plot{max-width:100%;display:block;margin:6px 0}
.strip .row{display:flex;gap:6px}
.strip figure{margin:0;width:220px}
.strip img.frame{width:220px;image-rendering:pixelated;border:1px solid #888}
figcaption{font-size:11px}
.ok{color:#070}.failed{color:#b00}.notrun{color:#777}
pre{white-space:pre-wrap;font-size:11px;background:#f6f6f6;padding:4px}
"""

# Runs in the page: counts images that decoded, so a headless browser's DOM dump
# shows whether every embedded image rendered.
CHECK = """
<div id="render-check" data-images="?" data-decoded="?"></div>
<script>
window.addEventListener('load', function () {
  var imgs = document.querySelectorAll('img'), ok = 0;
  for (var i = 0; i < imgs.length; i++) if (imgs[i].complete && imgs[i].naturalWidth > 0) ok++;
  var d = document.getElementById('render-check');
  d.setAttribute('data-images', imgs.length);
  d.setAttribute('data-decoded', ok);
  d.textContent = ok + ' of ' + imgs.length + ' images decoded';
});
</script>
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("dir")
    ap.add_argument("--out")
    ap.add_argument("--oitsim", help="oitsim executable (for the depth-complexity heatmap)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args()
    out = a.out or os.path.join(a.dir, "report.html")
    with open(os.path.join(a.dir, "results.json")) as f:
        res = json.load(f)
    plan = {}
    if os.path.exists(os.path.join(a.dir, "plan.json")):
        with open(os.path.join(a.dir, "plan.json")) as f:
            plan = json.load(f)
    trace_paths = {t["name"]: t["path"] for t in plan.get("traces", [])}
    points = res["points"]
    for p in points:
        p["_dir"] = os.path.join(a.dir, "points", p["id"])
    ok = [p for p in points if p["status"] == "ok"]
    not_run = [p for p in points if p["status"] == "not run"]  # e.g. Slurm tasks still to come
    failed = [p for p in points if p["status"] not in ("ok", "not run")]

    body = [f"<h1>oitsim sweep report</h1><p>spec <code>{html.escape(str(res.get('spec')))}</code>: "
            f"{len(points)} points, <span class='ok'>{len(ok)} ok</span>, "
            f"<span class='failed'>{len(failed)} failed</span>"
            + (f", <span class='notrun'>{len(not_run)} not run</span>" if not_run else "")
            + ". Errors are against the exact A-buffer; "
            f"frame time, DRAM and footprint come from timing-mode points (functional points show the "
            f"functional model's state traffic and state bytes instead).</p>"]
    if failed:
        body.append("<h2>Failed points</h2>")
        for p in failed:
            body.append(f"<p class='failed'>{html.escape(p['id'])}</p><pre>{html.escape(p['error'])}</pre>")
    if not_run:
        body.append("<h2>Points not run</h2><p class='notrun'>No status, output or report yet (rerun "
                    "<code>oitsim report</code> when they have run): "
                    + ", ".join(html.escape(p["id"]) for p in not_run) + "</p>")

    speed = speed_modes(ok)
    # Whole or not at all, as every other output (temporary file, then rename).
    speed_path = os.path.join(a.dir, "speed.json")
    speed_tmp = f"{speed_path}.tmp.{os.getpid()}"
    try:
        with open(speed_tmp, "w") as f:
            json.dump(speed, f, indent=1, default=lambda v: None)
        try:
            os.replace(speed_tmp, speed_path)
        except OSError as e:  # name the file the user knows, not the temporary
            raise OSError(e.errno, e.strerror, speed_path) from e
    finally:
        if os.path.exists(speed_tmp):
            os.remove(speed_tmp)
    if speed["rows"]:
        body.append("<h2>Simulator speed modes</h2>")
        body.append(f"<p>Goal: {speed['goal']}: <b>{'met' if speed['goal_met'] else 'not met'}</b>.</p>")
        body.append(table(["mode", "groups", "max cycle error %", "max mean GB/s error %", "min speed-up", "goal"],
                          [[html.escape(m), v["groups"], fmt(v["max_cycle_err_pct"]), fmt(v["max_mean_gbps_err_pct"]),
                            fmt(v["min_speedup"]), "met" if v["goal_met"] else "not met"]
                           for m, v in sorted(speed["modes"].items())]))
        body.append(f'<img class="plot" src="{speed_plot(speed)}" alt="speed modes">')
        body.append(table(["trace", "config", "mode", "wall s", "speed-up", "cycles", "cycle err %",
                           "DRAM bytes err %", "mean GB/s err %", "peak GB/s err %"],
                          [[html.escape(r["trace"]), html.escape(r["config"]), html.escape(r["mode"]),
                            fmt(r["wall_s"]), fmt(r["speedup"]), fmt(r.get("cycles")), fmt(r.get("cycle_err_pct")),
                            fmt(r.get("dram_bytes_err_pct")), fmt(r.get("mean_gbps_err_pct")),
                            fmt(r.get("peak_gbps_err_pct"))] for r in speed["rows"]]))

    for trace in sorted({p["trace"] for p in points}):
        tp = [p for p in ok if p["trace"] == trace]
        body.append(f"<h2>Trace {html.escape(trace)}</h2>")
        if not tp:
            body.append("<p>No point of this trace has succeeded.</p>")
            continue
        m0 = tp[0]["metrics"]
        body.append(f"<p>{m0.get('trace.width')} x {m0.get('trace.height')}, {m0.get('trace.fragments')} fragments "
                    f"(<code>{html.escape(str(m0.get('trace.path')))}</code>)</p>")
        body.append("<h3>Cost against image error</h3>")
        left_out = [p for p in tp if num(p["metrics"], "timing.cycles") is None]
        if left_out and len(left_out) < len(tp):
            body.append(f"<p>The plots show the timing model's figures; {len(left_out)} functional-mode point(s) "
                        "of this trace are not plotted (their error is in the table below): "
                        + ", ".join(html.escape(p["id"]) for p in left_out) + "</p>")
        body.append(f'<img class="plot pareto" src="{pareto_plots(tp, trace)}" alt="Pareto plots {html.escape(trace)}">')
        body.append("<h3>Images</h3>" + image_strip(tp))
        st = stall_plot(tp, trace)
        if st:
            body.append(f'<h3>Stalls and lock waits</h3><img class="plot" src="{st}" alt="stalls">')
        hm = heatmap(trace_paths.get(trace) or m0.get("trace.path"), a.oitsim)
        if hm:
            body.append(f'<h3>Depth complexity</h3><img class="plot" src="{hm}" alt="depth complexity">')

    body.append("<h2>All points</h2>")
    axes = res.get("axes", [])
    rows = []
    for p in points:
        m = p["metrics"]
        rows.append([html.escape(p["id"]), html.escape(p["trace"]),
                     f"<span class='{p['status'].replace(' ', '')}'>{p['status']}</span>"]
                    + [html.escape(str(p["axes"].get(ax, ""))) for ax in axes]
                    + [fmt(num(m, "image.metrics.rmse")), fmt(num(m, "image.metrics.ssim")),
                       fmt(num(m, "image.metrics.psnr")), fmt(num(m, "timing.frame_time_us")),
                       fmt(dram_bytes(m)), fmt(footprint(m)), fmt(num(m, "sim.wall_seconds")),
                       fmt(p.get("wall_seconds"))])
    body.append(table(["id", "trace", "status"] + axes + ["RMSE", "SSIM", "PSNR", "frame us", "DRAM bytes",
                                                         "footprint B", "sim wall s", "process wall s"], rows))
    body.append("<p>Every metric of every point: results.csv / results.json beside this page.</p>")
    page = ("<!DOCTYPE html><html><head><meta charset='utf-8'><title>oitsim sweep report</title>"
            f"<style>{CSS}</style></head><body>\n" + CHECK + "\n".join(body) + "\n</body></html>\n")
    tmp = out + ".tmp"
    try:
        with open(tmp, "w") as f:
            f.write(page)
        os.replace(tmp, out)
    except OSError:
        if os.path.exists(tmp):
            os.remove(tmp)
        raise
    if not a.quiet:
        print(f"report {out} ({len(page) // 1024} KiB, {len(points)} points: {len(ok)} ok, {len(failed)} failed, "
              f"{len(not_run)} not run)")
        if speed:
            for mode, v in sorted(speed["modes"].items()):
                print(f"speed  {mode}: max cycle error {v['max_cycle_err_pct']:.3f} %, "
                      f"min speed-up {v['min_speedup']:.1f}x: goal {'met' if v['goal_met'] else 'not met'}")


def run():
    """main() with I/O errors as one line on stderr (exit 1), not a traceback."""
    try:
        return main()
    except OSError as e:
        what = f"{e.filename}: {e.strerror}" if e.filename else str(e)
        print(f"make_report.py: error: cannot read or write {what}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(run())
