// The property registry: one row per RopConfig field, bound by member pointers
// so the tree and the struct cannot drift apart silently (tests/oit_rop/
// test_config.cpp counts each section's fields against the registry).
#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/memory/DramTimings.hpp"
#include "oit_rop/config/RepeatedKeys.hpp"
#include "traces/InputFile.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <stdexcept>
#include <variant>

namespace oit::rop {
namespace {

using Value = std::variant<bool, uint64_t, double, std::string>;

struct Property {
  std::string path, unit, description;
  PropertyType type = PropertyType::Integer;
  uint64_t imin = 0, imax = std::numeric_limits<uint64_t>::max();
  bool pow2 = false;
  double fmin = 0, fmax = 0;
  bool fmin_open = false;  // (fmin, fmax] instead of [fmin, fmax]
  std::vector<std::string> names;  // Enum
  std::function<Value(const RopConfig&)> get;
  std::function<void(RopConfig&, const Value&)> put;

  std::string allowed() const {
    switch (type) {
      case PropertyType::Bool: return "true | false";
      case PropertyType::Integer:
        return fmt::format("[{}, {}]{}", imin, imax, pow2 ? ", power of two" : "");
      case PropertyType::Float: return fmt::format("{}{}, {}]", fmin_open ? "(" : "[", fmin, fmax);
      case PropertyType::Enum: return fmt::format("{}", fmt::join(names, " | "));
    }
    return {};
  }
};

std::string formatValue(const Value& v) {
  struct {
    std::string operator()(bool b) const { return b ? "true" : "false"; }
    std::string operator()(uint64_t u) const { return std::to_string(u); }
    std::string operator()(double d) const { return fmt::format("{}", d); }  // shortest round-trip
    std::string operator()(const std::string& s) const { return s; }
  } f;
  return std::visit(f, v);
}

nlohmann::json jsonValue(const Value& v) {
  return std::visit([](const auto& x) { return nlohmann::json(x); }, v);
}

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
      integer("dram.twtr", &R::dram, &DramConfig::twtr, 0, 255, "tCK",
              "write-to-read turnaround: end of write data to the next read command on the channel; the read's "
              "data follows CL later, so the bus idles tWTR + CL at each switch from writes to reads"),
      integer("dram.trtw", &R::dram, &DramConfig::trtw, 0, 255, "tCK",
              "read-to-write turnaround: idle data bus between read data and the next write data"),
      integer("dram.banks", &R::dram, &DramConfig::banks, 1, 256, "", "banks per channel"),
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

      integer("sim.quantum_cycles", &R::sim, &SimConfig::quantum_cycles, 1, 1000000000, "cycles",
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

const Property* find(std::string_view path) {
  for (const auto& p : registry())
    if (p.path == path) return &p;
  return nullptr;
}

size_t editDistance(std::string_view a, std::string_view b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diag = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diag + (a[i - 1] == b[j - 1] ? 0 : 1)});
      diag = up;
    }
  }
  return row[b.size()];
}

// Properties that were replaced: setting one is an error naming its successor.
struct Retired {
  std::string_view path, message;
};
constexpr Retired kRetired[] = {
    {"lock.ordered",
     "'lock.ordered' was replaced by lock.mode (ordered | unordered | none): lock.ordered=true is "
     "lock.mode=ordered; lock.ordered=false is lock.mode=unordered, whose image now follows the order the "
     "fragments enter the lock (oit_rop/DESIGN.md)"},
};

