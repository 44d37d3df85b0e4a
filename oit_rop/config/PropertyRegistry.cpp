// The property registry's rows (PropertyRegistry.hpp): one per RopConfig
// field, with its path, range, unit and description.
#include "oit_rop/config/PropertyRegistry.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace oit::rop::config_registry {

std::string Property::allowed() const {
  switch (type) {
    case PropertyType::Bool: return "true | false";
    case PropertyType::Integer:
      return fmt::format("[{}, {}]{}", imin, imax, pow2 ? ", power of two" : "");
    case PropertyType::Float: return fmt::format("{}{}, {}]", fmin_open ? "(" : "[", fmin, fmax);
    case PropertyType::Enum: return fmt::format("{}", fmt::join(names, " | "));
  }
  return {};
}

namespace {

// ---- registry builders -----------------------------------------------------

Property base(std::string path, std::string unit, std::string desc) {
  Property p;
  p.path = std::move(path);
  p.unit = std::move(unit);
  p.description = std::move(desc);
  return p;
}

template <class Sec, class T>
Property integer(std::string path, Sec RopConfig::*sec, T Sec::*mem, uint64_t lo, uint64_t hi,
                 std::string unit, std::string desc, bool pow2 = false) {
  Property p = base(std::move(path), std::move(unit), std::move(desc));
  p.type = PropertyType::Integer;
  p.imin = lo;
  p.imax = std::min<uint64_t>(hi, std::numeric_limits<T>::max());
  p.pow2 = pow2;
  p.get = [=](const RopConfig& c) -> Value { return uint64_t((c.*sec).*mem); };
  p.put = [=](RopConfig& c, const Value& v) { (c.*sec).*mem = T(std::get<uint64_t>(v)); };
  return p;
}

template <class Sec>
Property real(std::string path, Sec RopConfig::*sec, double Sec::*mem, double lo, bool lo_open,
              double hi, std::string unit, std::string desc) {
  Property p = base(std::move(path), std::move(unit), std::move(desc));
  p.type = PropertyType::Float;
  p.fmin = lo;
  p.fmin_open = lo_open;
  p.fmax = hi;
  p.get = [=](const RopConfig& c) -> Value { return (c.*sec).*mem; };
  p.put = [=](RopConfig& c, const Value& v) { (c.*sec).*mem = std::get<double>(v); };
  return p;
}

template <class Sec>
Property boolean(std::string path, Sec RopConfig::*sec, bool Sec::*mem, std::string desc) {
  Property p = base(std::move(path), "", std::move(desc));
  p.type = PropertyType::Bool;
  p.get = [=](const RopConfig& c) -> Value { return (c.*sec).*mem; };
  p.put = [=](RopConfig& c, const Value& v) { (c.*sec).*mem = std::get<bool>(v); };
  return p;
}

// `names` in the enum's declaration order.
template <class Sec, class E>
Property enumeration(std::string path, Sec RopConfig::*sec, E Sec::*mem, std::vector<std::string> names,
                     std::string desc) {
  Property p = base(std::move(path), "", std::move(desc));
  p.type = PropertyType::Enum;
  p.names = names;
  p.get = [=](const RopConfig& c) -> Value { return names.at(size_t((c.*sec).*mem)); };
  p.put = [=](RopConfig& c, const Value& v) {
    const auto it = std::find(names.begin(), names.end(), std::get<std::string>(v));
    (c.*sec).*mem = E(it - names.begin());
  };
  return p;
}

constexpr double kInf = std::numeric_limits<double>::infinity();

}  // namespace

