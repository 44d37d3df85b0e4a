#!/usr/bin/env python3
"""Print the Markdown tables of reports/repro/README.md from the committed
results (so the README's numbers come from the tables, not from hand copying).

    python3 reports/repro/tables.py error-vs-k        # from error-vs-k/results.csv
    python3 reports/repro/tables.py hardware-pareto   # from hardware-pareto/results.csv
    python3 reports/repro/tables.py table1-memory     # from table1-memory/results.csv
    python3 reports/repro/tables.py speed-modes       # from speed-modes/speed.json

reports/repro/regenerate.sh NAME reruns a reproduction and prints its table.
"""
import csv
import json
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
MIB = 1024.0 * 1024.0


def grouped(n):
    """3776640 -> '3 776 640' (the README's thousands separator)."""
    return f"{n:,}".replace(",", " ")


def rows_of(name):
    return list(csv.DictReader(open(os.path.join(HERE, name, "results.csv"), newline="")))


def error_vs_k():
    """RMSE / SSIM, then the FLIP mean (when the results have it), per trace, algorithm and k."""
    rows = rows_of("error-vs-k")
    ks = sorted({int(r["axis.layers"]) for r in rows})
    cells = {}
    for r in rows:
        cells.setdefault((r["trace"], r["axis.algo"]), {})[int(r["axis.layers"])] = r
    head = "| trace | algorithm | " + " | ".join(f"k={k}" for k in ks) + " |"
    rule = "|---|---|" + "---|" * len(ks)
    print(head)
    print(rule)
    for (trace, algo), by_k in sorted(cells.items()):
        print(f"| {trace} | {algo} | " + " | ".join(
            f"{float(by_k[k]['image.metrics.rmse']):.4f} / {float(by_k[k]['image.metrics.ssim']):.4f}" for k in ks) + " |")
    if all(r.get("image.metrics.flip.mean") for r in rows):
        print()
        print(head.replace("| algorithm |", "| algorithm (FLIP mean) |"))
        print(rule)
        for (trace, algo), by_k in sorted(cells.items()):
            print(f"| {trace} | {algo} | " + " | ".join(
                f"{float(by_k[k]['image.metrics.flip.mean']):.4f}" for k in ks) + " |")


def table1_memory():
    """The blending arrays allocated per configuration and trace (bytes, MiB)."""
    rows = rows_of("table1-memory")
    print("| trace | config | fragments F | blend_arrays allocated (bytes) | MiB |")
    print("| --- | --- | --- | --- | --- |")
    for r in rows:
        b = int(r["memory.footprint.allocated.blend_arrays"])
        print(f"| {r['trace']} | {r['axis.config']} | {grouped(int(r['trace.fragments']))} | {grouped(b)} "
              f"| {b / MIB:.2f} |")


def hardware_pareto():
    """Frame time, what bounds it, the traffic between the ROP caches and the l2, DRAM's bytes, the bytes
    left dirty against compulsory, footprint, lock waits and error, per trace, algorithm and k."""
    rows = rows_of("hardware-pareto")
    order = {"particles": 0, "hair": 1}
    algos = {"mlab": 0, "hybrid": 1, "adaptive": 2}
    rows.sort(key=lambda r: (order.get(r["trace"], 9), algos.get(r["axis.algo"], 9), int(r["axis.layers"])))
    print("| trace | algorithm k | frame time (us) | bound by (share) | ROP caches <-> l2 (MiB) "
          "| DRAM read+written (MiB) | left dirty / compulsory (MiB) | traffic / compulsory "
          "| footprint allocated (MiB) | lock wait cycles | RMSE | SSIM |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        dram = int(r["memory.dram_read_bytes.total"]) + int(r["memory.dram_write_bytes.total"])
        foot = sum(int(r[f"memory.footprint.allocated.{s}"]) for s in ("blend_arrays", "colour", "depth", "resolve"))
        # The level below the ROP caches (levels.1: the l2) serves their fills and takes their write-backs;
        # without an l2 that is DRAM.
        l2 = (int(r["memory.levels.1.read_bytes"]) + int(r["memory.levels.1.write_bytes"])
              if r.get("memory.levels.1.name") else dram)
        print(f"| {r['trace']} | {r['axis.algo']} {r['axis.layers']} | {float(r['timing.frame_time_us']):.0f} "
              f"| {r['timing.bound_by.resource']} {100 * float(r['timing.bound_by.share']):.0f} % "
              f"| {l2 / MIB:.1f} | {dram / MIB:.1f} "
              f"| {int(r['memory.end_dirty_bytes.total']) / MIB:.2f} / {int(r['memory.compulsory_bytes.total']) / MIB:.2f} "
              f"| {float(r['memory.traffic_over_compulsory']):.2f}x "
              f"| {foot / MIB:.2f} | {grouped(int(r['lock.wait_cycles']))} "
              f"| {float(r['image.metrics.rmse']):.4f} | {float(r['image.metrics.ssim']):.4f} |")


def speed_modes():
    data = json.load(open(os.path.join(HERE, "speed-modes", "speed.json")))
    cols = ["timing q=1 skip=off", "functional", "timing q=200 skip=on", "timing q=1000 skip=on",
            "timing q=100000 skip=on"]
    table = {}
    for r in data["rows"]:
        table.setdefault((r["trace"], r["config"]), {})[r["mode"]] = r
    print("| trace, config | cycle-by-cycle | functional | fast: skip idle, q=200 (default) | skip idle, q=1000 "
          "| skip idle, q=100000 |")
    print("| --- | --- | --- | --- | --- | --- |")
    order = {"particles": 0, "hair": 1}
    for (trace, config) in sorted(table, key=lambda k: (order.get(k[0], 9), k[1].split()[0] != "mlab")):
        modes = table[(trace, config)]
        name = config.split(" k=")[0] + config.split(" k=")[1].split()[0]  # "mlab k=4 rgba8t8z32" -> "mlab4"
        cells = []
        for i, m in enumerate(cols):
            r = modes.get(m)
            if r is None:
                cells.append("-")
            elif i == 0:
                cells.append(f"{r['wall_s']:.2f} s, {grouped(r['cycles'])} cycles")
            elif m == "functional":
                cells.append(f"{r['wall_s']:.2f} s ({r['speedup']:.1f}x), no cycles")
            else:
                unit = " cycles" if i == 2 else ""
                cells.append(f"{r['wall_s']:.2f} s ({r['speedup']:.1f}x), {r['cycle_err_pct']:+.3f} %{unit}")
        print(f"| {trace} {name} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    which = sys.argv[1] if len(sys.argv) > 1 else ""
    tables = {"error-vs-k": error_vs_k, "hardware-pareto": hardware_pareto, "table1-memory": table1_memory,
              "speed-modes": speed_modes}
    if which not in tables:
        sys.exit("usage: tables.py " + "|".join(tables))
    tables[which]()
