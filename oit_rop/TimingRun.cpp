#include "oit_rop/TimingRun.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <memory>
#include <numeric>
#include <stdexcept>
#include <tlm>
#include <vector>

#include "oit_rop/Bottleneck.hpp"
#include "oit_rop/memory/ArrayLayout.hpp"
#include "oit_rop/memory/CacheLevel.hpp"
#include "oit_rop/memory/PortCalendar.hpp"
#include "oit_rop/stages/BlendAlu.hpp"
#include "oit_rop/stages/FrontEnd.hpp"
#include "oit_rop/OitRop.hpp"
#include "oit_rop/config/ConfigTree.hpp"

namespace oit::rop {

namespace {

using nlohmann::json;

uint64_t alignUp(uint64_t v, uint64_t a) { return (v + a - 1) / a * a; }

void validate(const RopConfig& c) {
  auto bad = [](const std::string& what) { throw std::invalid_argument("timing config: " + what); };
  if (!(c.clock.core_mhz > 0)) bad("clock.core_mhz must be > 0");
  if (!(c.input.fragments_per_clock > 0)) bad("input.fragments_per_clock must be > 0");
  if (c.lock.capacity == 0) bad("lock.capacity must be > 0");
  if (c.alu.blends_per_clock == 0) bad("alu.blends_per_clock must be > 0");
  if (!(c.alu.fp16_rate > 0) || !(c.alu.fp32_rate > 0)) bad("alu.fp16_rate and alu.fp32_rate must be > 0");
  if (c.stats.interval_cycles == 0) bad("stats.interval_cycles must be > 0");
  if (c.sim.engine == SimEngine::Approximate && c.lock.mode != LockMode::Ordered)
    bad(approximateLockModeProblem(c.lock.mode));
}

// The trace as the partitions' SystemC threads read it. SystemC turns an
// exception escaping a thread into an sc_report ("(E549) uncaught exception:
// ... In file: ... In process: ..."), so the first exception of the source is
// kept here and rethrown after sc_start(): a bad record reads the same in
// timing mode as in functional mode (file, byte offset, record, field).
class CapturingSource final : public FragmentSource {
 public:
  explicit CapturingSource(FragmentSource& inner) : inner_(inner) {}
  const TraceHeader& header() const override { return inner_.header(); }
  const std::string& path() const override { return inner_.path(); }
  std::span<const Fragment> next() override {
    try {
      return inner_.next();
    } catch (...) {
      if (!error_) error_ = std::current_exception();
      throw;
    }
  }
  uint64_t position() const override { return inner_.position(); }
  void rewind() override {
    try {
      inner_.rewind();
    } catch (...) {
      if (!error_) error_ = std::current_exception();
      throw;
    }
  }
  const std::exception_ptr& error() const { return error_; }

