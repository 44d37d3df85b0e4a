"""Where a frame's time goes, per timing point: the phases, what bounds it (the
timing model's bound_by and root causes when the report has them, else the
per-stage stalls as shares of the frame), DRAM bandwidth and utilisation, cache
and L2 hit rates, traffic over compulsory; and the lock's waiters over time."""
import json
import os

import matplotlib.pyplot as plt
import numpy as np

from . import data
from .page import cell, esc, fmt_num, fmt_pct, table
from .plots import empty_panel, figure_html

PHASE_COLOURS = {"opaque": "#8c8c8c", "transparent": "#fd8d3c", "transparent pass 1": "#fd8d3c",
                 "transparent pass 2": "#a63603", "transparent pass 3": "#fdbe85", "resolve": "#2b8cbe"}


def _phase_rank(name):
    """opaque, the transparent pass(es) in order, then the resolve."""
    if name == "opaque":
        return (0, 0)
    if name == "resolve":
        return (2, 0)
    return (1, int(name.rsplit(" ", 1)[1]) if name[-1].isdigit() else 0)
# timing.root_cause_cycles keys, from the input to the memory (oit_rop/RootCause.hpp).
ROOT_CAUSES = ["input", "input_starvation", "scoreboard_full", "lock_wait", "alu", "rop_cache_miss", "l2",
               "dram_latency", "dram_bandwidth", "dram_bank_conflict", "dram_turnaround", "dram_refresh",
               "pipeline_latency", "atomic_wait", "list_walk", "sort"]
CAUSE_SHORT = {"lock_wait": "lock", "scoreboard_full": "scoreboard", "cache_miss_wait": "miss",
               "dram_bandwidth": "DRAM", "alu_busy": "ALU", "input_starved": "starved",
               "atomic_wait": "atomics", "list_walk": "list walk", "sort": "sort"}


def _order(points, configs):
    return sorted(points, key=lambda p: (configs.label(p), data.algorithm(p), data.k_of(p) or 0, p["id"]))


def bottleneck_table(points, configs):
    """One table per hardware configuration (a row per point)."""
    ms = [p["metrics"] for p in points]
    has_l2 = any(data.level_hit_rate(m, "l2") is not None for m in ms)
    has_toc = any(data.num(m, "memory.traffic_over_compulsory") is not None for m in ms)
    has_bound = any(isinstance(m.get("timing.bound_by.resource"), str) for m in ms)
    headers = ["algorithm", "frame (us)", "opaque (us)", "transparent (us; passes)", "resolve (us)",
               "bound by (share of frame)" if has_bound else "largest stall (share of frame)",
               "DRAM mean / peak (GB/s)", "DRAM utilisation", "cache hit rate"]
    if has_l2:
        headers.append("L2 hit rate")
    if has_toc:
        headers.append("traffic / compulsory")
    out = [("<p class='note'>Frame phases from the partition that finished last (opaque pre-pass, the transparent "
            "pass(es), the resolve; a two-pass algorithm's passes each in brackets). " + ("Bound by: the timing model's <code>timing.bound_by</code>. " if has_bound else
            "Largest stall: the per-stage stall cycles (summed over partitions, as a share of cycles x partitions) "
            "of the stage and cause that stall most, waiting for upstream (<code>input_starved</code>) left out; "
            "the timing model's own <code>bound_by</code> replaces it when reports carry it. ") +
            "DRAM utilisation: mean GB/s over the channels' peak; cache: each partition's ROP cache of blending-array lines (<code>cache.line_bytes</code>). Click a header "
            "to sort.</p>")]
    for conf in [c for c in configs.all_labels(points) if c != configs.FUNCTIONAL]:
        rows = []
        for p in _order([p for p in points if configs.label(p) == conf], configs):
            m = p["metrics"]
            ph = data.phases_us(m) or []
            passes = [v for n, v in ph if n.startswith("transparent")]
            transparent = sum(passes) if ph else None
            # A two-pass algorithm's passes each (adaptive: build, composite), summed in the sort value.
            transparent_text = (f"{fmt_num(transparent)} ({' + '.join(fmt_num(v) for v in passes)})"
                                if len(passes) > 1 else None)
            phase = dict(ph)
            b = data.bound_by(m)
            bound = (f"{esc(b[0])} {fmt_pct(b[1])}" + ("" if b[2] == "bound_by" else
                                                     " <span class='note'>(stall)</span>") if b else "")
            util = data.dram_utilisation(m)
            mean, peak = data.num(m, "memory.mean_gbps"), data.num(m, "memory.peak_gbps")
            r = [cell(data.algo_label(p), esc(data.algo_label(p)), "t"),
                 cell(data.frame_us(m)), cell(phase.get("opaque")), cell(transparent, transparent_text),
                 cell(phase.get("resolve")),
                 cell(b[1] if b else None, bound, "t"),
                 cell(mean, f"{fmt_num(mean)} / {fmt_num(peak)}" if mean is not None else ""),
                 shaded(util), cell(data.num(m, "cache.hit_rate"), fmt_pct(data.num(m, "cache.hit_rate")))]
            if has_l2:
                l2 = data.level_hit_rate(m, "l2")
                r.append(cell(l2, fmt_pct(l2)))
            if has_toc:
                toc = data.num(m, "memory.traffic_over_compulsory")
                r.append(cell(toc, fmt_num(toc, 3, "x") if toc is not None else ""))
            rows.append(r)
        out.append(table(headers, rows, caption=f"<b>{esc(conf)}</b>"))
    return "\n".join(out)


