"""The page's tables: the hardware configurations (what each preset is), and
every point with its main figures (sortable, units in the headers, a CSV)."""
import csv
import io
import urllib.parse

from . import data
from .page import cell, esc, fmt_num, fmt_pct, table

# The parameters that say what a machine is (oit_rop/config/CONFIG.md), in this order.
KEY_PARAMETERS = [
    ("clock.core_mhz", "core clock (MHz)"),
    ("partitions.count", "ROP partitions"),
    ("input.fragments_per_clock", "fragments per clock per partition"),
    ("lock.capacity", "lock scoreboard entries per partition"),
    ("lock.granularity", "lock granularity"),
    ("cache.size_bytes", "blend-array cache per partition (KiB)"),
    ("cache.ways", "cache ways"),
    ("alu.blends_per_clock", "blends per clock per partition"),
    ("dram.channels", "DRAM channels"),
    ("dram.channel_gbps", "GB/s per channel"),
    ("dram.banks", "banks per channel"),
]


def configs_section(points, configs):
    labels = [c for c in configs.all_labels(points) if c != configs.FUNCTIONAL]
    if not labels:
        return ""
    params = {c: configs.params(c) for c in labels}
    keys = [k for k, _ in KEY_PARAMETERS]
    # Every other parameter that differs between the configurations, too.
    differing = sorted({k for c in labels for k in params[c] if k not in keys and k != "preset"
                        and len({str(params[o].get(k)) for o in labels}) > 1})
    headers = ["parameter"] + labels
    rows = []
    for k, name in KEY_PARAMETERS + [(k, k) for k in differing]:
        r = [cell(name, esc(name), "t")]
        for c in labels:
            v = params[c].get(k)
            if k == "cache.size_bytes" and isinstance(v, (int, float)):
                v = v / 1024
            r.append(cell(v if isinstance(v, (int, float)) else str(v), fmt_num(v) if isinstance(v, (int, float))
                          else esc(v)))
        rows.append(r)
    peak = [cell(None, "peak DRAM (GB/s)", "t")]
    for c in labels:
        ch, gbps = params[c].get("dram.channels"), params[c].get("dram.channel_gbps")
        v = ch * gbps if isinstance(ch, (int, float)) and isinstance(gbps, (int, float)) else None
        peak.append(cell(v, fmt_num(v)))
    rows.append(peak)
    return ("<h2 id='hardware'>Hardware configurations</h2><p>Each timing point ran on one of these machines "
            "(the preset, then the sweep's settings; every parameter: <code>oitsim config --preset NAME</code> and "
            "<code>oit_rop/config/CONFIG.md</code>). Plots and tables keep them apart.</p>" + table(headers, rows))


COLUMNS = [
    # (header, value of a point, text or None for the default number format)
    ("FLIP mean", lambda p, c: data.flip_mean(p["metrics"])),
    ("RMSE", lambda p, c: data.rmse(p["metrics"])),
    ("SSIM", lambda p, c: data.num(p["metrics"], "image.metrics.ssim"), 5),
    ("PSNR (dB)", lambda p, c: data.num(p["metrics"], "image.metrics.psnr")),
    ("frame (us)", lambda p, c: data.frame_us(p["metrics"])),
    ("DRAM (MiB)", lambda p, c: _mib(data.dram_bytes(p["metrics"]))),
    ("DRAM mean (GB/s)", lambda p, c: data.num(p["metrics"], "memory.mean_gbps")),
    ("DRAM utilisation (%)", lambda p, c: _pct(data.dram_utilisation(p["metrics"]))),
    ("cache hit rate (%)", lambda p, c: _pct(data.num(p["metrics"], "cache.hit_rate"))),
    ("allocated (MiB)", lambda p, c: _mib(data.footprint(p["metrics"]) or data.num(p["metrics"], "memory.state_bytes"))),
    ("touched (MiB)", lambda p, c: _mib(data.footprint(p["metrics"], "touched"))),
    ("lock-wait cycles", lambda p, c: data.num(p["metrics"], "lock.wait_cycles")),
    ("sim wall (s)", lambda p, c: data.num(p["metrics"], "sim.wall_seconds")),
    ("process wall (s)", lambda p, c: p.get("wall_seconds")),
]


def _mib(v):
    return None if v is None else v / data.MIB


def _pct(v):
    return None if v is None else 100.0 * v


def points_section(points, configs, axes, csv_link):
    """Every point: sortable, numbers with separators, a CSV of what is shown."""
    headers = ["id", "scene", "status", "hardware"] + [f"axis {a}" for a in axes] + [c[0] for c in COLUMNS]
    rows, raw = [], []
    for p in points:
        status = p["status"]
        vals = [c[1](p, configs) for c in COLUMNS]
        r = [cell(p["id"], esc(p["id"]), "t"), cell(p["trace"], esc(p["trace"]), "t"),
             cell(status, f"<span class='{status.replace(' ', '')}'>{esc(status)}</span>", "t"),
             cell(configs.label(p) if status == "ok" else "", esc(configs.label(p)) if status == "ok" else "", "t")]
        r += [cell(str(p["axes"].get(a, "")), esc(p["axes"].get(a, "")), "t") for a in axes]
        r += [cell(v, fmt_num(v, c[2] if len(c) > 2 else 3)) for v, c in zip(vals, COLUMNS)]
        rows.append(r)
        raw.append([p["id"], p["trace"], status, configs.label(p) if status == "ok" else ""] +
                   [p["axes"].get(a, "") for a in axes] + ["" if v is None else v for v in vals])
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(headers)
    w.writerows(raw)
    href = "data:text/csv;charset=utf-8," + urllib.parse.quote(buf.getvalue())
    links = (f"<p><a download='oitsim-points.csv' href='{href}'>Download this table as CSV</a>"
             + (f" &middot; every metric of every point: <a href='{csv_link}'>results.csv</a> (beside this page)"
                if csv_link else "") + ". Click a header to sort.</p>")
    return links + table(headers, rows)


__all__ = ["configs_section", "points_section", "fmt_pct"]