[[noreturn]] void unknownPath(std::string_view path) {
  for (const Retired& r : kRetired)
    if (r.path == path) throw std::invalid_argument(std::string(r.message));
  // A group name ("lock") lists its properties.
  std::vector<std::string> members;
  const std::string prefix = std::string(path) + ".";
  for (const auto& p : registry())
    if (p.path.starts_with(prefix)) members.push_back(p.path);
  if (!members.empty())
    throw std::invalid_argument(fmt::format("'{}' is a group, not a property; its properties: {}", path,
                                            fmt::join(members, ", ")));
  // Closest full path; a bare leaf name ("granularity") matches its full path exactly.
  const Property* best = nullptr;
  size_t best_d = std::numeric_limits<size_t>::max();
  for (const auto& p : registry()) {
    const std::string_view leaf = std::string_view(p.path).substr(p.path.rfind('.') + 1);
    const size_t d = std::min(editDistance(path, p.path), leaf == path ? 0 : editDistance(path, leaf) + 2);
    if (d < best_d) best_d = d, best = &p;
  }
  if (best && best_d <= std::max<size_t>(3, path.size() / 3))
    throw std::invalid_argument(fmt::format("unknown property '{}'; did you mean '{}'?", path, best->path));
  throw std::invalid_argument(fmt::format(
      "unknown property '{}'; groups: clock, partitions, input, early_depth, lock, cache, alu, dram, stats, "
      "skip, sim (`oitsim config` lists every property)",
      path));
}

std::string expected(const Property& p) {
  const char* what = p.type == PropertyType::Bool      ? "a boolean"
                     : p.type == PropertyType::Integer ? "an integer"
                     : p.type == PropertyType::Float   ? "a number"
                                                       : "one of";
  return p.unit.empty() ? fmt::format("{} {}", what, p.allowed())
                        : fmt::format("{} {} ({})", what, p.allowed(), p.unit);
}

[[noreturn]] void badValue(const Property& p, std::string_view value, std::string_view why) {
  throw std::invalid_argument(
      fmt::format("{}: '{}' {}; expected {}", p.path, value, why, expected(p)));
}

// Range checks shared by text and JSON input; `shown` is the value as given.
Value checked(const Property& p, Value v, std::string_view shown) {
  if (p.type == PropertyType::Integer) {
    const uint64_t u = std::get<uint64_t>(v);
    if (u < p.imin || u > p.imax) badValue(p, shown, "is out of range");
    if (p.pow2 && !std::has_single_bit(u)) badValue(p, shown, "is not a power of two");
  } else if (p.type == PropertyType::Float) {
    const double d = std::get<double>(v);
    if (!std::isfinite(d)) badValue(p, shown, "is not a finite number");
    if (d < p.fmin || (p.fmin_open && d == p.fmin) || d > p.fmax) badValue(p, shown, "is out of range");
  } else if (p.type == PropertyType::Enum) {
    if (std::find(p.names.begin(), p.names.end(), std::get<std::string>(v)) == p.names.end())
      badValue(p, shown, "is not a known value");
  }
  return v;
}

Value parseText(const Property& p, std::string_view text) {
  std::string_view s = text;
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
  while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
  if (s.empty()) badValue(p, text, "is empty");
  switch (p.type) {
    case PropertyType::Bool: {
      std::string l(s);
      std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return char(std::tolower(c)); });
      if (l == "true" || l == "on" || l == "yes" || l == "1") return true;
      if (l == "false" || l == "off" || l == "no" || l == "0") return false;
      badValue(p, text, "is not a boolean");
    }
    case PropertyType::Integer: {
      uint64_t u = 0;
      const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), u);
      if (ec == std::errc::result_out_of_range) badValue(p, text, "is out of range");
      if (ec != std::errc() || end == s.data()) badValue(p, text, "is not a non-negative integer");
      std::string_view suffix(end, size_t(s.data() + s.size() - end));
      uint64_t scale = 1;
      // Sizes in bytes read naturally as 64KiB or 2MiB.
      if (!suffix.empty() && p.unit == "bytes") {
        if (suffix == "KiB" || suffix == "K") scale = uint64_t(1) << 10;
        else if (suffix == "MiB" || suffix == "M") scale = uint64_t(1) << 20;
        else if (suffix == "GiB" || suffix == "G") scale = uint64_t(1) << 30;
        else if (suffix != "B") badValue(p, text, "has an unknown suffix (use B, KiB, MiB or GiB)");
      } else if (!suffix.empty()) {
        badValue(p, text, "is not a non-negative integer");
      }
      if (u > std::numeric_limits<uint64_t>::max() / scale) badValue(p, text, "is out of range");
      return checked(p, u * scale, text);
    }
    case PropertyType::Float: {
      double d = 0;
      const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), d);
      if (ec == std::errc::result_out_of_range && end == s.data() + s.size()) badValue(p, text, "is out of range");
      if (ec != std::errc() || end != s.data() + s.size()) badValue(p, text, "is not a number");
      return checked(p, d, text);
    }
    case PropertyType::Enum: return checked(p, std::string(s), text);
  }
  return {};
}