def shaded(share):
    """A percentage cell with a bar behind it."""
    if share is None:
        return cell(None, "")
    return (f'<td data-v="{float(share)!r}" class="shade" style="--s:{100 * min(1.0, share):.0f}%">'
            f"{fmt_pct(share)}</td>")


def phase_figure(points, scene, configs):
    confs = [c for c in configs.all_labels(points) if c != configs.FUNCTIONAL]
    fig, axes = plt.subplots(1, len(confs), figsize=(15, 0.42 * max(len([p for p in points if configs.label(p) == c])
                                                                    for c in confs) + 1.6), squeeze=False)
    for ax, conf in zip(axes[0], confs):
        pts = _order([p for p in points if configs.label(p) == conf], configs)
        names = [data.algo_label(p) for p in pts]
        left = np.zeros(len(pts))
        phase_names = []
        for p in pts:
            for n, _ in data.phases_us(p["metrics"]) or []:
                if n not in phase_names:
                    phase_names.append(n)
        if not phase_names:
            empty_panel(ax, "no phase ends in these reports")
            continue
        for n in sorted(phase_names, key=_phase_rank):
            vals = np.array([dict(data.phases_us(p["metrics"]) or []).get(n, 0.0) for p in pts])
            colour = PHASE_COLOURS.get(n, "#fdd0a2")
            ax.barh(names, vals, left=left, color=colour, label=n, edgecolor="white", linewidth=0.5)
            left += vals
        ax.invert_yaxis()
        ax.set_xlabel("modelled time (us)")
        ax.set_ylabel("algorithm")
        ax.set_title(f"{conf}: frame time by phase")
        ax.grid(alpha=0.3, axis="x")
        ax.legend(loc="lower right", fontsize=8)
    fig.suptitle(f"{scene}: frame time by phase")
    fig.tight_layout()
    return figure_html(fig, f"{scene}: frame time by phase")


def cause_figure(points, scene, configs):
    """Root causes (share of partition-cycles) when the reports have them, else
    each stage's stalled share of the frame, labelled with its main cause."""
    confs = [c for c in configs.all_labels(points) if c != configs.FUNCTIONAL]
    root = any(data.prefixed(p["metrics"], "timing.root_cause_cycles.") for p in points)
    tallest = max(len([p for p in points if configs.label(p) == c]) for c in confs)
    fig, axes = plt.subplots(1, len(confs), figsize=(15, 0.42 * tallest + 2.0), squeeze=False)
    for ax, conf in zip(axes[0], confs):
        pts = _order([p for p in points if configs.label(p) == conf], configs)
        names = [data.algo_label(p) for p in pts]
        if root:
            # The causes some point of this machine has, in the pipeline's order
            # (ROOT_CAUSES), any cause the list does not know after them.
            seen = {c for p in pts for c, v in data.prefixed(p["metrics"], "timing.root_cause_cycles.").items() if v}
            causes = [c for c in ROOT_CAUSES if c in seen] + sorted(seen - set(ROOT_CAUSES)) or ROOT_CAUSES[:1]
            total = [data.num(p["metrics"], "timing.partition_cycles") or 1.0 for p in pts]
            grid = np.array([[data.prefixed(p["metrics"], "timing.root_cause_cycles.").get(c, 0.0) / t
                              for c in causes] for p, t in zip(pts, total)])
            cols, notes = causes, None
        else:
            cols = data.STAGES
            grid = np.zeros((len(pts), len(cols)))
            notes = [["" for _ in cols] for _ in pts]
            for i, p in enumerate(pts):
                sh = data.stall_shares(p["metrics"])
                for j, s in enumerate(cols):
                    by_cause = {c: v for (st, c), v in sh.items() if st == s}
                    grid[i][j] = sum(by_cause.values())
                    if by_cause:
                        main = max(by_cause, key=by_cause.get)
                        notes[i][j] = CAUSE_SHORT[main]
        im = ax.imshow(np.clip(grid, 0, 1), cmap="Reds", vmin=0, vmax=1, aspect="auto")
        for i in range(len(pts)):
            for j in range(len(cols)):
                v = grid[i][j]
                if v >= 0.005:
                    text = f"{100 * v:.0f}%" + (f"\n{notes[i][j]}" if notes and notes[i][j] else "")
                    ax.text(j, i, text, ha="center", va="center", fontsize=8,
                            color="white" if v > 0.6 else "black")
        ax.set_xticks(range(len(cols)))
        ax.set_xticklabels([c.replace("_", " ") for c in cols], rotation=30, ha="right")
        ax.set_yticks(range(len(pts)))
        ax.set_yticklabels(names)
        ax.set_xlabel("root cause" if root else "pipeline stage (main stall cause under the share)")
        ax.set_ylabel("algorithm")
        ax.set_title(f"{conf}: " + ("share of partition-cycles by root cause" if root else
                                    "share of the frame each stage stalls"))
        fig.colorbar(im, ax=ax, fraction=0.04, label="share of the frame")
    fig.suptitle(f"{scene}: " + ("root causes (timing.root_cause_cycles)" if root else
                                 "per-stage stalls as a share of frame time (stall cycles / (cycles x partitions))"))
    fig.tight_layout()
    return figure_html(fig, f"{scene}: stalls")


