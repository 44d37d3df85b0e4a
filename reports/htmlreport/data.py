"""The sweep's points as the report sees them: metrics by name, labels, and the
groupings the sections use (scene, hardware configuration, algorithm, k).

Every accessor returns None when a point lacks the metric (functional points
have no timing; reports from before a metric existed lack it), and the
sections fall back or leave the cell empty; no value is ever invented.
"""
import json
import math

# Settings of the ROP configuration that change how fast the simulator runs,
# not the modelled hardware (a speed-mode axis is not another machine).
SIM_PREFIXES = ("config.rop.sim.", "config.rop.stats.")
SIM_KEYS = ("config.rop.skip.idle_cycles",)

STAGES = ["shader_input", "early_depth", "pixel_lock", "cache", "blend_alu", "resolve"]
STALL_CAUSES = ["lock_wait", "scoreboard_full", "cache_miss_wait", "dram_bandwidth", "alu_busy", "input_starved",
                "atomic_wait", "list_walk", "sort"]
MIB = 1024.0 * 1024.0


def num(m, key):
    """A finite number from the flattened metrics, else None."""
    v = m.get(key)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return None
    return float(v) if math.isfinite(v) else None


def json_list(m, key):
    """Arrays of numbers are JSON text in the flattened metrics."""
    v = m.get(key)
    if isinstance(v, list):
        return v
    if isinstance(v, str):
        try:
            out = json.loads(v)
            return out if isinstance(out, list) else None
        except ValueError:
            return None
    return None


def prefixed(m, prefix):
    """{rest of key: number} of every numeric metric under prefix."""
    out = {}
    for k, v in m.items():
        if k.startswith(prefix):
            x = num(m, k)
            if x is not None:
                out[k[len(prefix):]] = x
    return out


def is_timing(p):
    return num(p["metrics"], "timing.cycles") is not None


def algorithm(p):
    return p["metrics"].get("config.algorithm") or p["axes"].get("algo") or "?"


def uses_k(p):
    """False for an algorithm that ignores k (config.ignored_settings)."""
    ignored = json_list(p["metrics"], "config.ignored_settings")
    if ignored is not None:
        return "layers" not in ignored
    return algorithm(p) not in ("abuffer", "alpha", "wsum", "wavg", "wboit", "stochastic")


def k_of(p):
    k = num(p["metrics"], "config.layers")
    return int(k) if k is not None and uses_k(p) else None


def algo_label(p):
    k = k_of(p)
    return f"{algorithm(p)} k={k}" if k is not None else algorithm(p)


# --- costs and errors ---------------------------------------------------------

def frame_us(m):
    return num(m, "timing.frame_time_us")


def dram_bytes(m):
    r, w = num(m, "memory.dram_read_bytes.total"), num(m, "memory.dram_write_bytes.total")
    return r + w if r is not None and w is not None else None


def footprint(m, kind="allocated"):
    vals = prefixed(m, f"memory.footprint.{kind}.")
    return sum(vals.values()) if vals else None


def state_traffic(m):
    r, w = num(m, "memory.state_read_bytes"), num(m, "memory.state_write_bytes")
    return r + w if r is not None and w is not None else None


def flip_mean(m):
    return num(m, "image.metrics.flip.mean")


def rmse(m):
    return num(m, "image.metrics.rmse")


def dram_utilisation(m):
    mean, peak = num(m, "memory.mean_gbps"), num(m, "memory.channel_peak_gbps")
    return mean / peak if mean is not None and peak else None


def memory_levels(m):
    """memory.levels (the memory-system work): [{name, hit_rate, ...}] by index."""
    levels = []
    i = 0
    while f"memory.levels.{i}.name" in m:
        levels.append({k[len(f"memory.levels.{i}."):]: v for k, v in m.items()
                       if k.startswith(f"memory.levels.{i}.")})
        i += 1
    return levels


def level_hit_rate(m, name):
    for lv in memory_levels(m):
        if lv.get("name") == name and isinstance(lv.get("hit_rate"), (int, float)):
            return float(lv["hit_rate"])
    return None