Value parseJson(const Property& p, const nlohmann::json& j) {
  if (j.is_string()) return parseText(p, j.get<std::string>());
  const std::string shown = j.dump();
  switch (p.type) {
    case PropertyType::Bool:
      if (j.is_boolean()) return j.get<bool>();
      break;
    case PropertyType::Integer:
      if (j.is_number_unsigned()) return checked(p, j.get<uint64_t>(), shown);
      if (j.is_number_integer()) badValue(p, shown, "is out of range");  // negative
      if (j.is_number_float()) {
        const double d = j.get<double>();
        // 65536.0 is an integer; 1e30 or 2.5 are not.
        if (d >= 0 && d < 18446744073709551616.0 && std::floor(d) == d) return checked(p, uint64_t(d), shown);
        // A whole number past 2^64 - 1 (JSON reads it as a double) is a range error.
        if (d >= 18446744073709551616.0 && std::isfinite(d) && std::floor(d) == d) badValue(p, shown, "is out of range");
        badValue(p, shown, "is not a non-negative integer");
      }
      break;
    case PropertyType::Float:
      if (j.is_number()) return checked(p, j.get<double>(), shown);
      break;
    case PropertyType::Enum: break;
  }
  badValue(p, shown, fmt::format("has the wrong JSON type ({})", j.type_name()));
}

}  // namespace

std::string approximateLockModeProblem(LockMode mode) {
  return fmt::format(
      "lock.mode={} is not modelled by sim.engine=approximate (it visits fragments in submission order, so it "
      "cannot apply inserts in lock-entry order or race them); use sim.engine=cycle or lock.mode=ordered",
      lockModeName(mode));
}

const char* lockModeName(LockMode m) {
  switch (m) {
    case LockMode::Ordered: return "ordered";
    case LockMode::Unordered: return "unordered";
    case LockMode::None: return "none";
  }
  return "?";
}

const char* toString(PropertyType t) {
  switch (t) {
    case PropertyType::Bool: return "bool";
    case PropertyType::Integer: return "integer";
    case PropertyType::Float: return "float";
    case PropertyType::Enum: return "enum";
  }
  return "?";
}

ConfigTree::ConfigTree(RopConfig preset_cfg) : cfg_(preset_cfg), defaults_(std::move(preset_cfg)) {}

ConfigTree ConfigTree::forPreset(std::string_view name) { return ConfigTree(presetConfig(name)); }

void ConfigTree::set(std::string_view path, std::string_view value) {
  const Property* p = find(path);
  if (!p) {
    if (path == "preset")
      throw std::invalid_argument("'preset' is not a property: choose it with --preset or a file's \"preset\" key");
    unknownPath(path);
  }
  p->put(cfg_, parseText(*p, value));
}

void ConfigTree::setJson(std::string_view path, const nlohmann::json& value) {
  const Property* p = find(path);
  if (!p) unknownPath(path);
  p->put(cfg_, parseJson(*p, value));
}

