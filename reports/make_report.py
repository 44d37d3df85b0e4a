#!/usr/bin/env python3
"""Draws DIR/report.html for an `oitsim sweep` folder: one page (every plot and
thumbnail embedded as a data URI; full-size images of large frames are opened
from the sweep folder beside the page) that an architect can decide from.

Called by `oitsim report DIR` after it has rebuilt DIR/results.json; needs
Debian's python3-matplotlib (and numpy). The sections live in htmlreport/
(reports/SWEEP.md, "The report"): per scene, where the time goes (bottleneck),
cost against error per hardware configuration, curves against k and any other
numeric axis, the memory table, the image grid and the depth complexity; the
simulator's speed modes; every point. Also writes DIR/speed.json for scripts.
"""
import argparse
import html
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from htmlreport import bottleneck, curves, data, images, memory, ordering, page, pareto, speed, tables  # noqa: E402
from htmlreport.page import esc, fmt_num  # noqa: E402
from htmlreport.plots import Styles  # noqa: E402
from htmlreport.speed import speed_modes, speed_plot  # noqa: E402,F401  (tests import speed_modes from here)


class Progress:
    """One line per step on stderr, with the seconds since the start."""

    def __init__(self, quiet):
        self.quiet = quiet
        self.t0 = time.monotonic()

    def __call__(self, what):
        if not self.quiet:
            print(f"report: {what} ({time.monotonic() - self.t0:.1f} s)", file=sys.stderr, flush=True)


def write_atomically(path, text):
    """Whole or not at all, as every other output (temporary file, then rename)."""
    tmp = f"{path}.tmp.{os.getpid()}"
    try:
        with open(tmp, "w") as f:
            f.write(text)
        try:
            os.replace(tmp, path)
        except OSError as e:  # name the file the user knows, not the temporary
            raise OSError(e.errno, e.strerror, path) from e
    finally:
        if os.path.exists(tmp):
            os.remove(tmp)


def speed_section(speed_data):
    if not speed_data["rows"]:
        return ""
    t = page.table
    c = page.cell
    out = ["<h2 id='speed'>Simulator speed modes</h2>",
           f"<p>Goal: {esc(speed_data['goal'])}: <b>{'met' if speed_data['goal_met'] else 'not met'}</b>.</p>"]
    out.append(t(["mode", "groups", "max cycle error (%)", "max mean GB/s error (%)", "min speed-up (x)", "goal"],
                 [[c(m, esc(m), "t"), c(v["groups"]), c(v["max_cycle_err_pct"]), c(v["max_mean_gbps_err_pct"]),
                   c(v["min_speedup"]), c("met" if v["goal_met"] else "not met", None, "t")]
                  for m, v in sorted(speed_data["modes"].items())]))
    out.append(speed_plot(speed_data))
    out.append(t(["trace", "config", "mode", "wall (s)", "speed-up (x)", "cycles", "cycle error (%)",
                  "DRAM bytes error (%)", "mean GB/s error (%)", "peak GB/s error (%)"],
                 [[c(r["trace"], esc(r["trace"]), "t"), c(r["config"], esc(r["config"]), "t"),
                   c(r["mode"], esc(r["mode"]), "t"), c(r["wall_s"]), c(r["speedup"]), c(r.get("cycles")),
                   c(r.get("cycle_err_pct")), c(r.get("dram_bytes_err_pct")), c(r.get("mean_gbps_err_pct")),
                   c(r.get("peak_gbps_err_pct"))] for r in speed_data["rows"]]))
    return "\n".join(out)


