"""Simulator speed modes: each mode's wall clock and its cycle and bandwidth
error against the cycle-by-cycle run of the same trace, algorithm, k, format
and hardware (every other ROP parameter equal)."""
import json
import math

import matplotlib.pyplot as plt

from .data import dram_bytes, num
from .plots import figure_html

SPEED_KEYS = ("config.rop.sim.quantum_cycles", "config.rop.skip.idle_cycles")


def speed_modes(points):
    """Speed modes of the simulator against the cycle-by-cycle reference
    (quantum 1, no idle skipping) of the same trace and hardware settings."""
    def mode_of(m):
        if m.get("config.mode") == "functional":
            return "functional"
        q, s = m.get(SPEED_KEYS[0]), m.get(SPEED_KEYS[1])
        return f"timing q={q} skip={'on' if s else 'off'}"

    def base_key(p):
        m = p["metrics"]
        return (p["trace"], m.get("config.algorithm"), m.get("config.layers"), m.get("config.format"))

    def hardware(p):
        # Every ROP parameter but the speed settings: points that differ in any
        # other (cache.ways, a preset ...) model different hardware and are
        # never compared with each other (audit: a cache.ways axis was measured
        # against the other ways' reference, 15.9 % "error").
        m = p["metrics"]
        return tuple(sorted((k, json.dumps(v)) for k, v in m.items()
                            if k.startswith("config.rop.") and k not in SPEED_KEYS))

    # Timing points group by trace, algorithm, k, format and every other ROP
    # parameter; a functional point (no ROP configuration) joins every group of
    # its trace and algorithm.
    groups = {}
    for p in points:
        if p["metrics"].get("config.mode") == "timing":
            groups.setdefault((base_key(p), hardware(p)), []).append(p)
    for p in points:
        if p["metrics"].get("config.mode") == "functional":
            for key, ps in groups.items():
                if key[0] == base_key(p):
                    ps.append(p)
    # Name the hardware settings that tell groups of one configuration apart.
    varying = {}
    for (base, hw) in groups:
        for k, v in hw:
            varying.setdefault((base, k), set()).add(v)
    rows = []
    for key, ps in sorted(groups.items(), key=lambda kv: str(kv[0])):
        refs = [p for p in ps if p["metrics"].get(SPEED_KEYS[0]) == 1 and p["metrics"].get(SPEED_KEYS[1]) is False]
        if not refs:
            continue
        ref = refs[0]["metrics"]
        base, hw = key
        config = f"{base[1]} k={base[2]} {base[3]}"
        extra = [f"{k[len('config.rop.'):]}={json.loads(v)}" for k, v in hw if len(varying[(base, k)]) > 1]
        if extra:
            config += " " + " ".join(extra)
        for p in ps:
            m = p["metrics"]
            row = {"trace": base[0], "config": config, "mode": mode_of(m), "id": p["id"],
                   "wall_s": num(m, "sim.wall_seconds"), "process_wall_s": p.get("wall_seconds")}
            row["speedup"] = (num(ref, "sim.wall_seconds") / row["wall_s"]) if row["wall_s"] else None
            if num(m, "timing.cycles") is not None:
                row["cycles"] = int(m["timing.cycles"])
                # Signed: (mode - reference) / reference (the goal takes |error|).
                row["cycle_err_pct"] = 100.0 * (m["timing.cycles"] - ref["timing.cycles"]) / ref["timing.cycles"]
                rb, b = dram_bytes(ref), dram_bytes(m)
                row["dram_bytes_err_pct"] = 100.0 * (b - rb) / rb if rb else 0.0
                rg, g = num(ref, "memory.mean_gbps"), num(m, "memory.mean_gbps")
                row["mean_gbps_err_pct"] = 100.0 * (g - rg) / rg if rg else 0.0
                rp, pk = num(ref, "memory.peak_gbps"), num(m, "memory.peak_gbps")
                row["peak_gbps_err_pct"] = 100.0 * (pk - rp) / rp if rp else 0.0
            rows.append(row)
    goal = "a timing mode within 1% of cycle-by-cycle cycles at >= 10x its speed"
    if not rows:
        # Still a JSON object (scripts read speed.json): no group had its reference point.
        return {"rows": [], "modes": {}, "goal": goal, "goal_met": False,
                "note": "no speed-mode group: each needs a cycle-by-cycle timing point (sim.quantum_cycles=1, "
                        "skip.idle_cycles=false) of the same trace, algorithm, k, format and other ROP parameters"}
    # The goal: a timing mode (not functional, not the reference) within 1 % of
    # the cycle-by-cycle cycles in every group, at >= 10x its speed in every group.
    verdicts = {}
    for r in rows:
        if r["mode"] == "functional" or r["mode"].startswith("timing q=1 skip=off"):
            continue
        v = verdicts.setdefault(r["mode"], {"max_cycle_err_pct": 0.0, "max_mean_gbps_err_pct": 0.0,
                                            "min_speedup": math.inf, "groups": 0})
        v["groups"] += 1
        v["max_cycle_err_pct"] = max(v["max_cycle_err_pct"], abs(r.get("cycle_err_pct", math.inf)))
        v["max_mean_gbps_err_pct"] = max(v["max_mean_gbps_err_pct"], abs(r.get("mean_gbps_err_pct", math.inf)))
        v["min_speedup"] = min(v["min_speedup"], r["speedup"] or 0.0)
    for v in verdicts.values():
        v["goal_met"] = v["max_cycle_err_pct"] <= 1.0 and v["min_speedup"] >= 10.0
    return {"rows": rows, "modes": verdicts, "goal": goal, "goal_met": any(v["goal_met"] for v in verdicts.values())}


def speed_plot(speed):
    fig, ax = plt.subplots(figsize=(8, 4.5))
    modes = sorted({r["mode"] for r in speed["rows"]})
    for i, mode in enumerate(modes):
        sel = [r for r in speed["rows"] if r["mode"] == mode and r["wall_s"]]
        ax.scatter([r["wall_s"] for r in sel], [max(abs(r.get("cycle_err_pct", 100.0)), 1e-4) for r in sel],
                   label=mode + (" (no cycles: plotted at 100 %)" if mode == "functional" else
                                 " (the reference: plotted at 1e-4 %)" if mode.startswith("timing q=1 ") else ""),
                   color=plt.cm.tab10(i), s=40)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.axhline(1.0, color="grey", linestyle="--", linewidth=1, label="1 % goal")
    ax.set_xlabel("simulator wall-clock seconds (sim.wall_seconds)")
    ax.set_ylabel("|cycles - cycle-by-cycle| / cycle-by-cycle (%)")
    ax.set_title("simulator speed modes: wall-clock against cycle error")
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3, which="both")
    return figure_html(fig, "speed modes")


