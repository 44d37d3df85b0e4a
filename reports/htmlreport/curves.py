"""Curves where the axis is ordered: error (FLIP, RMSE) and frame time against
k, one line per algorithm and hardware configuration; and any other numeric
sweep axis (cache.ways, lock.capacity, ...) against frame time and error."""
import math

import matplotlib.pyplot as plt
from matplotlib.lines import Line2D

from . import data
from .plots import LINESTYLES, apply_scale, empty_panel, figure_html

METRICS = [
    ("FLIP mean vs A-buffer (0-1)", data.flip_mean, False),
    ("RMSE vs A-buffer (linear RGB, 0-1)", data.rmse, False),
    ("frame time (us)", data.frame_us, True),
]


def _is_number(s):
    try:
        return math.isfinite(float(s))
    except (TypeError, ValueError):
        return False


def _k_axis(ax, ks):
    ax.set_xscale("log", base=2)
    ax.set_xticks(ks)
    ax.set_xticklabels([str(k) for k in ks])
    ax.minorticks_off()


def k_figure(points, scene, configs, styles):
    """Columns: FLIP, RMSE, frame time against k. An image does not depend on the
    hardware, so the error panels draw one line per algorithm; frame time one
    per algorithm and configuration (line style). Algorithms without k: a
    horizontal dashed line at their value."""
    with_k = [p for p in points if data.k_of(p) is not None]
    ks = sorted({data.k_of(p) for p in with_k})
    if len(ks) < 2:
        return None
    confs = [c for c in configs.all_labels(points) if c != configs.FUNCTIONAL]
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for ax, (name, f, per_config) in zip(axes, METRICS):
        lines = confs if per_config else [None]
        plotted = []
        for li, conf in enumerate(lines):
            for algo in sorted({data.algorithm(p) for p in points}):
                mine = [p for p in points if data.algorithm(p) == algo and (conf is None or configs.label(p) == conf)]
                pairs = sorted({(data.k_of(p), f(p["metrics"])) for p in mine
                                if data.k_of(p) is not None and f(p["metrics"]) is not None})
                style = LINESTYLES[li % len(LINESTYLES)]
                if pairs:
                    ax.plot([k for k, _ in pairs], [v for _, v in pairs], marker=styles.marker(algo),
                            color=styles.colour(algo), linestyle=style, markersize=6)
                    plotted += [v for _, v in pairs]
                else:
                    vals = [f(p["metrics"]) for p in mine if data.k_of(p) is None and f(p["metrics"]) is not None]
                    if vals:
                        ax.axhline(vals[0], color=styles.colour(algo), linestyle=(0, (2, 3)), linewidth=1.5)
                        plotted.append(vals[0])
        if not plotted:
            empty_panel(ax, f"no {name.split(' (')[0]} in these points")
            continue
        _k_axis(ax, ks)
        apply_scale(ax, "y", plotted, allow_zero=True)
        ax.set_xlabel("k (rows, nodes or layers per pixel)")
        ax.set_ylabel(name)
        ax.set_title(name.split(" (")[0] + (" (line style: hardware)" if per_config and len(lines) > 1 else ""))
        ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], marker=styles.marker(a), color=styles.colour(a), label=a)
               for a in sorted({data.algorithm(p) for p in points})]
    handles += [Line2D([], [], color="black", linestyle=LINESTYLES[i % len(LINESTYLES)], label=c)
                for i, c in enumerate(confs)] if len(confs) > 1 else []
    handles.append(Line2D([], [], color="grey", linestyle=(0, (2, 3)), label="algorithm without k (its value)"))
    fig.legend(handles=handles, loc="upper center", ncol=min(8, len(handles)), frameon=False, bbox_to_anchor=(0.5, 1.02))
    fig.suptitle(f"{scene}: error and frame time against k", y=1.08)
    fig.tight_layout()
    return figure_html(fig, f"{scene}: against k")


def numeric_axes(res_axes, points):
    """Sweep axes (other than k) whose values are all numbers, at least two."""
    out = []
    for ax in res_axes:
        if ax in ("layers", "algo"):
            continue
        vals = {p["axes"].get(ax) for p in points if ax in p["axes"]}
        if len(vals) >= 2 and all(_is_number(v) for v in vals):
            out.append(ax)
    return out


def axis_figure(points, scene, axis, configs, styles):
    """Frame time, FLIP and RMSE against one numeric axis; one line per
    algorithm, k and every other setting (the points that differ only in this axis)."""
    def series_key(p):
        others = tuple(sorted((a, v) for a, v in p["axes"].items() if a != axis))
        return (data.algorithm(p),) + others

    series = {}
    for p in points:
        if axis in p["axes"]:
            series.setdefault(series_key(p), []).append(p)
    xs_all = sorted({float(p["axes"][axis]) for p in points if axis in p["axes"]})
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    for ax, (name, f, _) in zip(axes, [METRICS[2], METRICS[0], METRICS[1]]):
        plotted = []
        for i, (key, ps) in enumerate(sorted(series.items())):
            pairs = sorted((float(p["axes"][axis]), f(p["metrics"])) for p in ps if f(p["metrics"]) is not None)
            if len(pairs) < 2:
                continue
            label = " ".join([key[0]] + [f"{a}={v}" for a, v in key[1:] if a != "algo"])
            ax.plot([x for x, _ in pairs], [y for _, y in pairs], marker=styles.marker(key[0]),
                    color=styles.colour(key[0]), linestyle=LINESTYLES[i % len(LINESTYLES)], label=label)
            plotted += [y for _, y in pairs]
        if not plotted:
            empty_panel(ax, f"no {name.split(' (')[0]} varies with {axis}")
            continue
        apply_scale(ax, "x", xs_all, allow_zero=True)
        apply_scale(ax, "y", plotted, allow_zero=True)
        ax.set_xlabel(f"{axis} (sweep axis)")
        ax.set_ylabel(name)
        ax.grid(alpha=0.3, which="both")
        if len(series) <= 10:
            ax.legend(fontsize=8)
    fig.suptitle(f"{scene}: against {axis}")
    fig.tight_layout()
    return figure_html(fig, f"{scene}: against {axis}")


def section(points, scene, res_axes, configs, styles, log):
    parts = []
    log(f"{scene}: curves against k")
    kf = k_figure(points, scene, configs, styles)
    if kf:
        parts.append(kf)
    for axis in numeric_axes(res_axes, points):
        log(f"{scene}: curves against {axis}")
        parts.append(axis_figure(points, scene, axis, configs, styles))
    return "\n".join(parts)
