#!/usr/bin/env python3
"""The memory hierarchy's page (reports/repro/memory-hierarchy/results.md) from
the three sweeps run.sh makes (their results.json):

    python3 reports/repro/memory-hierarchy/make_page.py out/repro/memory-hierarchy > results.md
"""
import json
import os
import sys

MIB = 1024.0 * 1024.0


def points(work, sweep):
    data = json.load(open(os.path.join(work, sweep, "results.json")))
    rows = [p for p in data["points"] if p["status"] == "ok"]
    if len(rows) != data["summary"]["points"]:
        sys.exit(f"{sweep}: {data['summary']['points'] - len(rows)} point(s) did not finish")
    return rows


def m(p, key):
    return p["metrics"][key]


def traffic(p):
    """DRAM bytes during the frame, left dirty, compulsory (MiB), and their ratio."""
    dram = m(p, "memory.dram_read_bytes.total") + m(p, "memory.dram_write_bytes.total")
    return (dram / MIB, m(p, "memory.end_dirty_bytes.total") / MIB, m(p, "memory.compulsory_bytes.total") / MIB,
            m(p, "memory.traffic_over_compulsory"))


def levels(p):
    out = []
    i = 0
    while f"memory.levels.{i}.name" in p["metrics"]:
        k = f"memory.levels.{i}."
        out.append({f: p["metrics"][k + f] for f in ("name", "accesses", "hits", "misses", "hit_rate", "fill_bytes",
                                                     "writeback_bytes", "compulsory_misses", "capacity_misses",
                                                     "conflict_misses")})
        i += 1
    return out


def table(header, rows):
    """A Markdown table: the header's cells, then each row's."""
    print("| " + " | ".join(header) + " |")
    print("|" + " --- |" * len(header))
    for r in rows:
        print("| " + " | ".join(str(c) for c in r) + " |")
    print()


def levels_page(work):
    rows = points(work, "memory-levels")
    print("## Bytes per level against compulsory (1280x720, MLAB k=4 `rgba8t8z32`)")
    print()
    print("Per point: the frame, DRAM bytes moved during it, the bytes left dirty in the caches at its end "
          "(they reach DRAM when evicted, during the next frame), the compulsory bytes (every byte the frame writes "
          "leaves the chip once; nothing is read that the frame did not write) and the ratio "
          "`memory.traffic_over_compulsory` = (DRAM + left dirty) / compulsory.")
    print()
    table(["trace", "hierarchy", "frame (us)", "DRAM (MiB)", "left dirty (MiB)", "compulsory (MiB)", "ratio"],
          [[p["trace"], p["axes"]["hierarchy"], f"{m(p, 'timing.frame_time_us'):.0f}", f"{d:.1f}", f"{e:.1f}",
            f"{c:.2f}", f"{r:.2f}"] for p in rows for d, e, c, r in [traffic(p)]])
    print("Where the traffic comes from: each level's hit rate, its misses by cause (compulsory: a sector it never "
          "held; conflict: a fully associative LRU cache of as many lines, filling sectors alike, would have held "
          "the sectors; capacity: it would have missed too) and the bytes it filled from below and wrote back.")
    print()
    table(["trace", "hierarchy", "level", "accesses", "hit rate", "compulsory", "capacity", "conflict",
           "filled (MiB)", "written back (MiB)"],
          [[p["trace"], p["axes"]["hierarchy"], l["name"], l["accesses"], f"{100 * l['hit_rate']:.1f} %",
            l["compulsory_misses"], l["capacity_misses"], l["conflict_misses"], f"{l['fill_bytes'] / MIB:.1f}",
            f"{l['writeback_bytes'] / MIB:.1f}"] for p in rows for l in levels(p)])


