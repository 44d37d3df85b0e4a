"""The price of order: where a scene's timing points differ in lock.mode
(ordered, unordered, none: oit_rop/DESIGN.md, "Ordering"), frame time and lock
waits against image error and flicker in one figure, each algorithm's modes
joined by a line, and the same figures in a table."""
import matplotlib.pyplot as plt
from matplotlib.lines import Line2D

from . import data
from .page import cell, esc, fmt_num, table
from .plots import apply_scale, empty_panel, figure_html

MODES = ["ordered", "unordered", "none"]
MODE_MARKERS = {"ordered": "o", "unordered": "s", "none": "X"}


def mode_of(p):
    return p["metrics"].get("lock.mode") or p["metrics"].get("config.rop.lock.mode")


def applies(points):
    """True when the scene's timing points hold more than one lock mode."""
    return len({mode_of(p) for p in points if data.is_timing(p)} - {None}) > 1


def _machine(p, configs):
    """The hardware configuration without its lock mode (the modes of one
    machine are compared with each other)."""
    words = [w for w in configs.label(p).split(" ") if not w.startswith("lock.mode=")]
    return " ".join(words)


def _error(m):
    """FLIP mean where the report has it, else RMSE; and the axis name."""
    f = data.flip_mean(m)
    return (f, "FLIP mean vs A-buffer (0-1)") if f is not None else (data.rmse(m), "RMSE vs A-buffer (linear RGB, 0-1)")


def _flicker(m):
    return data.num(m, "image.flicker.std_mean")


def _groups(points, configs):
    """{(algorithm label, machine): {mode: point}} of the timing points."""
    out = {}
    for p in points:
        if data.is_timing(p) and mode_of(p) in MODES:
            out.setdefault((data.algo_label(p), _machine(p, configs)), {})[mode_of(p)] = p
    return out


def figure(points, scene, configs, styles):
    groups = _groups(points, configs)
    fig, axes = plt.subplots(1, 2, figsize=(15, 5.2))
    panels = [
        (axes[0], lambda m: _error(m)[0], lambda m: data.frame_us(m), "frame time (us)"),
        (axes[1], _flicker, lambda m: data.num(m, "lock.wait_cycles"), "lock wait (fragment-cycles)"),
    ]
    xnames = ["", "flicker: per-pixel std across seeds (sRGB8 levels, mean)"]
    for p in points:
        if data.is_timing(p) and _error(p["metrics"])[0] is not None:
            xnames[0] = _error(p["metrics"])[1]
            break
    machines = sorted({mach for _, mach in groups})
    for i, (ax, xf, yf, yname) in enumerate(panels):
        xs, ys = [], []
        for (algo_label, mach), by_mode in sorted(groups.items()):
            pts = [(xf(by_mode[mo]["metrics"]), yf(by_mode[mo]["metrics"]), mo) for mo in MODES if mo in by_mode]
            pts = [(x, y, mo) for x, y, mo in pts if x is not None and y is not None]
            if not pts:
                continue
            algo = data.algorithm(next(iter(by_mode.values())))
            style = ["-", "--", ":", "-."][machines.index(mach) % 4]
            ax.plot([x for x, _, _ in pts], [y for _, y, _ in pts], color=styles.colour(algo), linestyle=style,
                    linewidth=1, zorder=2)
            for x, y, mo in pts:
                ax.scatter([x], [y], color=styles.colour(algo), marker=MODE_MARKERS[mo], s=54, zorder=3,
                           edgecolors="black", linewidths=0.4)
            ax.annotate(algo_label, (pts[0][0], pts[0][1]), fontsize=9, xytext=(4, 3),
                        textcoords="offset points", color=styles.colour(algo))
            xs += [x for x, _, _ in pts]
            ys += [y for _, y, _ in pts]
        if not xs:
            empty_panel(ax, "no flicker: run the points with\n`seeds` (oitsim run --seeds N)" if i == 1
                        else "no error figures in these points")
            continue
        apply_scale(ax, "x", xs, allow_zero=True)
        apply_scale(ax, "y", ys, allow_zero=True)
        ax.set_xlabel(xnames[i])
        ax.set_ylabel(yname)
        ax.set_title(["frame time against error", "lock waits against flicker"][i])
        ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], linestyle="", marker=MODE_MARKERS[mo], color="grey", markeredgecolor="black",
                      markersize=8, label=f"lock.mode={mo}") for mo in MODES]
    handles += [Line2D([], [], color="grey", linestyle=["-", "--", ":", "-."][i % 4], label=mach)
                for i, mach in enumerate(machines)]
    fig.legend(handles=handles, loc="upper center", ncol=min(6, len(handles)), frameon=False, bbox_to_anchor=(0.5, 1.0))
    fig.suptitle(f"{scene}: the price of order (colour: algorithm; a line joins one algorithm's modes on one machine)",
                 y=1.05)
    fig.tight_layout()
    return figure_html(fig, f"{scene}: frame time and lock waits against error and flicker per lock mode")


def section(points, scene, configs, styles, log):
    log(f"{scene}: the price of order")
    groups = _groups(points, configs)
    rows = []
    for (algo_label, mach), by_mode in sorted(groups.items()):
        for mo in MODES:
            if mo not in by_mode:
                continue
            m = by_mode[mo]["metrics"]
            diff = data.num(m, "image.flicker.differing_fraction")
            rows.append([cell(algo_label, esc(algo_label), "t"), cell(mach, esc(mach), "t"), cell(mo, esc(mo), "t"),
                         cell(data.frame_us(m), fmt_num(data.frame_us(m))),
                         cell(data.num(m, "lock.wait_cycles"), fmt_num(data.num(m, "lock.wait_cycles"))),
                         cell(data.num(m, "lock.lost_updates"), fmt_num(data.num(m, "lock.lost_updates"))),
                         cell(data.flip_mean(m), fmt_num(data.flip_mean(m))),
                         cell(data.rmse(m), fmt_num(data.rmse(m))),
                         cell(_flicker(m), fmt_num(_flicker(m))),
                         cell(diff, fmt_num(None if diff is None else 100 * diff))])
    note = ("<p class='note'>With <code>lock.mode=ordered</code> each pixel's inserts happen in submission order "
            "(the functional model's image, the same for every seed); <code>unordered</code> inserts in the order "
            "the fragments enter the lock, <code>none</code> races the read-modify-writes and loses updates, so "
            "their images depend on timing. Flicker needs points run with <code>seeds</code> (the spec setting of "
            "<code>oitsim run --seeds N</code>).</p>")
    return (note + figure(points, scene, configs, styles) +
            table(["algorithm", "machine", "lock.mode", "frame (us)", "lock wait (cycles)", "lost updates",
                   "FLIP mean", "RMSE", "flicker std (sRGB8)", "flickering pixels (%)"], rows))