def scene_section(scene, tp, all_tp, res, configs, styles, trace_paths, out_dir, oitsim, log):
    """Everything about one scene; returns (html, reference URI)."""
    sid = "scene-" + scene
    body = [f"<h2 id='{esc(sid)}'>Scene {esc(scene)}</h2>"]
    if not tp:
        return "\n".join(body + ["<p>No point of this scene has succeeded.</p>"]), None
    m0 = tp[0]["metrics"]
    body.append(f"<p>{fmt_num(data.num(m0, 'trace.width'))} x {fmt_num(data.num(m0, 'trace.height'))} pixels, "
                f"{fmt_num(data.num(m0, 'trace.fragments'))} fragments; {len(tp)} points ok of {len(all_tp)} "
                f"(<code>{esc(m0.get('trace.path'))}</code>).</p>")
    if any(data.is_timing(p) for p in tp):
        body.append("<h3>Where the time goes</h3>" + bottleneck.section(tp, scene, configs, log))
    body.append("<h3>Cost against image error</h3>" + pareto.section(tp, scene, configs, styles, log))
    if ordering.applies(tp):
        body.append("<h3>The price of order</h3>" + ordering.section(tp, scene, configs, styles, log))
    cv = curves.section(tp, scene, res.get("axes", []), configs, styles, log)
    if cv:
        body.append("<h3>Against k and the other numeric axes</h3>" + cv)
    log(f"{scene}: memory table")
    mem = memory.section(tp, scene, configs)
    if mem:
        body.append("<h3>Memory (as the MLAB paper's Table 1)</h3>" + mem)
    grid, ref_uri = images.scene_grid(tp, scene, out_dir, log)
    body.append("<h3>Images</h3><p class='note'>Per algorithm and k: the image, and under it its |difference| x4 "
                "(left) and its FLIP map (right). With lock.mode=ordered an image does not depend on the hardware "
                "configuration (the timing model decides when, never what), so one grid serves every machine; "
                "images the timing run drew (lock.mode unordered or none) are labelled with their order. Click any thumbnail "
                "for the full-size image; click that to swap it with the reference.</p>" +
                images.colourbar_html() + grid)
    log(f"{scene}: depth complexity")
    hm = images.depth_heatmap(trace_paths.get(scene) or m0.get("trace.path"), oitsim)
    if hm:
        body.append("<h3>Depth complexity</h3>" + hm)
    return "\n".join(body), ref_uri


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("dir")
    ap.add_argument("--out")
    ap.add_argument("--oitsim", help="oitsim executable (for the depth-complexity heatmap)")
    ap.add_argument("--quiet", action="store_true")
    a = ap.parse_args()
    log = Progress(a.quiet)
    out = a.out or os.path.join(a.dir, "report.html")
    out_dir = os.path.dirname(os.path.abspath(out))
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
    log(f"{len(points)} points read ({len(ok)} ok)")

    speed_data = speed_modes(ok)
    write_atomically(os.path.join(a.dir, "speed.json"), json.dumps(speed_data, indent=1, default=lambda v: None))

    configs = data.Configs(ok)
    styles = Styles({data.algorithm(p) for p in ok})
    scenes = sorted({p["trace"] for p in points})
    dups = res.get("duplicates", [])
    body = ["<h1>oitsim sweep report</h1>",
            f"<p>Spec <code>{esc(res.get('spec'))}</code>: {len(points)} points, <span class='ok'>{len(ok)} ok</span>, "
            f"<span class='failed'>{len(failed)} failed</span>"
            + (f", <span class='notrun'>{len(not_run)} not run</span>" if not_run else "") + "."
            + (f" {len(dups)} more combinations differ only in settings their algorithm or mode ignores and ran "
               "once (<code>duplicates</code> in results.json)." if dups else "") + "</p>",
            "<p class='toc'>" + " ".join(
                (["<a href='#hardware'>hardware</a>"] if configs.order else []) +
                [f"<a href='#scene-{esc(s)}'>{esc(s)}</a>" for s in scenes] +
                (["<a href='#speed'>speed modes</a>"] if speed_data["rows"] else []) +
                ["<a href='#points'>all points</a>"]) + "</p>",
            "<p class='note'>Errors are against the exact A-buffer: FLIP (Andersson et al. 2020, 0 = no visible "
            "difference, 1 = the largest) at the points' pixels per degree, and RMSE. Frame time, DRAM and "
            "footprint come from timing-mode points, per hardware configuration; functional points show the "
            "functional model's per-pixel state traffic and size instead. Axes are logarithmic where a range "
            "spans more than a decade.</p>"]
    body.append(tables.configs_section(ok, configs))
    if failed:
        body.append("<h2>Failed points</h2>")
        for p in failed:
            body.append(f"<p class='failed'>{esc(p['id'])}</p><pre>{esc(p['error'])}</pre>")
    if not_run:
        body.append("<h2>Points not run</h2><p class='notrun'>No status, output or report yet (rerun "
                    "<code>oitsim report</code> when they have run): "
                    + ", ".join(esc(p["id"]) for p in not_run) + "</p>")
    refs = {}
    for scene in scenes:
        tp = [p for p in ok if p["trace"] == scene]
        html_part, ref = scene_section(scene, tp, [p for p in points if p["trace"] == scene], res, configs, styles,
                                       trace_paths, out_dir, a.oitsim, log)
        body.append(html_part)
        if ref:
            refs[scene] = ref
    if speed_data["rows"]:
        log("speed modes")
        body.append(speed_section(speed_data))
    log("all points table")
    body.append("<h2 id='points'>All points</h2>")
    csv_path = os.path.join(a.dir, "results.csv")
    csv_link = os.path.relpath(csv_path, out_dir) if os.path.exists(csv_path) else None
    body.append(tables.points_section(points, configs, res.get("axes", []), csv_link))
    text = page.page("oitsim sweep report", "\n".join(body), json.dumps(refs).replace("</", "<\\/"))
    write_atomically(out, text)
    if not a.quiet:
        print(f"report {out} ({len(text) // 1024} KiB, {len(points)} points: {len(ok)} ok, {len(failed)} failed, "
              f"{len(not_run)} not run)")
        for mode, v in sorted(speed_data["modes"].items()):
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
