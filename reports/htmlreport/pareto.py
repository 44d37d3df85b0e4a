"""Cost against image error, one row of panels per hardware configuration (one
Pareto front each), the same figure against FLIP and against RMSE."""
import matplotlib.pyplot as plt
from matplotlib.lines import Line2D

from . import data
from .plots import apply_scale, empty_panel, figure_html, pareto_front

TIMING_COSTS = [
    ("frame time (us)", lambda m: data.frame_us(m)),
    ("DRAM read + written (MiB)", lambda m: _mib(data.dram_bytes(m))),
    ("footprint allocated (MiB)", lambda m: _mib(data.footprint(m))),
]
FUNCTIONAL_COSTS = [
    ("per-pixel state traffic (MiB, functional model)", lambda m: _mib(data.state_traffic(m))),
    ("per-pixel state (MiB, functional model)", lambda m: _mib(data.num(m, "memory.state_bytes"))),
]
ERRORS = {
    "flip": ("FLIP mean vs A-buffer (0-1)", data.flip_mean),
    "rmse": ("RMSE vs A-buffer (linear RGB, 0-1)", data.rmse),
}


def _mib(v):
    return None if v is None else v / data.MIB


def figure(points, scene, configs, styles, error):
    """One figure: rows = hardware configurations, columns = costs."""
    xname, xf = ERRORS[error]
    rows = configs.all_labels(points)
    ncols = 3
    fig, axes = plt.subplots(len(rows), ncols, figsize=(15, 3.9 * len(rows) + 0.6), squeeze=False)
    for r, conf in enumerate(rows):
        pts = [p for p in points if configs.label(p) == conf]
        costs = FUNCTIONAL_COSTS if conf == configs.FUNCTIONAL else TIMING_COSTS
        for c in range(ncols):
            ax = axes[r][c]
            if c >= len(costs):
                empty_panel(ax, "no frame time:\nfunctional points have\nno timing model")
                continue
            yname, yf = costs[c]
            sel = [(xf(p["metrics"]), yf(p["metrics"]), p) for p in pts]
            sel = [(x, y, p) for x, y, p in sel if x is not None and y is not None]
            if not sel:
                empty_panel(ax, f"no {yname.split(' (')[0]} or {error.upper()} in these points")
                continue
            for algo in sorted({data.algorithm(p) for _, _, p in sel}):
                mine = [(x, y, p) for x, y, p in sel if data.algorithm(p) == algo]
                ax.scatter([s[0] for s in mine], [s[1] for s in mine], color=styles.colour(algo),
                           marker=styles.marker(algo), s=42, zorder=3, edgecolors="black", linewidths=0.4)
                at = {}
                for x, y, p in mine:
                    if data.k_of(p) is not None:
                        at.setdefault((x, y), []).append(f"k{data.k_of(p)}")
                for (x, y), ks in at.items():
                    ax.annotate("/".join(dict.fromkeys(ks)), (x, y), fontsize=9, xytext=(4, 3),
                                textcoords="offset points", color=styles.colour(algo))
            front = pareto_front([s[0] for s in sel], [s[1] for s in sel])
            ax.step([sel[i][0] for i in front], [sel[i][1] for i in front], where="post", color="grey",
                    linestyle="--", linewidth=1, zorder=2)
            apply_scale(ax, "x", [s[0] for s in sel], allow_zero=True)
            apply_scale(ax, "y", [s[1] for s in sel], allow_zero=True)
            ax.set_xlabel(xname)
            ax.set_ylabel(yname)
            ax.set_title(f"{conf}: {yname.split(' (')[0]}")
            ax.grid(alpha=0.3, which="both")
    handles = [Line2D([], [], linestyle="", marker=styles.marker(a), color=styles.colour(a), markeredgecolor="black",
                      markersize=8, label=a) for a in sorted({data.algorithm(p) for p in points})]
    handles.append(Line2D([], [], color="grey", linestyle="--", label="Pareto front (this configuration)"))
    fig.legend(handles=handles, loc="upper center", ncol=min(8, len(handles)), frameon=False,
               bbox_to_anchor=(0.5, 1.0))
    fig.suptitle(f"{scene}: cost against image error ({error.upper()}); lower left is better", y=1.04)
    fig.tight_layout()
    return figure_html(fig, f"{scene}: cost against {error.upper()}")


def section(points, scene, configs, styles, log):
    """Both variants, FLIP shown first; a toggle switches."""
    group = f"pareto-{scene}"
    parts = [f'<div class="toggle" data-for="{group}">error axis: '
             '<button class="on" data-show="flip">FLIP</button><button data-show="rmse">RMSE</button></div>']
    for error in ("flip", "rmse"):
        log(f"{scene}: cost against {error.upper()}")
        img = figure(points, scene, configs, styles, error)
        hidden = "" if error == "flip" else " hidden"
        parts.append(f'<div data-group="{group}" data-variant="{error}"{hidden}>{img}</div>')
    return "\n".join(parts)
