"""Matplotlib helpers: figures as data URIs that carry their axis labels (the
browser test checks every plot has them), log axes where a range spans more
than a decade, one colour and marker per algorithm."""
import base64
import html
import io
import json
import math

import matplotlib

matplotlib.use("Agg")  # no display: render to PNG in memory
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker  # noqa: E402

# Large enough to read at 1400 px: a 15-inch figure at 90 dpi is 1350 px wide.
DPI = 90
plt.rcParams.update({"font.size": 10, "axes.titlesize": 11, "axes.labelsize": 10, "legend.fontsize": 9,
                     "xtick.labelsize": 9, "ytick.labelsize": 9})

MARKERS = ["o", "s", "^", "D", "v", "P", "X", "*", "<", ">", "h", "p"]
LINESTYLES = ["-", "--", ":", "-."]


class Styles:
    """One colour and marker per algorithm, the same in every plot of the page."""

    def __init__(self, algorithms):
        self.algos = sorted(algorithms)

    def colour(self, algo):
        return plt.cm.tab10(self.algos.index(algo) % 10) if algo in self.algos else "grey"

    def marker(self, algo):
        return MARKERS[self.algos.index(algo) % len(MARKERS)] if algo in self.algos else "o"


def axes_labels(fig):
    """[[xlabel, ylabel], ...] of every visible axes with its axis drawn (image
    panels with the axis turned off are pictures, not plots)."""
    out = []
    for ax in fig.axes:
        if not (ax.get_visible() and ax.axison):
            continue
        if hasattr(ax, "_colorbar"):  # a colour bar has one axis: its label stands for both
            label = ax.get_xlabel() or ax.get_ylabel()
            out.append([label, label])
        else:
            out.append([ax.get_xlabel(), ax.get_ylabel()])
    return out


def figure_html(fig, alt, cls="plot"):
    """<img> of the figure, its axis labels in data-axes."""
    labels = axes_labels(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=DPI, bbox_inches="tight")
    plt.close(fig)
    uri = "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()
    return (f'<img class="{cls}" src="{uri}" alt="{html.escape(alt)}" '
            f"data-axes='{html.escape(json.dumps(labels))}'>")


def scale_for(values, allow_zero=False):
    """'log' when the positive values span more than a decade, 'symlog' when
    zeros must show too, else 'linear'."""
    pos = [v for v in values if v is not None and v > 0]
    if len(pos) < 2 or max(pos) / min(pos) <= 10.0:
        return "linear", None
    if allow_zero and any(v == 0 for v in values if v is not None):
        return "symlog", min(pos)
    return "log", None


def apply_scale(ax, axis, values, allow_zero=True):
    kind, lin = scale_for(values, allow_zero)
    setter = ax.set_xscale if axis == "x" else ax.set_yscale
    if kind == "symlog":  # log, with a linear stretch down to 0 (costs and errors are never negative)
        setter("symlog", linthresh=lin)
        # Minor ticks of a symlog axis cost most of a figure's drawing time and
        # carry no label: the decades' grid lines are enough to read it.
        (ax.xaxis if axis == "x" else ax.yaxis).set_minor_locator(matplotlib.ticker.NullLocator())
        if axis == "x":
            ax.set_xlim(left=0)
        else:
            ax.set_ylim(bottom=0)
    elif kind == "log":
        setter("log")
        (ax.xaxis if axis == "x" else ax.yaxis).set_minor_locator(matplotlib.ticker.NullLocator())
    elif axis == "x":
        ax.set_xlim(left=0)
    else:
        ax.set_ylim(bottom=0)
    return kind


def pareto_front(xs, ys):
    """Indices of the points no other point beats on both axes (both minimised)."""
    idx = sorted(range(len(xs)), key=lambda i: (xs[i], ys[i]))
    front, best = [], math.inf
    for i in idx:
        if ys[i] < best:
            front.append(i)
            best = ys[i]
    return front


def empty_panel(ax, text):
    ax.text(0.5, 0.5, text, ha="center", va="center", transform=ax.transAxes, fontsize=10, color="#555")
    ax.set_axis_off()