void ConfigTree::applyJson(const nlohmann::json& j, const std::string& origin) {
  if (!j.is_object())
    throw std::invalid_argument(fmt::format("{}: expected a JSON object, found {}", origin, j.type_name()));
  std::map<std::string, std::string> seen;  // property path -> key as written
  std::function<void(const nlohmann::json&, const std::string&)> walk = [&](const nlohmann::json& obj,
                                                                            const std::string& prefix) {
    for (const auto& [key, val] : obj.items()) {
      const std::string path = prefix.empty() ? key : prefix + "." + key;
      const std::string shown = prefix.empty() ? key : prefix + "/" + key;  // where it sits in the file
      if (prefix.empty() && key == "preset") {
        if (!val.is_string() || canonicalPresetName(val.get<std::string>()) != cfg_.preset)
          throw std::invalid_argument(fmt::format(
              "{}: key 'preset': the file is for preset {} but the tree was built from preset '{}'; pass "
              "--preset {} (or drop the key)",
              origin, val.dump(), cfg_.preset, val.is_string() ? val.get<std::string>() : "NAME"));
        continue;
      }
      if (val.is_object() && !find(path)) {
        walk(val, path);
        continue;
      }
      try {
        if (val.is_null() || val.is_array() || val.is_object())
          throw std::invalid_argument(fmt::format("{}: expected {}, found a JSON {}", path,
                                                  find(path) ? expected(*find(path)) : "a value", val.type_name()));
        const auto [it, fresh] = seen.emplace(path, shown);
        if (!fresh)
          throw std::invalid_argument(fmt::format("{} is given twice (also as '{}')", path, it->second));
        setJson(path, val);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument(fmt::format("{}: key '{}': {}", origin, shown, e.what()));
      }
    }
  };
  walk(j, "");
}

namespace {

// Far above any real configuration (a few KiB): a larger file is not one.
constexpr uint64_t kMaxConfigFileBytes = uint64_t{16} << 20;

// Reads a config file (JSON, comments allowed). Every error names the file:
// syntax errors with nlohmann's line and column, number overflow (1e400) and a
// key repeated within one object (JSON parsers keep the last silently).
nlohmann::json readConfigFile(const std::string& file) {
  // A regular file only, opened without blocking (a FIFO would hang, a device
  // never end, a directory gave "basic_filebuf::underflow error").
  const InputFile in = openInputFile(file);
  if (!in && in.error != 0) throw std::invalid_argument(fmt::format("{}: cannot open config file", file));
  if (!in) throw std::invalid_argument(fmt::format("{}: {} (expected a JSON config file)", file, in.problem));
  std::string text, problem;
  if (!readAll(in, kMaxConfigFileBytes, text, problem))
    throw std::invalid_argument(fmt::format("{}: config file {}", file, problem));
  const auto cb = refuseRepeatedKeys<nlohmann::json>(
      [&](const std::string& key) {
        throw std::invalid_argument(fmt::format(
            "{}: key '{}' appears twice in the same JSON object (the second would silently replace the first); "
            "give each key once",
            file, key));
      },
      KeyPath::Slashed);
  try {
    return nlohmann::json::parse(text, cb, true, /*ignore_comments=*/true);
  } catch (const nlohmann::json::exception& e) {  // parse_error (with line, column), out_of_range.406 ...
    throw std::invalid_argument(fmt::format("{}: not valid JSON: {}", file, e.what()));
  }
}

}  // namespace

void ConfigTree::loadJson(const std::string& file) { applyJson(readConfigFile(file), file); }