 private:
  FragmentSource& inner_;
  std::exception_ptr error_;
};

json stageJson(const StageCycles& s) {
  json stalls = json::object();
  for (unsigned i = 0; i < kStallCount; ++i) stalls[stallKey(Stall(i))] = s.stalls[i];
  return {{"busy", s.busy}, {"idle", s.idle}, {"stalls", stalls}, {"stalled", s.stalled()}};
}

json bySurface(const std::array<uint64_t, kSurfaceCount>& v) {
  json j = json::object();
  uint64_t total = 0;
  for (unsigned i = 0; i < kSurfaceCount; ++i) {
    j[surfaceKey(Surface(i))] = v[i];
    total += v[i];
  }
  j["total"] = total;
  return j;
}

// An insert gets all its lines or waits (BlendArrayCache::acquire), so the
// cache must have a miss-queue entry for each and the ways for those that
// share a set.
void checkCacheServesInserts(const RopConfig& cfg, const CacheGeometry& g, const FragmentLines& lines,
                             const model::OitAlgorithm& algo) {
  const char* layout = cfg.memory.array_layout == ArrayLayoutKind::RowMajor ? "row_major" : "pixel_major";
  if (lines.maxLines() > cfg.cache.miss_queue)
    throw std::invalid_argument(fmt::format(
        "cache.miss_queue ({}) is smaller than the {} cache lines one {} insert touches ({} bytes per pixel, "
        "memory.array_layout {}, cache.line_bytes {}): an insert gets all its lines or waits, so it could never "
        "start; raise cache.miss_queue or cache.line_bytes",
        cfg.cache.miss_queue, lines.maxLines(), algo.name(), algo.bytesPerPixel(), layout, cfg.cache.line_bytes));
  const uint32_t in_set = lines.maxLinesInOneSet(g.sets);
  if (in_set > g.ways)
    throw std::invalid_argument(fmt::format(
        "one {} insert touches {} lines of one set of the cache but a set has {} ways (cache.ways {}, {} sets; "
        "memory.array_layout {}): it could never get them all; raise cache.ways or cache.size_bytes, or use "
        "pixel_major",
        algo.name(), in_set, g.ways, cfg.cache.ways, g.sets, layout));
}

// One cache level's figures for memory.levels[] (report.json).
json levelJson(const std::string& name, const LevelStats& l, bool classified) {
  const uint64_t accesses = LevelStats::total(l.accesses), hits = LevelStats::total(l.hits);
  json by = json::object();
  for (unsigned i = 0; i < kSurfaceCount; ++i)
    by[surfaceKey(Surface(i))] = {{"accesses", l.accesses[i]},       {"hits", l.hits[i]},
                                  {"misses", l.misses[i]},           {"read_bytes", l.read_bytes[i]},
                                  {"write_bytes", l.write_bytes[i]}, {"fill_bytes", l.fill_bytes[i]},
                                  {"writeback_bytes", l.writeback_bytes[i]}, {"writebacks", l.writebacks[i]}};
  json j = {{"name", name},
          {"accesses", accesses},
          {"hits", hits},
          {"misses", LevelStats::total(l.misses)},
          {"hit_rate", accesses ? double(hits) / double(accesses) : 0.0},
          {"read_bytes", LevelStats::total(l.read_bytes)},
          {"write_bytes", LevelStats::total(l.write_bytes)},
          {"fill_bytes", LevelStats::total(l.fill_bytes)},
          {"writeback_bytes", LevelStats::total(l.writeback_bytes)},
          {"writebacks", LevelStats::total(l.writebacks)},
          {"victims_in", l.victims_in},
          {"miss_classes", classified},
          {"by_surface", by}};
  // Not classified (stats.level_miss_classes off): no split at all, not zeros.
  if (classified) {
    j["compulsory_misses"] = l.compulsory_misses;
    j["capacity_misses"] = l.capacity_misses;
    j["conflict_misses"] = l.conflict_misses;
  }
  return j;
}

// Bytes still dirty somewhere in the hierarchy at the frame's end, per
// surface: each byte once, whichever levels hold it (the upper level's copy
// first: it is the newer one). The ranges of all levels are multiples of
// `unit` bytes, aligned.
std::array<uint64_t, kSurfaceCount> endDirtyBytes(const std::vector<std::vector<DirtyRange>>& by_level, uint32_t unit) {
  // Every unit in level order, sorted by address keeping that order among
  // equal ones (a stable sort): the first of each address is the upper
  // level's. (A hash map of a million units was 2 % of the bench trace's run.)
  struct Held {
    uint64_t addr;
    Surface surface;
  };
  std::vector<Held> held;
  size_t n = 0;
  for (const auto& ranges : by_level)
    for (const DirtyRange& r : ranges) n += (r.addr + r.bytes - r.addr / unit * unit + unit - 1) / unit;
  held.reserve(n);
  for (const auto& ranges : by_level)
    for (const DirtyRange& r : ranges)
      for (uint64_t a = r.addr / unit * unit; a < r.addr + r.bytes; a += unit) held.push_back({a, r.surface});
  std::stable_sort(held.begin(), held.end(), [](const Held& x, const Held& y) { return x.addr < y.addr; });
  std::array<uint64_t, kSurfaceCount> bytes{};
  for (size_t i = 0; i < held.size(); ++i)
    if (i == 0 || held[i].addr != held[i - 1].addr) bytes[unsigned(held[i].surface)] += unit;
  return bytes;
}

}  // namespace

std::string vcdFilePath(const std::string& path) {
  if (path.empty()) return path;
  // SystemC appends ".vcd" to the name it is given; OitRop strips one first.
  if (path.size() > 4 && path.compare(path.size() - 4, 4, ".vcd") == 0) return path;
  return path + ".vcd";
}

void checkVcdWritable(const std::string& path) {
  const std::string file = vcdFilePath(path);
  std::error_code ec;
  const bool existed = std::filesystem::exists(file, ec);
  errno = 0;
  std::FILE* f = std::fopen(file.c_str(), "a");  // creates it, never truncates
  if (!f) {
    const int err = errno;
    throw std::invalid_argument(fmt::format("{}: cannot write the VCD file: {}", file,
                                            err ? std::strerror(err) : "cannot open for writing"));
  }
  std::fclose(f);
  if (!existed) std::filesystem::remove(file, ec);
}

TimingResult runTiming(FragmentSource& trace, model::OitAlgorithm& algo, const RopConfig& cfg,
                       const TimingOptions& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  if (sc_core::sc_get_status() != sc_core::SC_ELABORATION || sc_core::sc_find_object("oit_rop"))
    throw std::logic_error("runTiming: SystemC elaborates once per process; run one timing simulation per process");
  validate(cfg);
  // SystemC cannot report a VCD it fails to open (it crashes later): check first.
  if (!opt.vcd_path.empty()) checkVcdWritable(opt.vcd_path);
  CapturingSource src(trace);

  const TraceHeader& h = src.header();
  const model::DrawClassifier classes(h);
  algo.beginFrame(h);
  const FrameGeometry geo(h.width, h.height, cfg.partitions, cfg.lock.granularity);
  // Where the arrays live and which lines each insert touches; refused here,
  // before any work, when the cache could never serve an insert.
  const ArrayLayout layout(algo.layout(), algo.bytesPerPixel(), geo.tilePixels(), cfg.memory.array_layout,
                           cfg.cache.line_bytes, cfg.cache.sector_bytes);
  const FragmentLines lines(algo, layout, geo.tilePixels());
  checkCacheServesInserts(cfg, cacheGeometry(cfg.cache, cfg.cache.line_bytes), lines, algo);
  if (opt.progress) opt.progress(0.0, "opaque");
  // The opaque phase's work per partition, counted in the same read.
  std::vector<uint64_t> opaque_per_part(geo.partitions, 0);
  const model::OpaqueLayer opaque = model::buildOpaqueLayerWith(
      src, classes, [&](const Fragment& f) { ++opaque_per_part[geo.partitionOf(geo.tileOf(f.x, f.y))]; });

  FrontEnd front(src, algo, classes, opaque, std::move(opaque_per_part), geo, cfg);
  if (opt.progress) front.setProgress(opt.progress);

  // Address map: tile-linear surfaces, each 1 MiB aligned.
  AddressMap map;
  map.tile_stride = layout.tileStride();
  map.tile4_bytes = geo.tilePixels() * 4;
  map.blend_arrays = 0;
  map.depth = alignUp(uint64_t(geo.tiles()) * map.tile_stride, 1u << 20);
  map.colour = map.depth + alignUp(uint64_t(geo.tiles()) * map.tile4_bytes, 1u << 20);
  map.node_pool = map.colour + alignUp(uint64_t(geo.tiles()) * map.tile4_bytes, 1u << 20);

  PartitionSetup setup;
  setup.cfg = &cfg;
  setup.geo = &geo;
  setup.front = &front;
  setup.algo = &algo;
  setup.layout = &layout;
  setup.lines = &lines;
  setup.map = map;
  setup.array_rows = algo.layout().rows;
  setup.format_rate = BlendAlu::formatRate(cfg.alu, algo.layout());
  setup.bounded = algo.bounded();
  setup.node_bytes = algo.poolNodeBytes();
  // The A-buffer's global node counter: one atomic unit for every partition.
  std::unique_ptr<NodeCounter> counter;
  std::unique_ptr<NodePool> pool;
  if (!algo.bounded()) {
    // Partitions run up to a quantum apart: its calendar keeps as much as the shared levels' ports.
    counter = std::make_unique<NodeCounter>(cfg.abuffer.atomics_per_clock, cfg.abuffer.atomic_latency,
                                            PortCalendar::sharedLookback(cfg.sim.quantum_cycles));
    setup.counter = counter.get();
    pool = std::make_unique<NodePool>(map.node_pool, algo.poolNodeBytes(), cfg.dram.burst_bytes);
    setup.pool = pool.get();
  }

  const CoreClock clock(cfg.clock.core_mhz);
  tlm::tlm_global_quantum::instance().set(clock.time(std::max<uint64_t>(1, cfg.sim.quantum_cycles)));
  auto top = std::make_unique<OitRop>("oit_rop", setup, opt.vcd_path);
  top->dram().memory().setSampleInterval(std::max<uint64_t>(1, cfg.stats.interval_cycles));
  try {
    sc_core::sc_start();
  } catch (const sc_core::sc_report& r) {
    // An exception thrown in a process: rethrow the original, not SystemC's wrapper.
    if (src.error()) std::rethrow_exception(src.error());
    if (std::strcmp(r.get_msg_type(), sc_core::SC_ID_SIMULATION_UNCAUGHT_EXCEPTION_) == 0)
      throw std::runtime_error(r.get_msg());
    throw;
  }
  if (!top->allDone()) throw std::logic_error("runTiming: the simulation stopped before every partition finished");

  // ---- Frame time and per-stage accounting ----
  const unsigned n = top->partitionCount();
  Cycle cycles = 0;
  for (unsigned i = 0; i < n; ++i) cycles = std::max(cycles, top->partition(i).result().end);
  StageAccounts sum;
  json parts = json::array();
  uint64_t skipped = 0, culled_early = 0, culled_late = 0, tiles_skipped = 0, tiles_resolved = 0, merges_skipped = 0;
  uint64_t node_w = 0, node_r = 0;
  LockStats lock{};
  CacheStats cache{};
  uint64_t arrays_written = 0;             // the ROP caches' written sectors, in bytes
  std::vector<DirtyRange> dirty_rop;       // the ROP caches' dirty sectors at the end
  std::vector<std::vector<DirtyRange>> dirty_by_level(1);
  EarlyDepthStats depth{};
  AluStats alu{};
  std::vector<uint64_t> part_frags;
  std::vector<PartitionPhases> phases;
  uint64_t lost_updates = 0;
  for (unsigned i = 0; i < n; ++i) {
    const RopPartition& p = top->partition(i);
    PartitionResult r = p.result();
    // Each partition's accounts cover its own cycles exactly (every cycle up to
    // its end busy, stalled or idle); only the cycles after it finished, until
    // the frame's end, are padded with idle. (Checked before padding: padding
    // alone would turn cycles a stage lost into idle ones.)
    try {
      r.accounts.checkBalanced(r.end);
    } catch (const std::logic_error& e) {
      throw std::logic_error(fmt::format("partition {} (end cycle {}): {}", i, r.end, e.what()));
    }
    r.accounts.padTo(cycles);  // every stage now adds up to the frame's cycles
    json stages = json::object();
    for (unsigned s = 0; s < kStageCount; ++s) {
      sum.stage[s] += r.accounts.stage[s];
      stages[stageKey(Stage(s))] = stageJson(r.accounts.stage[s]);
    }
    parts.push_back({{"end_cycle", r.end}, {"opaque_end_cycle", r.opaque_end}, {"pass_end_cycles", r.pass_end},
                     {"fragments", r.fragments}, {"stages", stages},
                     {"skipped_idle_cycles", r.skipped_idle}, {"lock_peak_occupancy", p.lockStats().peak_occupancy}});
    part_frags.push_back(r.fragments);
    phases.push_back({r.opaque_end, r.end, r.pass_end, r.root_causes});
    skipped += r.skipped_idle;
    culled_early += r.culled_early;
    culled_late += r.culled_late;
    tiles_skipped += r.tiles_skipped_fast_clear;
    tiles_resolved += r.tiles_resolved;
    merges_skipped += r.merges_skipped;
    node_w += r.node_bytes_written;
    node_r += r.node_bytes_read;
    const LockStats& l = p.lockStats();
    lock.arrivals += l.arrivals;
    lock.conflicts += l.conflicts;
    lock.wait_cycles += l.wait_cycles;
    lock.longest_wait = std::max(lock.longest_wait, l.longest_wait);
    lock.out_of_order_entries += l.out_of_order_entries;
    lock.entries += l.entries;
    lock.peak_occupancy = std::max(lock.peak_occupancy, l.peak_occupancy);
    cache += p.cache().stats();
    arrays_written += p.cache().writtenBytes();
    p.cache().dirtyRanges(dirty_rop);
    const EarlyDepthStats& d = p.earlyDepth().stats();
    depth.tested += d.tested;
    depth.depth_reads += d.depth_reads;
    depth.depth_buffer_hits += d.depth_buffer_hits;
    depth.hiz_decided += d.hiz_decided;
    alu.blends += p.alu().stats().blends;
    alu.compares += p.alu().stats().compares;
    alu.moves += p.alu().stats().moves;
    alu.dropped += p.alu().stats().dropped;
    // lock.mode unordered / none: the outcomes were decided at lock entry.
    if (const BlendArrayRmw* rmw = p.rmw()) {
      for (unsigned pass = 0; pass < rmw->passOutcomes().size(); ++pass) front.addOutcomes(pass, rmw->passOutcomes()[pass]);
      lost_updates += rmw->lostUpdates();
    }
  }

  // ---- The image: functional resolve of the per-pixel state ----
  TimingResult res;
  const size_t pixels = size_t(h.width) * h.height;
  const unsigned words = algo.stateWords();
  res.image = model::Image(h.width, h.height);
  const auto& state = front.state();
  for (size_t p = 0; p < pixels; ++p) {
    const model::Rgb bg = opaque.landed(p) ? opaque.colour[p] : opt.clear_colour;
    res.image.pixels[p] = algo.resolve(state.data() + p * words, bg);
  }
  res.counts = front.counts();
  res.pool_bytes = algo.poolBytes();
  res.counts.source_passes = unsigned(front.sourceReads() + (classes.anyOpaque() ? 1 : 0));

  // ---- Statistics ----
  const model::RenderCounts& rc = res.counts;
  const double frame_us = double(cycles) / cfg.clock.core_mhz;
  json timing = {{"cycles", cycles},
                 {"frame_time_us", frame_us},
                 {"clock_mhz", cfg.clock.core_mhz},
                 {"partitions", n},
                 {"partition_cycles", cycles * n},
                 {"skipped_idle_cycles", skipped},
                 {"fragments_per_cycle", cycles ? double(rc.fragments_in) * algo.passes() / double(cycles) : 0.0}};
  json stages = json::object();
  for (unsigned s = 0; s < kStageCount; ++s) stages[stageKey(Stage(s))] = stageJson(sum.stage[s]);
  timing["stages"] = stages;
  timing["per_partition"] = parts;

  json pass_outcomes = json::array();
  for (const auto& po : rc.pass_outcomes) pass_outcomes.push_back({{"stored", po[0]}, {"merged", po[1]}, {"discarded", po[2]}});
  json fragments = {{"in", rc.fragments_in},
                    {"opaque", rc.opaque},
                    {"culled_by_depth", rc.culled},
                    {"blended", rc.stored},
                    {"merged", rc.merged},
                    {"discarded", rc.discarded},
                    {"dropped_pool_full", algo.bounded() ? 0 : rc.discarded},
                    {"outcomes_sum_to_in", rc.balanced()},
                    {"per_partition", part_frags},
                    {"pass_outcomes", pass_outcomes},
                    {"rmw_bytes_read", rc.bytes_read},
                    {"rmw_bytes_written", rc.bytes_written}};

  const MemoryStats& ms = top->dram().memory().stats();
  const double bytes_total = double(ms.readBytes() + ms.writeBytes());
  double peak_gbps = 0;
  json series = json::array();
  // Bandwidth from the bytes the DRAM buses moved per interval (by bus time):
  // the sampler's request-time counts can bunch up across partitions that run
  // a quantum apart, which would report more than the channels can move.
  // The frame usually ends inside the last interval: its bytes are divided by
  // the part of it the frame covers (else its rate is underestimated). A short
  // last part may be mostly one burst, so the rate is clamped to what the
  // channels can move; and peak is never below mean (mean is the average of the
  // per-interval rates weighted by their lengths, with requested bytes <= bus bytes).
  const std::vector<uint64_t>& bus = ms.bus_bytes_per_interval;
  const Cycle interval = top->sampleInterval();  // stats.interval_cycles, doubled per stats.max_samples
  const double channel_peak_gbps = top->dram().memory().peakBytesPerCycle() * cfg.clock.core_mhz * 1e6 / 1e9;
  for (size_t i = 0; i < bus.size(); ++i) {
    const Cycle begin = Cycle(i) * interval;
    const Cycle covered = cycles > begin ? std::min<Cycle>(cycles - begin, interval) : interval;
    const double seconds = double(covered) / (cfg.clock.core_mhz * 1e6);
    peak_gbps = std::max(peak_gbps, std::min(double(bus[i]) / seconds / 1e9, channel_peak_gbps));
  }
  const size_t sampled = top->samples().size();
  for (size_t i = 0; i < sampled; ++i) {
    const TimeSample& s = top->samples()[i];
    series.push_back({{"cycle", s.cycle},
                      {"dram_bytes", i < bus.size() ? bus[i] : 0},
                      {"scoreboard_occupancy", s.occupancy},
                      {"lock_waiters", s.lock_waiters}});
  }
  // The sampler stops when the last partition is done, at or before the frame's
  // end: one more sample at the end cycle holds the rest of the bus bytes (so the
  // series adds up to every byte moved, and a frame shorter than one interval
  // still has one sample, an empty one of 0 cycles too). Nothing is in flight then.
  const Cycle last_sampled = sampled ? top->samples().back().cycle : 0;
  if (cycles > last_sampled || series.empty()) {
    uint64_t rest = 0;
    for (size_t i = sampled; i < bus.size(); ++i) rest += bus[i];
    series.push_back({{"cycle", cycles}, {"dram_bytes", rest}, {"scoreboard_occupancy", 0}, {"lock_waiters", 0}});
  }
  // What bounds the frame: root causes, utilisation per resource, phases.
  ResourceWork work;
  work.input_fragments = double(rc.opaque) + double(std::accumulate(part_frags.begin(), part_frags.end(), uint64_t(0)));
  work.input_rate = cfg.input.fragments_per_clock;
  work.depth_tests = double(depth.tested);
  for (size_t i = 0; i < sampled; ++i) work.mean_occupancy += double(top->samples()[i].occupancy);
  work.mean_occupancy = sampled ? work.mean_occupancy / double(sampled) : 0.0;
  work.lock_capacity = cfg.lock.capacity;
  work.cache_accesses = double(cache.accesses);
  work.cache_ports = std::max(1.0, std::ceil(double(cfg.alu.blends_per_clock)));
  work.alu_work = double(alu.blends + alu.dropped) + double(tiles_resolved) * double(geo.tilePixels());
  work.alu_rate = double(cfg.alu.blends_per_clock) * setup.format_rate;
  for (Cycle b : ms.channel_busy) work.dram_busy_cycles += double(b);
  work.dram_channels = double(ms.channel_busy.size());
  auto port_bytes = [](const LevelStats& s) {
    return double(LevelStats::total(s.read_bytes) + LevelStats::total(s.write_bytes));
  };
  if (top->l2()) {
    work.l2_bytes = port_bytes(top->l2()->stats());
    work.l2_per_clock = cfg.l2.bytes_per_clock * cfg.l2.slices;
  }
  if (top->l3()) {
    work.l3_bytes = port_bytes(top->l3()->stats());
    work.l3_per_clock = cfg.l3.bytes_per_clock * cfg.l3.slices;
  }
  if (counter) {
    work.atomics = double(counter->atomics());
    work.atomics_per_clock = cfg.abuffer.atomics_per_clock;
  }
  timing.update(bottleneckJson(phases, cycles, work));
  const double mean_gbps = frame_us > 0 ? bytes_total / (frame_us * 1e-6) / 1e9 : 0.0;
  if (bus.size() <= 1) peak_gbps = mean_gbps;  // shorter than one interval
  peak_gbps = std::max(peak_gbps, mean_gbps);

  uint32_t landed_tiles = 0, landed_resolved = 0;
  for (uint32_t t = 0; t < geo.tiles(); ++t) {
    if (!front.opaqueLanded()[t]) continue;
    ++landed_tiles;
    // Resolved tiles: every one without fast clear, else those a fragment wrote.
    if (!cfg.skip.fast_clear || top->partition(geo.partitionOf(t)).cache().touched(t)) ++landed_resolved;
  }
  const uint64_t wh = uint64_t(h.width) * h.height;
  // A-buffer: heads + the pool as allocated (all of it when preallocated);
  // its nodes are node_pool_bytes_written, poolNodeBytes() each.
  // The arrays' bytes written: the sectors the inserts wrote, or (no fast
  // clear) every tile's, written clear at frame start; the A-buffer's nodes.
  const uint64_t arrays_touched =
      (cfg.skip.fast_clear ? arrays_written : uint64_t(geo.tiles()) * map.tile_stride) + node_w;
  json allocated = {{"blend_arrays", algo.bounded() ? wh * algo.bytesPerPixel() : 4 * wh + algo.poolBytes()},
                    {"depth", 4 * wh},
                    {"colour", 4 * wh},
                    {"resolve", 0}};
  json touched = {{"blend_arrays", arrays_touched},
                  {"depth", uint64_t(landed_tiles) * map.tile4_bytes},
                  {"colour", uint64_t(landed_tiles) * map.tile4_bytes},
                  {"resolve", tiles_resolved * map.tile4_bytes}};
  // Compulsory traffic (MEMORY.md): what a perfect, infinite cache would
  // still move: every byte the frame writes leaves the chip once (written back
  // when evicted, or still dirty at the end); nothing is read that the frame
  // did not write first (a resolve-written colour tile counts as resolve).
  std::array<uint64_t, kSurfaceCount> compulsory{};
  compulsory[unsigned(Surface::BlendArrays)] = arrays_touched;
  compulsory[unsigned(Surface::Depth)] = uint64_t(landed_tiles) * map.tile4_bytes;
  compulsory[unsigned(Surface::Colour)] = uint64_t(landed_tiles - landed_resolved) * map.tile4_bytes;
  compulsory[unsigned(Surface::Resolve)] = tiles_resolved * map.tile4_bytes;
  // Left dirty at the end, in the ROP caches and the shared levels: moved later
  // (when evicted), so counted beside the frame's DRAM bytes against compulsory.
  uint32_t unit = layout.sectorBytes();
  dirty_by_level[0] = std::move(dirty_rop);
  for (const CacheLevel* l : {top->l2(), top->l3()}) {
    if (!l) continue;
    dirty_by_level.emplace_back();
    l->dirtyRanges(dirty_by_level.back());
    unit = std::min(unit, l->sectorBytes());
  }
  const std::array<uint64_t, kSurfaceCount> end_dirty = endDirtyBytes(dirty_by_level, unit);
  uint64_t compulsory_total = 0, end_dirty_total = 0;
  for (unsigned i = 0; i < kSurfaceCount; ++i) {
    compulsory_total += compulsory[i];
    end_dirty_total += end_dirty[i];
  }
  const uint64_t moved = ms.readBytes() + ms.writeBytes() + end_dirty_total;
  json levels = json::array();
  {
    const uint64_t rop_misses = cache.misses;
    json rop = {{"name", "rop_cache"},
                {"accesses", cache.accesses},
                {"hits", cache.hits},
                {"misses", rop_misses},
                {"hit_rate", cache.hitRate()},
                {"read_bytes", cache.read_bytes},
                {"write_bytes", cache.write_bytes},
                {"fill_bytes", cache.fill_bytes},
                {"writeback_bytes", cache.writeback_bytes},
                {"writebacks", cache.writebacks},
                {"miss_classes", cfg.stats.miss_classes},
                {"compulsory_misses", cache.compulsory_misses},
                {"capacity_misses", cache.capacity_misses},
                {"conflict_misses", cache.conflict_misses}};
    levels.push_back(rop);
    if (top->l2()) levels.push_back(levelJson("l2", top->l2()->stats(), top->l2()->classifiesMisses()));
    if (top->l3()) levels.push_back(levelJson("l3", top->l3()->stats(), top->l3()->classifiesMisses()));
  }
  json memory = {{"dram_read_bytes", bySurface(ms.read_bytes)},
                 {"dram_write_bytes", bySurface(ms.write_bytes)},
                 {"requests", ms.requests},
                 {"row_hits", ms.row_hits},
                 {"row_misses", ms.row_misses},
                 {"peak_gbps", peak_gbps},
                 {"mean_gbps", mean_gbps},
                 {"channel_peak_gbps", channel_peak_gbps},
                 {"node_pool_bytes_written", node_w},
                 {"node_pool_bytes_read", node_r},
                 {"footprint", {{"allocated", allocated}, {"touched", touched}}},
                 {"compulsory_bytes", bySurface(compulsory)},
                 {"end_dirty_bytes", bySurface(end_dirty)},
                 {"traffic_over_compulsory", compulsory_total ? double(moved) / double(compulsory_total) : 0.0},
                 {"levels", levels}};
  json lockj = {{"conflicts", lock.conflicts},
                {"wait_cycles", lock.wait_cycles},
                {"longest_wait", lock.longest_wait},
                {"peak_occupancy", lock.peak_occupancy},
                {"out_of_order_entries", lock.out_of_order_entries},
                {"entries", lock.entries},
                {"capacity", cfg.lock.capacity},
                {"mode", lockModeName(cfg.lock.mode)},
                {"lost_updates", lost_updates}};
  json cachej = {{"hit_rate", cache.hitRate()},          {"accesses", cache.accesses},
                 {"hits", cache.hits},                   {"misses", cache.misses},
                 {"clear_fills", cache.clear_fills},     {"evictions", cache.evictions},
                 {"writebacks", cache.writebacks},       {"miss_queue_full", cache.miss_queue_full},
                 {"set_in_use", cache.set_in_use},
                 {"peak_misses_in_flight", cache.peak_misses_in_flight},
                 {"sector_misses", cache.sector_misses},
                 {"hits_under_miss", cache.hits_under_miss},
                 {"line_bytes", layout.lineBytes()},
                 {"sector_bytes", layout.sectorBytes()},
                 {"lines_per_tile", layout.linesPerTile()},
                 {"tile_stride_bytes", layout.tileStride()},
                 {"array_layout", cfg.memory.array_layout == ArrayLayoutKind::RowMajor ? "row_major" : "pixel_major"},
                 {"max_lines_per_insert", lines.maxLines()}};
  json skips = {{"early_depth_culled", culled_early},
                {"late_culled", culled_late},
                {"tiles_skipped_fast_clear", tiles_skipped},
                {"tiles_resolved", tiles_resolved},
                {"merges_skipped", merges_skipped},
                {"idle_cycles_skipped", skipped}};
  json depthj = {{"tested", depth.tested},
                 {"depth_tile_reads", depth.depth_reads},
                 {"depth_buffer_hits", depth.depth_buffer_hits},
                 {"hiz_decided", depth.hiz_decided}};
  json alu_j = {{"blends", alu.blends}, {"compares", alu.compares}, {"moves", alu.moves}, {"dropped", alu.dropped}};
  if (counter)
    alu_j["node_counter"] = {{"atomics", counter->atomics()},
                             {"wait_cycles", counter->waitCycles()},
                             {"atomics_per_clock", cfg.abuffer.atomics_per_clock}};
  json per_draw = json::object();
  std::vector<uint32_t> ids;
  for (const auto& [id, _] : front.perDraw()) ids.push_back(id);
  std::sort(ids.begin(), ids.end());
  for (uint32_t id : ids) {
    const DrawCounts& d = front.perDraw().at(id);
    per_draw[std::to_string(id)] = {{"fragments", d.fragments}, {"culled", d.culled}, {"inserted", d.inserted}};
  }
  res.stats = {{"timing", timing}, {"fragments", fragments}, {"memory", memory}, {"lock", lockj},
               {"cache", cachej},  {"skips", skips},         {"depth", depthj},   {"alu", alu_j},
               {"timeseries", {{"interval_cycles", interval}, {"samples", series}}},
               {"per_draw", per_draw}};
  top.reset();
  res.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (opt.progress) opt.progress(1.0, "done");
  return res;
}

}  // namespace oit::rop