def size_page(work):
    rows = points(work, "memory-cache-size")
    print("## Cache size (particles 640x360, MLAB k=4 `rgba8t8z32`, iris-pro-5200)")
    print()
    print("`rop-*`: the ROP cache per partition alone before DRAM; `l2-*`: the 64 KiB ROP caches and an l2 of "
          "that size; the last point is the preset (6 MB LLC, 128 MB eDRAM).")
    print()
    table(["caches", "frame (us)", "ROP hit rate", "DRAM (MiB)", "left dirty (MiB)", "ratio"],
          [[p["axes"]["cache"], f"{m(p, 'timing.frame_time_us'):.0f}", f"{100 * m(p, 'cache.hit_rate'):.1f} %",
            f"{d:.1f}", f"{e:.1f}", f"{r:.2f}"] for p in rows for d, e, _, r in [traffic(p)]])


def line_page(work):
    rows = points(work, "memory-line-size")
    print("## Line size and array layout (particles 640x360, k=4 `rgba8t8z32`, ROP caches before DRAM)")
    print()
    table(["algorithm", "layout", "line (B)", "frame (us)", "ROP accesses", "ROP hit rate",
           "lines per insert (max)", "DRAM (MiB)", "ratio"],
          [[p["axes"]["algo"], p["axes"]["memory.array_layout"], p["axes"]["cache.line_bytes"],
            f"{m(p, 'timing.frame_time_us'):.0f}", m(p, "cache.accesses"), f"{100 * m(p, 'cache.hit_rate'):.1f} %",
            m(p, "cache.max_lines_per_insert"), f"{d:.1f}", f"{r:.2f}"]
           for p in rows for d, _, _, r in [traffic(p)]])


def dram_page(work):
    rows = points(work, "memory-dram")
    print("## DRAM controller: closed page and scheduler (MLAB k=4 `rgba8t8z32`)")
    print()
    print("`dram.open_row=false`: closed page, one activate per request's run of bursts in a row and an "
          "auto-precharge after it; `dram.scheduler=fcfs`: reads in arrival order, `frfcfs`: a read whose data can "
          "go earlier takes the bus time older ones leave idle (MEMORY.md). Bunny 1280x720 (captured), particles "
          "640x360. `iris-pro-5200-dram-only`: the preset without its l2 and l3 (the ROP caches before DRAM).")
    print()
    base = {}
    for p in rows:
        if p["axes"]["dram.open_row"] == "true" and p["axes"]["dram.scheduler"] == "frfcfs":
            base[(p["trace"], p["axes"]["machine"])] = m(p, "timing.cycles")
    out = []
    for p in rows:
        hits, misses = m(p, "memory.row_hits"), m(p, "memory.row_misses")
        d, _, _, _ = traffic(p)
        b = base[(p["trace"], p["axes"]["machine"])]
        out.append([p["trace"], p["axes"]["machine"], "open" if p["axes"]["dram.open_row"] == "true" else "closed",
                    p["axes"]["dram.scheduler"], f"{m(p, 'timing.frame_time_us'):.0f}",
                    f"{100.0 * (m(p, 'timing.cycles') / b - 1):+.1f} %", f"{d:.1f}",
                    f"{100.0 * hits / max(1, hits + misses):.1f} %", f"{m(p, 'memory.mean_gbps'):.1f}"])
    table(["trace", "machine", "rows", "scheduler", "frame (us)", "against open + frfcfs", "DRAM (MiB)",
           "row hits (bursts)", "mean GB/s"], out)


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    work = sys.argv[1]
    print("# The memory hierarchy: bytes per level against compulsory, cache and line sizes")
    print()
    print("Made by `reports/repro/memory-hierarchy/run.sh` (the sweeps `reports/sweep/memory-levels.json`, "
          "`memory-cache-size.json`, `memory-line-size.json`, `memory-dram.json`; cycle engine). Definitions: "
          "[MEMORY.md](../../../oit_rop/memory/MEMORY.md), \"Compulsory traffic\".")
    print()
    levels_page(work)
    size_page(work)
    line_page(work)
    dram_page(work)


if __name__ == "__main__":
    main()