void ConfigTree::validate() const {
  std::vector<std::string> errs;
  const RopConfig& c = cfg_;
  if (c.input.latency_model == LatencyModel::Uniform && c.input.latency_min > c.input.latency_max)
    errs.push_back(fmt::format("input.latency_min ({}) > input.latency_max ({}) with the uniform latency model",
                               c.input.latency_min, c.input.latency_max));
  // A 2x2 quad must lie inside one tile (tile sizes are powers of two, so at
  // least 2 suffices): tiles are interleaved over the
  // partitions, each with its own scoreboard, so a quad straddling two tiles
  // would be locked in parts (audit: 1x1 tiles gave pixel-granularity waits).
  if (c.lock.granularity == LockGranularity::Quad &&
      (c.partitions.tile_width < 2 || c.partitions.tile_height < 2))
    errs.push_back(fmt::format(
        "lock.granularity quad needs partitions.tile_width and tile_height of at least 2 (now {} x {}): a 2x2 quad "
        "across two tiles would be split over partitions and locked in parts",
        c.partitions.tile_width, c.partitions.tile_height));
  // The ROP cache: lines hold whole sectors, the cache whole sets of lines.
  const auto sectorProblems = [&](const std::string& n, unsigned line, unsigned sector) {
    if (sector == 0) return;
    if (sector > line || line % sector != 0 || (sector & (sector - 1)) != 0)
      errs.push_back(fmt::format("{0}.sector_bytes ({1}) must be a power of two dividing {0}.line_bytes ({2})", n,
                                 sector, line));
    else if (line / sector > 32)
      errs.push_back(fmt::format("{0}.line_bytes ({1}) holds {2} sectors of {0}.sector_bytes ({3}); at most 32 are "
                                 "modelled (valid and dirty masks of 32 bits)",
                                 n, line, line / sector, sector));
    if (sector != 0 && sector < 8)
      errs.push_back(fmt::format("{}.sector_bytes ({}) must be at least 8 (or 0, the whole line)", n, sector));
  };
  if (c.cache.line_bytes > c.cache.size_bytes)
    errs.push_back(fmt::format("cache.line_bytes ({}) is larger than the cache, cache.size_bytes ({})",
                               c.cache.line_bytes, c.cache.size_bytes));
  else if (c.cache.size_bytes % (uint64_t(c.cache.ways) * c.cache.line_bytes) != 0)
    errs.push_back(fmt::format(
        "cache.size_bytes ({}) is not a multiple of cache.ways x cache.line_bytes ({} x {} = {}): every set holds "
        "whole lines",
        c.cache.size_bytes, c.cache.ways, c.cache.line_bytes, uint64_t(c.cache.ways) * c.cache.line_bytes));
  sectorProblems("cache", c.cache.line_bytes, c.cache.sector_bytes);
  // The shared levels: l3 behind l2, lines no smaller than the level above's
  // (a line above must fit in one line below).
  const auto levelProblems = [&](const std::string& n, const SharedCacheConfig& l, const std::string& above,
                                 unsigned above_line) {
    if (l.size_bytes == 0) return;
    if (l.line_bytes < above_line)
      errs.push_back(fmt::format("{}.line_bytes ({}) is smaller than {}.line_bytes ({}): a line of the level above "
                                 "must fit in one {} line",
                                 n, l.line_bytes, above, above_line, n));
    const uint64_t set_bytes = uint64_t(l.ways) * l.line_bytes * l.slices;
    if (l.line_bytes > l.size_bytes)
      errs.push_back(
          fmt::format("{}.line_bytes ({}) is larger than the cache, {}.size_bytes ({})", n, l.line_bytes, n, l.size_bytes));
    else if (l.size_bytes % set_bytes != 0)
      errs.push_back(fmt::format("{0}.size_bytes ({1}) is not a multiple of {0}.slices x {0}.ways x {0}.line_bytes "
                                 "({2} x {3} x {4} = {5}): every slice holds whole sets",
                                 n, l.size_bytes, l.slices, l.ways, l.line_bytes, set_bytes));
    sectorProblems(n, l.line_bytes, l.sector_bytes);
  };
  levelProblems("l2", c.l2, "cache", c.cache.line_bytes);
  if (c.l3.size_bytes != 0 && c.l2.size_bytes == 0)
    errs.push_back("l3.size_bytes is set but l2.size_bytes is 0: the l3 is the level behind the l2 (to model one "
                   "shared level, set l2.* instead)");
  else
    levelProblems("l3", c.l3, "l2", c.l2.line_bytes);
  if (c.dram.burst_bytes > c.dram.interleave_bytes)
    errs.push_back(fmt::format("dram.burst_bytes ({}) > dram.interleave_bytes ({}): a burst would span channels",
                               c.dram.burst_bytes, c.dram.interleave_bytes));
  if (c.dram.burst_bytes > c.dram.row_bytes)
    errs.push_back(fmt::format("dram.burst_bytes ({}) > dram.row_bytes ({})", c.dram.burst_bytes, c.dram.row_bytes));
  // The write queue's watermarks (MEMORY.md): a drain starts at write_high
  // waiting bursts and stops at or below write_low, within write_queue entries.
  if (c.dram.write_high > c.dram.write_queue)
    errs.push_back(fmt::format(
        "dram.write_high ({}) > dram.write_queue ({}): the high watermark must fit in the write queue",
        c.dram.write_high, c.dram.write_queue));
  if (c.dram.write_low >= c.dram.write_high)
    errs.push_back(fmt::format("dram.write_low ({}) >= dram.write_high ({}): the low watermark must be below the high one",
                               c.dram.write_low, c.dram.write_high));
  if (c.dram.trefi_ns > 0 && c.clock.core_mhz > 0 && c.dram.channel_gbps > 0 && c.dram.tck_ns > 0) {
    const std::string problem = DramTimings::refreshProblem(c.dram, c.clock.core_mhz);
    if (!problem.empty()) errs.push_back(problem);
  }
  if (c.alu.fp32_rate > c.alu.fp16_rate)
    errs.push_back(fmt::format("alu.fp32_rate ({}) > alu.fp16_rate ({}): wider rows cannot blend faster",
                               c.alu.fp32_rate, c.alu.fp16_rate));
  // The DRAM model keeps time in 2^-16 core cycles (MEMORY.md): a burst must
  // take at least one such tick on its channel's bus.
  if (c.clock.core_mhz > 0 && c.dram.channel_gbps > 0) {
    const double burst_cycles = double(c.dram.burst_bytes) * c.clock.core_mhz / (c.dram.channel_gbps * 1000.0);
    if (!(burst_cycles >= 1.0 / 65536))
      errs.push_back(fmt::format(
          "dram.channel_gbps ({} GB/s) at clock.core_mhz ({} MHz): a {}-byte burst takes {:.3g} core cycles, below "
          "the DRAM model's resolution of 2^-16 cycles; lower the bandwidth or raise the clock",
          c.dram.channel_gbps, c.clock.core_mhz, c.dram.burst_bytes, burst_cycles));
  }
  // Partitions resume 1 to N ps after each quantum boundary, in round-robin
  // order (DESIGN.md): those offsets must stay within half a cycle.
  if (c.clock.core_mhz > 0 && double(c.partitions.count) >= 0.5e6 / c.clock.core_mhz)
    errs.push_back(fmt::format(
        "partitions.count ({}) at clock.core_mhz ({} MHz): partition resume offsets of up to {} ps do not fit in half "
        "a {:.1f} ps cycle; use fewer partitions or a slower clock",
        c.partitions.count, c.clock.core_mhz, c.partitions.count, 1e6 / c.clock.core_mhz));
  // The approximate engine visits fragments in submission order and applies
  // no insert out of that order (DESIGN.md): it refuses what it cannot model.
  if (c.sim.engine == SimEngine::Approximate && c.lock.mode != LockMode::Ordered)
    errs.push_back(approximateLockModeProblem(c.lock.mode));
  // Single-field limits hold by construction via set(); recheck in case the
  // struct was edited directly (a programmatic caller).
  for (const auto& p : registry()) {
    const Value v = p.get(c);
    try {
      checked(p, v, formatValue(v));
    } catch (const std::invalid_argument& e) {
      errs.push_back(e.what());
    }
  }
  // One problem is one line; several are listed one per line.
  if (errs.size() == 1) throw std::invalid_argument(fmt::format("invalid configuration (preset {}): {}", c.preset, errs[0]));
  if (!errs.empty())
    throw std::invalid_argument(fmt::format("invalid configuration (preset {}):\n  {}", c.preset,
                                            fmt::join(errs, "\n  ")));
}