def phases_us(m):
    """Frame time by phase in us: [("opaque", us), ("transparent pass 1", us), ...,
    ("resolve", us)]. timing.phase_cycles when the report has it, else the phase
    ends of the partition that finished last."""
    mhz = num(m, "timing.clock_mhz")
    if not mhz:
        return None
    opaque, resolve = num(m, "timing.phase_cycles.opaque"), num(m, "timing.phase_cycles.resolve")
    passes = json_list(m, "timing.phase_cycles.transparent")
    if opaque is None or resolve is None or passes is None:
        ends = [(num(m, f"timing.per_partition.{i}.end_cycle"), i) for i in range(1024)
                if f"timing.per_partition.{i}.end_cycle" in m]
        if not ends:
            return None
        end, i = max(ends)
        o = num(m, f"timing.per_partition.{i}.opaque_end_cycle") or 0.0
        pass_ends = json_list(m, f"timing.per_partition.{i}.pass_end_cycles") or []
        passes, prev = [], o
        for e in pass_ends:
            passes.append(max(0.0, float(e) - prev))
            prev = float(e)
        opaque, resolve = o, max(0.0, end - prev)
    out = [("opaque", opaque / mhz)]
    for j, c in enumerate(passes):
        out.append((f"transparent pass {j + 1}" if len(passes) > 1 else "transparent", float(c) / mhz))
    out.append(("resolve", resolve / mhz))
    return out


def stall_shares(m):
    """{(stage, cause): share of the frame} = stall cycles summed over partitions
    / (cycles x partitions): the per-stage stalls scaled to frame time."""
    total = num(m, "timing.partition_cycles")
    if not total:
        return {}
    out = {}
    for s in STAGES:
        for c in STALL_CAUSES:
            v = num(m, f"timing.stages.{s}.stalls.{c}")
            if v:
                out[(s, c)] = v / total
    return out


def bound_by(m):
    """(what, share, measured): timing.bound_by when present; else the largest
    per-stage stall share (waiting on upstream, input_starved, is a symptom and
    left out), marked as a stall share."""
    res, share = m.get("timing.bound_by.resource"), num(m, "timing.bound_by.share")
    if isinstance(res, str) and share is not None:
        return res, share, "bound_by"
    shares = {k: v for k, v in stall_shares(m).items() if k[1] != "input_starved"}
    if not shares:
        return None
    (stage, cause), v = max(shares.items(), key=lambda kv: kv[1])
    return f"{stage}: {cause.replace('_', ' ')}", v, "stall share"


# --- hardware configurations --------------------------------------------------

def hardware_items(m):
    """The ROP parameters that describe the modelled machine (not the simulator's speed settings)."""
    return tuple(sorted((k[len("config.rop."):], json.dumps(v)) for k, v in m.items()
                        if k.startswith("config.rop.") and not k.startswith(SIM_PREFIXES) and k not in SIM_KEYS))


class Configs:
    """The sweep's hardware configurations, each named by its preset and the
    parameters that tell it apart from the others of that preset."""

    FUNCTIONAL = "functional model"

    def __init__(self, points):
        self.items = {}
        for p in points:
            if is_timing(p):
                self.items.setdefault(hardware_items(p["metrics"]), dict(hardware_items(p["metrics"])))
        by_preset = {}
        for key, d in self.items.items():
            by_preset.setdefault(json.loads(d.get("preset", '"?"')), []).append(key)
        self.labels = {}
        for preset, keys in by_preset.items():
            varying = sorted({k for key in keys for k, _ in key
                              if len({dict(other).get(k) for other in keys}) > 1})
            for key in keys:
                d = dict(key)
                extra = " ".join(f"{k}={json.loads(d[k])}" for k in varying if k in d)
                self.labels[key] = f"{preset} {extra}".strip()
        self.order = sorted(self.labels.values())

    def label(self, p):
        if not is_timing(p):
            return self.FUNCTIONAL
        return self.labels[hardware_items(p["metrics"])]

    def all_labels(self, points):
        present = {self.label(p) for p in points}
        return [c for c in self.order if c in present] + ([self.FUNCTIONAL] if self.FUNCTIONAL in present else [])

    def params(self, label):
        for key, lab in self.labels.items():
            if lab == label:
                return {k: json.loads(v) for k, v in key}
        return {}


def image_settings(p):
    """What besides algorithm and k decides a point's image (hardware does not:
    with lock.mode=ordered the timing model changes when, never what): format,
    bits, samples, weight, seed and background, where the algorithm uses them,
    and the insert order where the timing run drew the image."""
    m = p["metrics"]
    ignored = json_list(m, "config.ignored_settings") or []
    parts = []
    for key in ("format", "bits", "samples", "weight", "seed"):
        if key not in ignored and key != "layers" and m.get(f"config.{key}") is not None:
            parts.append(f"{key} {m.get(f'config.{key}')}")
    # With lock.mode unordered or none the timing run draws the image (its
    # order: lock entry or racing writes), so those images are kept apart.
    order = m.get("image.order")
    if order not in (None, "submission"):
        parts.append(f"order {order} ({m.get('lock.mode')})")
    bg = m.get("config.background")
    if bg not in (None, "[0.0,0.0,0.0]", "[0,0,0]"):
        parts.append(f"background {bg}")
    return ", ".join(parts)