def utilisation_figure(points, scene, configs):
    """timing.utilization (per resource, 0..1) when the reports have it."""
    pts = _order([p for p in points if data.prefixed(p["metrics"], "timing.utilization.")], configs)
    if not pts:
        return None
    res = sorted({r for p in pts for r in data.prefixed(p["metrics"], "timing.utilization.")})
    grid = np.array([[data.prefixed(p["metrics"], "timing.utilization.").get(r, 0.0) for r in res] for p in pts])
    fig, ax = plt.subplots(figsize=(15, 0.42 * len(pts) + 2.0))
    im = ax.imshow(np.clip(grid, 0, 1), cmap="Blues", vmin=0, vmax=1, aspect="auto")
    for i in range(len(pts)):
        for j in range(len(res)):
            ax.text(j, i, f"{100 * grid[i][j]:.0f}%", ha="center", va="center", fontsize=8,
                    color="white" if grid[i][j] > 0.6 else "black")
    ax.set_xticks(range(len(res)))
    ax.set_xticklabels([r.replace("_", " ") for r in res])
    ax.set_yticks(range(len(pts)))
    ax.set_yticklabels([f"{configs.label(p)}: {data.algo_label(p)}" for p in pts])
    ax.set_xlabel("resource")
    ax.set_ylabel("hardware: algorithm")
    fig.colorbar(im, ax=ax, fraction=0.03, label="utilisation (timing.utilization)")
    ax.set_title(f"{scene}: utilisation by resource")
    fig.tight_layout()
    return figure_html(fig, f"{scene}: utilisation")


def load_timeseries(p):
    try:
        with open(os.path.join(p["_dir"], "report.json")) as f:
            ts = json.load(f).get("timeseries", {})
        s = ts.get("samples", ts) if isinstance(ts, dict) else ts
        return s if isinstance(s, list) else []
    except (OSError, ValueError):
        return []


def lock_figure(points, scene, configs):
    """Lock waiters and scoreboard occupancy over time for the point of each
    configuration with the most lock-wait cycles."""
    confs = [c for c in configs.all_labels(points) if c != configs.FUNCTIONAL]
    worst_of = {}
    for conf in confs:
        pts = [p for p in points if configs.label(p) == conf]
        worst = max(pts, key=lambda p: data.num(p["metrics"], "lock.wait_cycles") or 0)
        worst_of[conf] = (worst, load_timeseries(worst))
    if all(len(series) < 3 for _, series in worst_of.values()):
        # No machine has a series to draw: a note, not a figure of empty panels.
        return (f"<p class='note'>{esc(scene)}: the lock over time is not drawn: every machine's frame is "
                f"shorter than three time-series intervals (stats.interval_cycles).</p>")
    fig, axes = plt.subplots(1, len(confs), figsize=(15, 4.0), squeeze=False)
    for ax, conf in zip(axes[0], confs):
        worst, series = worst_of[conf]
        mhz = data.num(worst["metrics"], "timing.clock_mhz") or 1.0
        if len(series) < 3:
            empty_panel(ax, f"{conf}: {data.algo_label(worst)}: the frame is shorter than three time-series\n"
                            f"intervals ({len(series)} sample(s) of stats.interval_cycles): nothing to draw")
            continue
        t = [s.get("cycle", 0) / mhz for s in series]
        ax.plot(t, [s.get("lock_waiters", 0) for s in series], label="lock waiters")
        ax.plot(t, [s.get("scoreboard_occupancy", 0) for s in series], label="scoreboard occupancy", alpha=0.7)
        ax.set_xlabel("modelled time (us)")
        ax.set_ylabel("fragments (all partitions)")
        waits = data.num(worst["metrics"], "lock.wait_cycles") or 0
        ax.set_title(f"{conf}: {data.algo_label(worst)} ({fmt_num(waits)} lock-wait cycles)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{scene}: the lock over time, for the point with the most lock-wait cycles on each machine")
    fig.tight_layout()
    return figure_html(fig, f"{scene}: lock over time")


def section(points, scene, configs, log):
    timing = [p for p in points if data.is_timing(p)]
    if not timing:
        return ""
    log(f"{scene}: bottleneck table and charts")
    parts = [bottleneck_table(timing, configs), phase_figure(timing, scene, configs),
             cause_figure(timing, scene, configs)]
    util = utilisation_figure(timing, scene, configs)
    if util:
        parts.append(util)
    parts.append(lock_figure(timing, scene, configs))
    return "\n".join(parts)