nlohmann::json ConfigTree::toJson() const {
  nlohmann::json j = nlohmann::json::object();
  j["preset"] = cfg_.preset;
  for (const auto& p : registry()) {
    std::string pointer = "/" + p.path;  // "/lock/granularity": nested objects
    std::replace(pointer.begin(), pointer.end(), '.', '/');
    j[nlohmann::json::json_pointer(pointer)] = jsonValue(p.get(cfg_));
  }
  return j;
}

std::vector<PropertyInfo> ConfigTree::properties() const {
  std::vector<PropertyInfo> out;
  out.reserve(registry().size());
  for (const auto& p : registry()) {
    out.push_back(PropertyInfo{.path = p.path,
                               .type = p.type,
                               .unit = p.unit,
                               .description = p.description,
                               .value = formatValue(p.get(cfg_)),
                               .default_value = formatValue(p.get(defaults_)),
                               .allowed = p.allowed(),
                               .enum_values = p.names,
                               .inferred = presetValueInferred(cfg_.preset, p.path)});
  }
  return out;
}

std::string ConfigTree::describe() const {
  const auto props = properties();
  size_t wp = 8, wv = 5, wu = 4, wd = 7;
  for (const auto& i : props) {
    wp = std::max(wp, i.path.size());
    wv = std::max(wv, i.value.size());
    wu = std::max(wu, i.unit.size());
    if (i.value != i.default_value) wd = std::max(wd, i.default_value.size());
  }
  std::string out = fmt::format("effective configuration (preset {}; * = changed from the preset)\n", cfg_.preset);
  out += fmt::format("  {:<{}} {:<{}} {:<{}} {:<{}} {}\n", "property", wp, "value", wv, "unit", wu, "default", wd,
                     "description");
  for (const auto& i : props) {
    const bool changed = i.value != i.default_value;
    out += fmt::format("{} {:<{}} {:<{}} {:<{}} {:<{}} {}\n", changed ? '*' : ' ', i.path, wp, i.value, wv, i.unit,
                       wu, changed ? i.default_value : "", wd, i.description);
  }
  return out;
}