const std::vector<Property>& registry() {
  using R = RopConfig;
  static const std::vector<Property> props = {
      real("clock.core_mhz", &R::clock, &ClockConfig::core_mhz, 1, false, 10000, "MHz",
           "ROP / core clock; every cycle count is in this clock"),

      integer("partitions.count", &R::partitions, &PartitionConfig::count, 1, 64, "",
              "ROP partitions; screen tiles are interleaved over them"),
      integer("partitions.tile_width", &R::partitions, &PartitionConfig::tile_width, 1, 64, "pixels",
              "screen tile width; tiles are the unit of the partition interleave, HiZ, tile locks, fast clear and resolve", true),
      integer("partitions.tile_height", &R::partitions, &PartitionConfig::tile_height, 1, 64, "pixels",
              "screen tile height", true),

      real("input.fragments_per_clock", &R::input, &InputConfig::fragments_per_clock, 0.001, false, 1024,
           "fragments/clock", "fragments entering the pixel shader per clock, per partition"),
      enumeration("input.latency_model", &R::input, &InputConfig::latency_model, {"fixed", "uniform"},
                  "pixel-shader latency: fixed = latency_min, uniform in [latency_min, latency_max]"),
      integer("input.latency_min", &R::input, &InputConfig::latency_min, 1, 1000000, "cycles",
              "shortest pixel-shader latency"),
      integer("input.latency_max", &R::input, &InputConfig::latency_max, 1, 1000000, "cycles",
              "longest pixel-shader latency (uniform model)"),
      integer("input.warp_size", &R::input, &InputConfig::warp_size, 1, 1024, "fragments",
              "fragments that share one pixel-shader latency draw (uniform model): consecutive trace fragments "
              "(by sequence number) form a warp; 1 = every fragment draws its own",
              true),
      integer("input.seed", &R::input, &InputConfig::seed, 0, std::numeric_limits<uint64_t>::max(), "",
              "seed of the shader-latency distribution"),

      boolean("early_depth.enabled", &R::early_depth, &EarlyDepthConfig::enabled,
              "cull transparent fragments at/behind the opaque depth before the lock"),
      boolean("early_depth.hierarchical", &R::early_depth, &EarlyDepthConfig::hierarchical,
              "per-tile max opaque depth culls without reading the depth buffer"),
      integer("early_depth.latency", &R::early_depth, &EarlyDepthConfig::latency, 1, 10000, "cycles",
              "depth-test latency"),

      integer("lock.capacity", &R::lock, &LockConfig::capacity, 1, 1u << 20, "fragments",
              "scoreboard entries per partition: fragments between issue and lock release"),
      enumeration("lock.granularity", &R::lock, &LockConfig::granularity, {"pixel", "quad", "tile"},
                  "interlock scope: one pixel, a 2x2 quad or a whole screen tile"),
      enumeration("lock.mode", &R::lock, &LockConfig::mode, {"ordered", "unordered", "none"},
                  "ordered: a lock address's fragments enter in submission order (ROV, PixelSync), the image is "
                  "the functional model's; unordered: one at a time in the order they reach the lock, the image "
                  "follows that order; none: no interlock, racing read-modify-writes lose updates (counted); "
                  "unordered and none need sim.engine=cycle (DESIGN.md)"),
      boolean("lock.per_primitive", &R::lock, &LockConfig::per_primitive,
              "quad/tile granularity: the fragments of one primitive take the lock together (they never overlap "
              "each other); false = each waits for every older fragment of its quad/tile (an upper bound)"),
      enumeration("lock.release", &R::lock, &LockConfig::release, {"end_of_blend", "end_of_shader"},
                  "release at the end of the critical section, or of the shader (INTEL ordering)"),
      integer("lock.shader_tail", &R::lock, &LockConfig::shader_tail, 0, 1000000, "cycles",
              "end of blend to end of shader (release = end_of_shader)"),

      integer("cache.size_bytes", &R::cache, &CacheConfig::size_bytes, 1024, uint64_t(1) << 30, "bytes",
              "the ROP's blending-array cache, per partition"),
      integer("cache.ways", &R::cache, &CacheConfig::ways, 1, 64, "", "cache associativity (LRU)"),
      integer("cache.miss_queue", &R::cache, &CacheConfig::miss_queue, 1, 4096, "lines",
              "outstanding line fills per partition (one entry per missing line)"),
      integer("cache.hit_latency", &R::cache, &CacheConfig::hit_latency, 1, 10000, "cycles", "cache hit latency"),
      integer("cache.line_bytes", &R::cache, &CacheConfig::line_bytes, 32, 1024, "bytes",
              "cache line (one tag); a fragment touches the lines holding the bytes its insert reads and writes",
              true),
      integer("cache.sector_bytes", &R::cache, &CacheConfig::sector_bytes, 0, 1024, "bytes",
              "fill and write-back unit inside a line (valid and dirty per sector); 0 = the whole line"),

      enumeration("memory.array_layout", &R::memory, &MemoryLayoutConfig::array_layout, {"pixel_major", "row_major"},
                  "per-pixel arrays of a tile in memory: pixel_major = each pixel's array contiguous, pixels in "
                  "tile order; row_major = row i of every pixel of the tile contiguous (MEMORY.md)"),

      integer("l2.size_bytes", &R::l2, &SharedCacheConfig::size_bytes, 0, uint64_t(1) << 32, "bytes",
              "shared cache between every partition and DRAM (or the l3); 0 = none"),
      integer("l2.ways", &R::l2, &SharedCacheConfig::ways, 1, 64, "", "l2 associativity per slice (LRU)"),
      integer("l2.line_bytes", &R::l2, &SharedCacheConfig::line_bytes, 32, 4096, "bytes", "l2 cache line", true),
      integer("l2.sector_bytes", &R::l2, &SharedCacheConfig::sector_bytes, 0, 4096, "bytes",
              "l2 fill and write-back unit inside a line; 0 = the whole line"),
      integer("l2.slices", &R::l2, &SharedCacheConfig::slices, 1, 256, "",
              "l2 slices: lines are spread over them by an address hash; each slice has its own port"),
      integer("l2.hit_latency", &R::l2, &SharedCacheConfig::hit_latency, 1, 100000, "cycles",
              "l2 hit latency (request to data, unloaded)"),
      real("l2.bytes_per_clock", &R::l2, &SharedCacheConfig::bytes_per_clock, 0.01, false, 4096, "bytes/clock",
           "l2 port bandwidth per slice, in core clocks"),
      boolean("l2.victim_only", &R::l2, &SharedCacheConfig::victim_only,
              "l2 is filled only with the evictions of the level above (a victim cache); reads that miss it do "
              "not allocate"),
      integer("l3.size_bytes", &R::l3, &SharedCacheConfig::size_bytes, 0, uint64_t(1) << 32, "bytes",
              "a further shared level of the same kind behind the l2; 0 = none"),
      integer("l3.ways", &R::l3, &SharedCacheConfig::ways, 1, 64, "", "l3 associativity per slice (LRU)"),
      integer("l3.line_bytes", &R::l3, &SharedCacheConfig::line_bytes, 32, 4096, "bytes", "l3 cache line", true),
      integer("l3.sector_bytes", &R::l3, &SharedCacheConfig::sector_bytes, 0, 4096, "bytes",
              "l3 fill and write-back unit inside a line; 0 = the whole line"),
      integer("l3.slices", &R::l3, &SharedCacheConfig::slices, 1, 256, "",
              "l3 slices: lines are spread over them by an address hash; each slice has its own port"),
      integer("l3.hit_latency", &R::l3, &SharedCacheConfig::hit_latency, 1, 100000, "cycles",
              "l3 hit latency (request to data, unloaded)"),
      real("l3.bytes_per_clock", &R::l3, &SharedCacheConfig::bytes_per_clock, 0.01, false, 4096, "bytes/clock",
           "l3 port bandwidth per slice, in core clocks"),
      boolean("l3.victim_only", &R::l3, &SharedCacheConfig::victim_only,
              "l3 is filled only with the evictions of the level above (a victim cache); reads that miss it do "
              "not allocate"),

      integer("alu.blends_per_clock", &R::alu, &AluConfig::blends_per_clock, 1, 1024, "blends/clock",
              "RGBA8-rate blend inserts per clock, per partition"),
      integer("alu.base_latency", &R::alu, &AluConfig::base_latency, 1, 10000, "cycles",
              "latency of one insert"),
      integer("alu.cycles_per_compare", &R::alu, &AluConfig::cycles_per_compare, 0, 10000, "cycles",
              "extra latency per row (node, layer, sample) whose depth an insert compares with the fragment's, "
              "as the functional insert reports it (ALGORITHMS.md, work per insert) [inferred]"),
      integer("alu.cycles_per_row_moved", &R::alu, &AluConfig::cycles_per_row_moved, 0, 10000, "cycles",
              "extra latency per row an insert writes: the new row, rows shifted or rescaled behind it, a merged "
              "row, an accumulator [inferred]"),
      real("alu.fp16_rate", &R::alu, &AluConfig::fp16_rate, 0.001, false, 1, "",
           "fp16-row blend throughput relative to 8-bit rows [inferred]"),
      real("alu.fp32_rate", &R::alu, &AluConfig::fp32_rate, 0.001, false, 1, "",
           "fp32-row blend throughput relative to 8-bit rows [inferred]"),

      integer("abuffer.pool_bytes", &R::abuffer, &ABufferConfig::pool_bytes, 0, std::numeric_limits<uint64_t>::max(),
              "bytes",
              "algorithm abuffer: its whole allocation, heads (4 B per pixel) + node pool, whatever the scene; "
              "fragments past the pool are dropped (fragments.dropped_pool_full); 0 = heads + "
              "abuffer.nodes_per_pixel nodes per pixel"),
      real("abuffer.nodes_per_pixel", &R::abuffer, &ABufferConfig::nodes_per_pixel, 0, true, 1e6, "nodes",
           "algorithm abuffer, abuffer.pool_bytes = 0: pool nodes per pixel of the frame, as applications size "
           "the pool by the screen [inferred]"),
      integer("abuffer.max_sorted", &R::abuffer, &ABufferConfig::max_sorted, 1, 1u << 20, "nodes",
              "algorithm abuffer: the resolve's local array (the shader's register budget): nodes per pixel "
              "loaded and sorted [inferred]"),
      enumeration("abuffer.overflow", &R::abuffer, &ABufferConfig::overflow, {"spill", "truncate"},
                  "algorithm abuffer, a list longer than max_sorted: spill = sort it all (exact image, "
                  "spill_cycles_per_node per node beyond), truncate = composite the first max_sorted nodes of the "
                  "list (the newest) only"),
      real("abuffer.atomics_per_clock", &R::abuffer, &ABufferConfig::atomics_per_clock, 0, true, 1024,
           "atomics/clock",
           "algorithm abuffer: increments of the global node counter per clock for the whole GPU, shared by all "
           "partitions [inferred]"),
      integer("abuffer.atomic_latency", &R::abuffer, &ABufferConfig::atomic_latency, 0, 100000, "cycles",
              "algorithm abuffer: one node-counter atomic, issue to returned index [inferred]"),
      integer("abuffer.sort_cycles_per_compare", &R::abuffer, &ABufferConfig::sort_cycles_per_compare, 0, 10000,
              "cycles", "algorithm abuffer: resolve's insertion sort, per compare [inferred]"),
      integer("abuffer.sort_cycles_per_move", &R::abuffer, &ABufferConfig::sort_cycles_per_move, 0, 10000,
              "cycles", "algorithm abuffer: resolve's insertion sort, per element moved [inferred]"),
      integer("abuffer.spill_cycles_per_node", &R::abuffer, &ABufferConfig::spill_cycles_per_node, 0, 1000000,
              "cycles", "algorithm abuffer, overflow = spill: per node beyond max_sorted [inferred]"),

      integer("dram.channels", &R::dram, &DramConfig::channels, 1, 64, "", "DRAM channels (shared by all partitions)"),
      real("dram.channel_gbps", &R::dram, &DramConfig::channel_gbps, 0.1, false, 10000, "GB/s",
           "peak bandwidth per channel"),
      real("dram.tck_ns", &R::dram, &DramConfig::tck_ns, 0, true, 100, "ns", "DRAM command clock period"),
      integer("dram.cl", &R::dram, &DramConfig::cl, 1, 255, "tCK", "CAS latency"),
      integer("dram.trcd", &R::dram, &DramConfig::trcd, 1, 255, "tCK", "activate to read/write"),
      integer("dram.trp", &R::dram, &DramConfig::trp, 1, 255, "tCK", "precharge time"),
      integer("dram.tras", &R::dram, &DramConfig::tras, 0, 255, "tCK",
              "activate to precharge: a row stays open at least this long (0 = no limit)"),
      integer("dram.trrd", &R::dram, &DramConfig::trrd, 0, 255, "tCK",
              "activate to activate on one channel (different banks; one rank per channel): a row miss or "
              "closed-page run waits for it (0 = no limit)"),
      integer("dram.tfaw", &R::dram, &DramConfig::tfaw, 0, 255, "tCK",
              "four-activate window: at most four activates per channel in any tFAW (0 = none; else at least "
              "4 x dram.trrd)"),
      integer("dram.twtr", &R::dram, &DramConfig::twtr, 0, 255, "tCK",
              "write-to-read turnaround: end of write data to the next read command on the channel; the read's "
              "data follows CL later, so the bus idles tWTR + CL at each switch from writes to reads"),
      integer("dram.trtw", &R::dram, &DramConfig::trtw, 0, 255, "tCK",
              "read-to-write turnaround: idle data bus between read data and the next write data"),
      integer("dram.banks", &R::dram, &DramConfig::banks, 1, 256, "", "banks per channel"),
      integer("dram.bank_groups", &R::dram, &DramConfig::bank_groups, 1, 64, "",
              "bank groups per channel (GDDR5/GDDR6: 4; 1 = none, as DDR3): a power of two dividing dram.banks; "
              "group = bank mod bank_groups, after dram.bank_hash",
              true),
      integer("dram.tccd_s", &R::dram, &DramConfig::tccd_s, 0, 255, "tCK",
              "column command to column command on the channel, other bank groups (0 = the burst's bus time, as "
              "in the presets: tCCD_S = BL / data beats per tCK)"),
      integer("dram.tccd_l", &R::dram, &DramConfig::tccd_l, 0, 255, "tCK",
              "column to column in one bank group: a row-hit stream to one group moves a burst per tCCD_L "
              "(0 = no distinction; else at least dram.tccd_s; needs dram.bank_groups > 1)"),
      integer("dram.trrd_l", &R::dram, &DramConfig::trrd_l, 0, 255, "tCK",
              "activate to activate in one bank group; dram.trrd holds between groups (0 = no distinction; else "
              "at least dram.trrd; needs dram.bank_groups > 1)"),
      integer("dram.twtr_l", &R::dram, &DramConfig::twtr_l, 0, 255, "tCK",
              "write-to-read turnaround in one bank group: end of a group's write data to a read command to the "
              "group; dram.twtr holds for the channel (0 = no distinction; else at least dram.twtr; needs "
              "dram.bank_groups > 1)"),
      integer("dram.row_bytes", &R::dram, &DramConfig::row_bytes, 64, 1u << 20, "bytes",
              "row-buffer size per bank (across the channel's chips)", true),
      integer("dram.burst_bytes", &R::dram, &DramConfig::burst_bytes, 8, 4096, "bytes",
              "access granularity (one burst)", true),
      integer("dram.interleave_bytes", &R::dram, &DramConfig::interleave_bytes, 8, 1u << 20, "bytes",
              "consecutive bytes on one channel before the next", true),
      boolean("dram.open_row", &R::dram, &DramConfig::open_row,
              "keep rows open: row hits pay CL only; false = closed page: one activate per request's run of "
              "bursts in a row, auto-precharge after it"),
      boolean("dram.bank_hash", &R::dram, &DramConfig::bank_hash,
              "bank = bank bits XOR every bank-sized group of row bits (permutation interleaving), so "
              "streams in far-apart regions fall in different banks; false = the plain row-bank-column map"),
      real("dram.controller_ns", &R::dram, &DramConfig::controller_ns, 0, false, 100000, "ns",
           "fixed controller + interconnect latency added to every access [inferred]"),
      real("dram.trefi_ns", &R::dram, &DramConfig::trefi_ns, 0, false, 1000000, "ns",
           "refresh interval: each channel refreshes all its banks once per tREFI (channels staggered); 0 = no "
           "refresh"),
      real("dram.trfc_ns", &R::dram, &DramConfig::trfc_ns, 0, false, 100000, "ns",
           "refresh cycle time: for tRFC the channel moves no data, and its open rows are closed after it"),
      enumeration("dram.scheduler", &R::dram, &DramConfig::scheduler, {"fcfs", "frfcfs"},
                  "read scheduling: fcfs = first come first served; frfcfs = a read whose data can go earlier takes "
                  "bus time the older reads leave idle (their precharge, activate, turnaround), never moving them"),
      integer("dram.queue_depth", &R::dram, &DramConfig::queue_depth, 1, 4096, "bursts",
              "FR-FCFS window per channel: a read may pass at most this many bursts of older requests "
              "(1 = fcfs)"),
      integer("dram.write_queue", &R::dram, &DramConfig::write_queue, 1, 4096, "bursts",
              "posted-write entries per channel: a write burst holds one from its acceptance until its data is on "
              "the bus; a full queue makes the writer wait"),
      integer("dram.write_high", &R::dram, &DramConfig::write_high, 1, 4096, "bursts",
              "high watermark: when this many write bursts wait on a channel, its controller drains writes in a "
              "batch (reads go first otherwise); write_high = 1, write_low = 0 writes every write at once"),
      integer("dram.write_low", &R::dram, &DramConfig::write_low, 0, 4095, "bursts",
              "low watermark: a batch stops once at most this many write bursts wait (whole rows of the oldest "
              "writes are drained)"),

      integer("stats.interval_cycles", &R::stats, &StatsConfig::interval_cycles, 1,
              std::numeric_limits<uint64_t>::max(), "cycles", "time-series sample period"),
      integer("stats.max_samples", &R::stats, &StatsConfig::max_samples, 2, 1u << 24, "",
              "time-series length limit: on reaching it, pairs of samples merge and the period doubles "
              "(even; an odd value counts as the next lower even one)"),
      boolean("stats.miss_classes", &R::stats, &StatsConfig::miss_classes,
              "classify the ROP cache's misses as compulsory, capacity or conflict (a fully associative shadow "
              "cache, updated on every line access; the shared levels': stats.level_miss_classes)"),
      boolean("stats.level_miss_classes", &R::stats, &StatsConfig::level_miss_classes,
              "classify the shared levels' (l2, l3) misses as well (a fully associative shadow of each level's "
              "lines, 2 M for a 128 MB l3: 28 % of the approximate engine's time on the bench trace, "
              "bench/RESULTS-timing.md; off, their report says miss_classes false and gives no split)"),

      boolean("skip.early_depth", &R::skip, &SkipConfig::early_depth,
              "culled fragments skip lock and cache (else they pass through both)"),
      boolean("skip.fast_clear", &R::skip, &SkipConfig::fast_clear,
              "untouched tiles are neither read from DRAM, cleared nor resolved"),
      boolean("skip.lazy_merge", &R::skip, &SkipConfig::lazy_merge, "no merge work while a pixel's array is not full"),
      boolean("skip.idle_cycles", &R::skip, &SkipConfig::idle_cycles,
              "the simulator jumps over cycles where nothing can move"),

      // At most 100000: the shared levels' port calendars and the node counter
      // keep rings of a power of two >= 2 x their lookback (2 x quantum +
      // 4096) cycles, 4 bytes a cycle per port and 8 for the counter: at
      // 100000 2 and 4 MiB; at 10^9 16 GiB per l2 slice, which the memory
      // pre-check did not count.
      integer("sim.quantum_cycles", &R::sim, &SimConfig::quantum_cycles, 1, 100000, "cycles",
              "tlm_quantumkeeper quantum: partitions may run this far apart, which changes how their DRAM "
              "requests interleave (1 = lockstep; DESIGN.md)"),
      enumeration("sim.engine", &R::sim, &SimConfig::engine, {"cycle", "approximate"},
                  "cycle: every stage evaluated on each cycle where one can move (the reference); approximate "
                  "(experimental, lock.mode=ordered only): each fragment visited once, its stage times computed from the resources' free "
                  "times; same image and counts; its speed in bench/RESULTS-timing.md, its frame cycles against "
                  "the cycle engine's in DESIGN.md"),
  };
  return props;
}

}  // namespace oit::rop::config_registry
