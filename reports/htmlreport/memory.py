"""Memory per algorithm and k, like the MLAB paper's Table 1: the per-pixel
blending arrays (or the A-buffer's heads and node pool) a GPU would allocate,
and what the frame touched, in MiB."""
from . import data
from .page import cell, esc, fmt_num, table


def _arrays(m):
    """(allocated, touched) bytes of the OIT storage; the functional model has
    no tiles: its per-pixel state, touched unknown."""
    a = data.num(m, "memory.footprint.allocated.blend_arrays")
    if a is not None:
        return a, data.num(m, "memory.footprint.touched.blend_arrays")
    return data.num(m, "memory.state_bytes"), None


def section(points, scene, configs):
    # Allocation depends on the algorithm, k, format and frame; what is touched
    # also on the hardware's tile size: one row per configuration only where it differs.
    entries = {}
    for p in points:
        a, t = _arrays(p["metrics"])
        if a is None:
            continue
        key = (data.algorithm(p), data.image_settings(p))
        entries.setdefault(key, {}).setdefault(data.k_of(p), {})[configs.label(p)] = (a, t)
    if not entries:
        return ""
    ks = sorted({k for row in entries.values() for k in row if k is not None})
    touched = any(t is not None for row in entries.values() for per in row.values() for _, t in per.values())
    unit = "allocated / touched (MiB)" if touched else "allocated (MiB)"
    headers = ["algorithm"] + [f"k = {k}" for k in ks]
    if any(None in row for row in entries.values()):
        headers = ["algorithm", "no k"] + headers[1:]
    rows = []
    for (algo, settings), row in sorted(entries.items()):
        by_conf = {}
        for k, per in row.items():
            for conf, v in per.items():
                by_conf.setdefault(conf, {})[k] = v
        same = all(len({v for v in per.values()}) == 1 for per in row.values())
        groups = [(None, {k: next(iter(per.values())) for k, per in row.items()})] if same else sorted(by_conf.items())
        for conf, vals in groups:
            name = algo + (f" ({settings})" if settings else "") + (f" on {conf}" if conf else "")
            r = [cell(name, esc(name), "t")]
            cols = ([None] if len(headers) > 1 and headers[1] == "no k" else []) + ks
            for k in cols:
                v = vals.get(k)
                if v is None:
                    r.append(cell(None, ""))
                    continue
                a, t = v
                text = fmt_num(a / data.MIB) + (" / " + fmt_num(t / data.MIB) if t is not None else "")
                r.append(cell(a / data.MIB, text))
            rows.append(r)
    return (f"<p class='note'>Each cell: {unit}. Blending arrays allocated (W x H x bytes per pixel; the A-buffer: "
            "4 W H of heads + 12 bytes per fragment) and touched by this frame (whole tiles, timing mode); functional "
            "points show their per-pixel state, allocated only. Depth and colour surfaces (4 W H each) are not "
            "included.</p>" + table(headers, rows))