ConfigTree resolveTree(const std::string& preset, const std::string& config_file,
                       const std::vector<std::string>& sets) {
  std::string name = preset, preset_from_file;
  nlohmann::json file_json;
  if (!config_file.empty()) {
    file_json = readConfigFile(config_file);
    // A file naming its preset supplies it when --preset was not given.
    if (file_json.is_object() && file_json.contains("preset") && file_json["preset"].is_string())
      preset_from_file = file_json["preset"].get<std::string>();
  }
  const bool from_file = name.empty() && !preset_from_file.empty();
  if (from_file) name = preset_from_file;
  if (name.empty()) name = "iris-pro-5200";
  ConfigTree tree = [&] {
    try {
      return ConfigTree::forPreset(name);
    } catch (const std::invalid_argument& e) {
      if (!from_file) throw;
      throw std::invalid_argument(fmt::format("{}: key 'preset': {}", config_file, e.what()));
    }
  }();
  if (!config_file.empty()) tree.applyJson(file_json, config_file);
  for (const auto& s : sets) {
    const size_t eq = s.find('=');
    if (eq == std::string::npos || eq == 0)
      throw std::invalid_argument(
          fmt::format("--set '{}': expected path=value, e.g. --set lock.granularity=quad", s));
    try {
      tree.set(std::string_view(s).substr(0, eq), std::string_view(s).substr(eq + 1));
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("--set '{}': {}", s, e.what()));
    }
  }
  tree.validate();
  return tree;
}

RopConfig resolveConfig(const std::string& preset, const std::string& config_file,
                        const std::vector<std::string>& sets) {
  return resolveTree(preset, config_file, sets).config();
}

std::string presetTableMarkdown() {
  std::vector<std::vector<PropertyInfo>> cols;
  const auto names = presetNames();
  for (const auto& n : names) cols.push_back(ConfigTree::forPreset(n).properties());
  std::string out = "| property | unit |";
  for (const auto& n : names) out += " " + n + " |";
  out += " allowed | description |\n| --- | --- |";
  for (size_t k = 0; k < names.size(); ++k) out += " --- |";
  out += " --- | --- |\n";
  for (size_t r = 0; r < cols[0].size(); ++r) {
    const PropertyInfo& i = cols[0][r];
    out += fmt::format("| `{}` | {} |", i.path, i.unit);
    for (const auto& c : cols) out += fmt::format(" {}{} |", c[r].value, c[r].inferred ? " (i)" : "");
    // A bare '|' ("pixel | quad") would split the Markdown cell.
    auto cell = [](const std::string& text) {
      std::string c;
      for (char ch : text) c += ch == '|' ? std::string("\\|") : std::string(1, ch);
      return c;
    };
    out += fmt::format(" {} | {} |\n", cell(i.allowed), cell(i.description));
  }
  return out;
}


}  // namespace oit::rop
