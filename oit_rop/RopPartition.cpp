#include "oit_rop/RopPartition.hpp"

#include "oit_rop/engines/ApproximateEngine.hpp"
#include "oit_rop/engines/CycleEngine.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <deque>
#include <functional>
#include <stdexcept>

namespace oit::rop {

namespace {
constexpr unsigned kResolvePrefetch = 8;  // tiles whose lines are fetched ahead of the resolve
constexpr Cycle kPostedWindow = 1024;     // posted DRAM writes may run this far ahead
uint8_t dummy_data[1];
// Whether a posted write waits for the l2's port (shared levels present, a
// miss's rest is RootCause::L2) rather than DRAM's write queue: see access().
bool writesWaitForL2Port(RootCause miss_rest) { return miss_rest == RootCause::L2; }
}  // namespace

RopPartition::RopPartition(sc_core::sc_module_name name, unsigned id, const PartitionSetup& setup,
                           MemoryPort& shared, MemorySystem& memory)
    : sc_module(name),
      dram("dram"),
      id_(id),
      s_(setup),
      cfg_(*setup.cfg),
      geo_(*setup.geo),
      front_(*setup.front),
      clock_(cfg_.clock.core_mhz),
      quantum_(std::max<Cycle>(1, cfg_.sim.quantum_cycles)),
      shader_(cfg_.input),
      early_(cfg_.early_depth, cfg_.input.fragments_per_clock, setup.map.tile4_bytes, setup.map.depth, *this,
             EarlyDepth::kDepthTiles, geo_.local),
      lock_(cfg_.lock),
      cache_(cfg_.cache,
             TileLines{setup.layout->lineBytes(), setup.layout->sectorBytes(), setup.layout->linesPerTile()},
             geo_.tiles(), setup.map.blend_arrays, shared, cfg_.skip.fast_clear, geo_.local, cfg_.stats.miss_classes),
      alu_(cfg_.alu, setup.format_rate),
      tok_(cfg_.lock.capacity),
      cache_q_(256),
      tail_q_(256),
      memory_(memory) {
  cache_ports_ = std::max(1u, unsigned(std::ceil(double(cfg_.alu.blends_per_clock))));
  tile_mask_ = (1u << geo_.tile_shift) - 1;
  early_cull_ = cfg_.early_depth.enabled && cfg_.skip.early_depth;
  merge_skip_ = cfg_.skip.lazy_merge && s_.array_rows > 1;
  miss_rest_ = cfg_.l2.size_bytes || cfg_.l3.size_bytes ? RootCause::L2 : RootCause::RopCacheMiss;
  root_.setBusShare(BusShareFn::of(memory));
  miss_waits_ = MissWaits(cfg_.cache.miss_queue);
  if (front_.defersInserts())
    rmw_ = std::make_unique<BlendArrayRmw>(cfg_.lock.mode, front_.pixelState(), cfg_.lock.capacity, front_.passes());
  payload_.set_extension(new DramExtension);  // owned (and freed) by the payload
  payload_.set_data_ptr(dummy_data);
  for (size_t i = 0; i < kStageCount; ++i) codes_ |= uint64_t(code(status_[i])) << (8 * i);
  if (cfg_.sim.engine == SimEngine::Approximate)
    approximate_ = std::make_unique<ApproximateEngine>(*this);
  else
    cycle_ = std::make_unique<CycleEngine>(*this);
  SC_THREAD(run);
}

RopPartition::~RopPartition() = default;

const LockStats& RopPartition::lockStats() const { return approximate_ ? approximate_->lockStats() : lock_.stats(); }
uint32_t RopPartition::occupancy() const { return approximate_ ? approximate_->occupancy() : lock_.occupancy(); }
uint32_t RopPartition::lockWaiters() const {
  return approximate_ ? approximate_->lockWaiters() : uint32_t(lock_.waiting());
}

Cycle RopPartition::access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) {
  DramExtension* ext = nullptr;
  payload_.get_extension(ext);
  ext->now = now;
  ext->surface = s;
  payload_.set_command(write ? tlm::TLM_WRITE_COMMAND : tlm::TLM_READ_COMMAND);
  payload_.set_address(addr);
  payload_.set_data_length(bytes);
  payload_.set_streaming_width(bytes);
  payload_.set_response_status(tlm::TLM_INCOMPLETE_RESPONSE);
  const sc_core::sc_time at = clock_.time(now), stamp = sc_core::sc_time_stamp();
  sc_core::sc_time delay = at > stamp ? at - stamp : sc_core::SC_ZERO_TIME;
  memory_.resetProbe();
  dram->b_transport(payload_, delay);
  if (!payload_.is_response_ok()) throw std::runtime_error("DramSystem refused a transfer");
  if (write) {
    if (ext->done >= last_write_done_) {
      last_write_done_ = ext->done;
      // A write into a shared level is done when its bytes crossed the level's
      // port (CacheLevel::access: write-allocate, fills and victims posted), so
      // it waited for that port, whatever DRAM traffic it started; without
      // shared levels, for the DRAM controller's write queue.
      const DramProbe d = writesWaitForL2Port(miss_rest_) ? DramProbe{} : memory_.probe();
      last_write_wait_ = splitWait(now, ext->done, d, miss_rest_);
    }
  } else if (s == Surface::Depth) {
    last_depth_ = splitWait(now, ext->done, memory_.probe(), miss_rest_);
  }
  return ext->done;
}

void RopPartition::syncQuantum() {
  // Synchronise on quantum boundaries (multiples of sim.quantum_cycles), so
  // partitions interleave their DRAM requests the same way whether or not
  // idle cycles are skipped.
  // At boundary k partition i resumes ((i + k) mod N + 1) ps after the
  // boundary's cycle: a round-robin order (each partition books its quantum's
  // DRAM requests first in turn; a fixed order would favour partition 0),
  // after the sampler, instead of however the kernel's event heap breaks ties
  // between equal times (which other timed waits, such as the sampler's
  // period, would change).
  const Cycle boundary = now_ / quantum_ * quantum_;
  const uint64_t place = (id_ + boundary / quantum_) % geo_.partitions;
  const sc_core::sc_time tb = clock_.time(boundary) + sc_core::sc_time(double(place + 1), sc_core::SC_PS),
                         stamp = sc_core::sc_time_stamp();
  qk_.set(tb > stamp ? tb - stamp : sc_core::SC_ZERO_TIME);
  qk_.sync();
  next_sync_ = boundary + quantum_;
}

void RopPartition::setAll(StageStatus v) {
  for (size_t i = 0; i < kStageCount; ++i) setStatus(Stage(i), v);
}

void RopPartition::flushAccounts() {
  for (size_t i = 0; i < kStageCount; ++i) {
    res_.accounts.stage[i].add(status_[i], now_ - since_[i]);
    since_[i] = now_;
  }
}

void RopPartition::opaquePhase() {
  for (uint32_t t = 0; t < geo_.tiles(); ++t)
    if (geo_.partitionOf(t) == id_) owned_.push_back(t);
  setAll(StageStatus::idle());
  // Without fast clear every blending-array tile is written clear at frame start.
  if (!cfg_.skip.fast_clear)
    for (uint32_t t : owned_)
      access(now_, s_.map.blend_arrays + uint64_t(t) * s_.map.tile_stride, s_.map.tile_stride, true,
             Surface::BlendArrays);
  const uint64_t n = front_.opaquePerPartition()[id_];
  if (n == 0) return;
  // The opaque pre-pass: its fragments enter at the input rate (depth test and
  // colour in the ROP's Z/colour path); the depth and colour of every tile
  // where an opaque fragment landed are written once, spread over the phase.
  const Cycle start = now_;
  const Cycle cycles = Cycle(std::ceil(double(n) / cfg_.input.fragments_per_clock));
  root_.set(now_, RootCause::Input);  // the pre-pass at the input rate
  std::vector<uint32_t> landed;
  for (uint32_t t : owned_)
    if (front_.opaqueLanded()[t] != 0) landed.push_back(t);
  setStatus(Stage::ShaderInput, StageStatus::busy());
  for (size_t i = 0; i < landed.size(); ++i) {
    const Cycle at = start + (i + 1) * cycles / landed.size();
    if (at > now_) advance(at, false);
    const uint32_t t = landed[i];
    access(now_, s_.map.depth + uint64_t(t) * s_.map.tile4_bytes, s_.map.tile4_bytes, true, Surface::Depth);
    access(now_, s_.map.colour + uint64_t(t) * s_.map.tile4_bytes, s_.map.tile4_bytes, true, Surface::Colour);
  }
  if (start + cycles > now_) advance(start + cycles, false);
  setAll(StageStatus::idle());
}

void RopPartition::nodeWrite() {
  // The node goes where the counter points (NodePool): consecutive with the
  // GPU's previous node; a burst is written once its last node is.
  res_.node_bytes_written += s_.node_bytes;
  const NodePool::Range r = s_.pool->append();
  if (r.bytes()) access(now_, r.begin, r.bytes(), true, Surface::BlendArrays);
}

void RopPartition::waitForFrontEnd() {
  // Another partition's backlog is at the high watermark: wait until it drains.
  advance(now_ + 1, true);
  front_.addWaiter();
  wait(front_.drained());
  const Cycle t = clock_.cycle(sc_core::sc_time_stamp());
  if (t > now_) advance(t, false);
}

// The A-buffer resolve's list walk over one tile (Yang et al. 2010): every
// pixel follows its list from the head, each node's read waiting for the
// previous node's pointer, so a list of n nodes is n dependent reads; the
// tile's pixels walk side by side (one read per pixel and step, of the node
// at its place in the pool: NodePool::address of its index, so nodes allocated
// together share lines and a pool that fits a cache level is read from it).
// Then each pixel sorts what it loaded (insertion sort,
// abuffer.sort_cycles_per_*; nodes past abuffer.max_sorted spill at
// abuffer.spill_cycles_per_node, or are ignored with truncate).
Cycle RopPartition::prepareWalk(uint32_t tile, std::vector<std::vector<uint32_t>>& lists, uint32_t& longest) {
  const FrontEnd::PixelState px = front_.pixelState();
  const uint32_t tx = tile % geo_.tiles_x, ty = tile / geo_.tiles_x;
  const uint32_t x0 = tx * geo_.tile_w, y0 = ty * geo_.tile_h;
  const uint32_t x1 = std::min(geo_.width, x0 + geo_.tile_w), y1 = std::min(geo_.height, y0 + geo_.tile_h);
  const ABufferConfig& ab = cfg_.abuffer;
  lists.resize(size_t(geo_.tile_w) * geo_.tile_h);
  size_t pixels = 0;
  longest = 0;
  Cycle slowest = 0;
  for (uint32_t y = y0; y < y1; ++y)
    for (uint32_t x = x0; x < x1; ++x) {
      const uint32_t* words = px.words + (size_t(y) * px.width + x) * px.words_per_pixel;
      const model::ResolveWork rw = px.algo->resolveWork(words);
      // The algorithm's own budget decides (the CLI builds it from abuffer.*):
      // truncate walks and sorts max_sorted nodes, spill all of them.
      const uint32_t walked = rw.sorted;
      const uint32_t spilled = rw.sorted == rw.nodes ? rw.spilled : 0;
      px.algo->listNodes(words, walked, lists[pixels++]);
      longest = std::max(longest, walked);
      const Cycle sort = Cycle(rw.compares) * ab.sort_cycles_per_compare + Cycle(rw.moves) * ab.sort_cycles_per_move +
                         Cycle(spilled) * ab.spill_cycles_per_node;
      slowest = std::max(slowest, sort);
      res_.list_nodes_walked += walked;
      res_.sort_cycles += sort;
    }
  for (size_t j = pixels; j < lists.size(); ++j) lists[j].clear();  // pixels past the frame's edge
  return slowest;
}

Cycle RopPartition::walkStep(const std::vector<std::vector<uint32_t>>& lists, uint32_t step, Cycle now) {
  // Issued when the previous step's reads are back (the resolve calls it at
  // that cycle, in time order with the partition's other requests: a walk
  // booked ahead all at once moved the shared levels' port calendars on and
  // pushed the other requests to their ring's oldest cycle, issue 22 s5).
  Cycle done = now;
  for (const auto& l : lists) {
    if (l.size() <= step) continue;
    done = std::max(done, access(now, s_.pool->address(l[step]), s_.node_bytes, false, Surface::BlendArrays));
    res_.node_bytes_read += s_.node_bytes;
  }
  res_.list_walk_cycles += done - now;
  return done;
}

void RopPartition::resolvePhase() {
  setAll(StageStatus::idle());
  if (s_.pool) {  // the nodes of a burst not yet complete
    const NodePool::Range r = s_.pool->flush();
    if (r.bytes()) access(now_, r.begin, r.bytes(), true, Surface::BlendArrays);
  }
  // Fast clear: tiles no fragment wrote keep their clear state; their colour
  // is already the opaque/clear colour, so they are neither read nor resolved.
  std::vector<uint32_t> tiles;
  for (uint32_t t : owned_) {
    if (!cfg_.skip.fast_clear || cache_.touched(t))
      tiles.push_back(t);
    else
      ++res_.tiles_skipped_fast_clear;
  }
  const double px_per_clock = std::max(1e-6, double(cfg_.alu.blends_per_clock) * s_.format_rate);
  std::deque<ResolveEntry> pf;
  if (!s_.bounded && walk_nodes_.size() < kResolvePrefetch) walk_nodes_.resize(kResolvePrefetch);
  size_t next_issue = 0;
  bool computing = false;
  uint32_t computing_tile = 0;
  Cycle compute_done = 0, sort_done = 0;
  // The issuing tile's lines, the next to read and when those read so far
  // are there. Each line read stays pinned until its tile's resolve is done
  // (as a fragment's until its blend), so fills in flight never exceed the
  // cache's lines: the pinned lines of the issuing tile, of each prefetched
  // tile (in pf's order) and of the tile being resolved.
  std::vector<LineTouch> lines;
  size_t line_next = 0;
  Cycle lines_ready = 0;
  WaitSplit lines_wait;  // the wait of the tile's line that is ready last (root causes)
  bool issuing = false;
  std::vector<LineTouch> issuing_pins, computing_pins;
  std::deque<std::vector<LineTouch>> pf_pins;
  const auto unpin = [&](uint32_t tile, std::vector<LineTouch>& pins) {
    if (!pins.empty() && cache_.release(tile, pins)) retry_at_ = 0;  // a set-refused line may go now
    pins.clear();
  };
  for (;;) {
    const Cycle now = now_;
    bool moved = false;
    if (computing && now >= compute_done) {
      unpin(computing_tile, computing_pins);
      access(now, s_.map.colour + uint64_t(computing_tile) * s_.map.tile4_bytes, s_.map.tile4_bytes, true,
             Surface::Resolve);
      computing = false;
      moved = true;
      ++res_.tiles_resolved;
    }
    unsigned acquired = 0;
    bool refused = false;
    while (next_issue < tiles.size() && pf.size() < kResolvePrefetch && acquired < cache_ports_) {
      // A tile's lines are read as one issue (one cache port); when the miss
      // queue lacks entries for the rest, they follow once entries free.
      const uint32_t t = tiles[next_issue];
      if (!issuing) {
        resolveLines(t, lines);
        line_next = 0;
        lines_ready = now;
        lines_wait = WaitSplit{now, now, now, RootCause::RopCacheMiss};
        issuing = true;
      }
      if (now < retry_at_) {
        refused = true;
        break;
      }
      while (line_next < lines.size()) {
        const std::span<const LineTouch> line(&lines[line_next], 1);
        memory_.resetProbe();
        const uint64_t misses = cache_.stats().misses;
        const Cycle r = cache_.acquire(now, t, line);
        if (r == kNever) {
          if (!cache_.refusedBySet()) {
            retry_at_ = cache_.missQueueFreesAt();
            refused_wait_ = miss_waits_.freeing(retry_at_, last_miss_);
          } else if (pf.empty() && !computing && !issuing_pins.empty()) {
            // Only this tile's own lines hold the set (more of its lines in
            // one set than ways): they were read, so they go, and the read goes on.
            unpin(t, issuing_pins);
            continue;
          } else {
            retry_at_ = kNever;  // until a resolved tile's lines are released
            refused_wait_ = last_miss_;
          }
          refused = true;
          break;
        }
        issuing_pins.push_back(lines[line_next]);
        if (r > lines_ready) {
          lines_ready = r;
          // A miss: its memory; a hit under a fill in flight: the latest miss's.
          lines_wait = cache_.stats().misses != misses ? splitWait(now, r, memory_.probe(), miss_rest_)
                       : r > now + cfg_.cache.hit_latency ? last_miss_
                                                           : WaitSplit{now, now, now, RootCause::RopCacheMiss};
          if (cache_.stats().misses != misses) {
            last_miss_ = lines_wait;
            miss_waits_.add(now, r, lines_wait);
          }
        }
        ++line_next;
      }
      if (refused) break;
      issuing = false;
      pf_pins.push_back(std::move(issuing_pins));
      issuing_pins.clear();
      // The tile's other inputs are fetched with its lines, and the resolve of
      // the tile waits for all of them: the opaque colour it composites over
      // (where an opaque fragment landed) and, for the A-buffer, its node
      // lists (every node of the tile read once).
      Cycle data = lines_ready;
      // The wait's root causes follow the input that arrives last.
      WaitSplit wait = lines_wait;
      auto input = [&](Cycle ready) {
        if (ready > data) {
          data = ready;
          wait = splitWait(now, ready, memory_.probe(), miss_rest_);
        }
      };
      if (front_.opaqueLanded()[t] != 0)
        input(access(now, s_.map.colour + uint64_t(t) * s_.map.tile4_bytes, s_.map.tile4_bytes, false, Surface::Colour));
      ResolveEntry e{t, data, 0, wait};
      if (!s_.bounded && front_.tileNodes()[t] != 0) {
        // The list walk's reads depend on each other: the chain, not a
        // resource, holds the tile (root cause list_walk). It starts when
        // the heads are there; the steps issue above, in time.
        e.slot = uint32_t(next_issue % kResolvePrefetch);  // at most kResolvePrefetch consecutive tiles in pf
        e.sort = prepareWalk(t, walk_nodes_[e.slot], e.steps);
        if (e.steps) {
          e.step_at = data;
          e.ready = kNever;
          e.wait = WaitSplit{now, now, now, RootCause::ListWalk};
        }
      }
      pf.push_back(e);
      ++next_issue;
      ++acquired;
      moved = true;
    }
    // The list walks in progress (a tile issued above starts now if its heads
    // are there): each step issues when the previous one's reads are back.
    for (ResolveEntry& e : pf) {
      if (e.step == e.steps || e.step_at > now) continue;
      e.step_at = walkStep(walk_nodes_[e.slot], e.step++, now);
      if (e.step == e.steps) e.ready = e.step_at;
      moved = true;
    }
    bool window_blocked = false;
    if (!computing && !pf.empty() && pf.front().ready <= now) {
      if (last_write_done_ > now + kPostedWindow) {
        window_blocked = true;
      } else {
        const uint32_t t = pf.front().tile;
        const Cycle sort = pf.front().sort;
        pf.pop_front();
        computing_pins = std::move(pf_pins.front());
        pf_pins.pop_front();
        uint64_t work = geo_.tilePixels();
        if (!s_.bounded) work = std::max<uint64_t>(work, front_.tileNodes()[t]);  // composite every node
        computing = true;
        computing_tile = t;
        // The A-buffer's pixels sort side by side: the tile waits for its slowest sort.
        sort_done = now + sort;
        compute_done = sort_done + std::max<Cycle>(1, Cycle(std::ceil(double(work) / px_per_clock)));
        moved = true;
      }
    }
    if (!computing && pf.empty() && next_issue == tiles.size()) break;
    // Root causes: the A-buffer's per-pixel sort, then the resolve's compute
    // at the blend rate; a tile's inputs wait for memory (or its list walk);
    // a refused acquire for the latest miss.
    if (computing) {
      const bool sorting = now < sort_done;
      setStatus(Stage::Resolve, sorting ? StageStatus::stall(Stall::Sort) : StageStatus::busy());
      root_.set(now, sorting ? RootCause::Sort : RootCause::Alu);
    } else if (window_blocked) {
      // The posted writes ran a window ahead: the resolve waits for what the
      // latest write waits for (the l2's port with shared levels, not DRAM).
      setStatus(Stage::Resolve,
                StageStatus::stall(writesWaitForL2Port(miss_rest_) ? Stall::CacheMissWait : Stall::DramBandwidth));
      root_.setWait(now, last_write_wait_);
    } else {
      setStatus(Stage::Resolve, StageStatus::stall(s_.bounded ? Stall::CacheMissWait : Stall::ListWalk));
      root_.setWait(now, !pf.empty() ? pf.front().wait : refused ? refused_wait_ : last_miss_);
    }
    Cycle next = now + 1;
    if (!moved && cfg_.skip.idle_cycles) {
      next = kNever;
      if (computing) next = std::min(next, now < sort_done ? sort_done : compute_done);
      if (!pf.empty() && pf.front().ready > now) next = std::min(next, pf.front().ready);
      for (const ResolveEntry& e : pf)
        if (e.step < e.steps) next = std::min(next, e.step_at);
      if (window_blocked) next = std::min(next, last_write_done_ - kPostedWindow);
      if (refused) next = std::min(next, retry_at_);
      if (!computing && !pf.empty() && pf.front().ready <= now && !window_blocked) next = now + 1;
      next = std::max(next == kNever ? now + 1 : next, now + 1);
    }
    advance(next, true);
  }
  // The frame ends when the last posted write reached DRAM: the DRAM
  // controller writes what its write queues still hold (MEMORY.md).
  // The root cause: the drain's own queueing by cause (its data on the bus
  // is bandwidth; the controller's bank, turnaround and refresh waits
  // theirs); past the drain, the posted writes still in flight: DRAM's
  // without shared levels, the l2 port's with them (their last write waits
  // for it; until issue 22 s5 it was charged dram_bandwidth with DRAM idle).
  memory_.resetProbe();
  const Cycle drained = memory_.drainWrites(now_);
  const Cycle end = std::max({now_, last_write_done_, drained});
  const bool port_tail = writesWaitForL2Port(miss_rest_) && last_write_done_ > drained;
  setStatus(Stage::Resolve, StageStatus::stall(port_tail ? Stall::CacheMissWait : Stall::DramBandwidth));
  root_.setWait(now_, splitWait(now_, end, memory_.probe(), port_tail ? RootCause::L2 : RootCause::DramBandwidth));
  if (end > now_) {
    if (cfg_.skip.idle_cycles)
      advance(end, true);
    else
      while (now_ < end) advance(now_ + 1, true);
  }
  setStatus(Stage::Resolve, StageStatus::idle());
}

void RopPartition::resolveLines(uint32_t t, std::vector<LineTouch>& out) {
  // The sectors holding the bytes the resolve reads of each pixel (its
  // final state: resolveBytes), of the lines this frame wrote (fast clear:
  // the others hold the clear value, known on chip).
  const ArrayLayout& layout = *s_.layout;
  resolve_fill_.assign(layout.linesPerTile(), 0);
  const uint32_t tx = t % geo_.tiles_x, ty = t / geo_.tiles_x;
  const uint32_t words = s_.algo->stateWords();
  const uint32_t* state = front_.state().data();
  for (uint32_t i = 0; i < geo_.tilePixels(); ++i) {
    const uint32_t x = tx * geo_.tile_w + i % geo_.tile_w, y = ty * geo_.tile_h + i / geo_.tile_w;
    if (x >= geo_.width || y >= geo_.height) continue;
    const uint32_t* w = state + (size_t(y) * geo_.width + x) * words;
    layout.addPrefixRead(i, s_.algo->resolveBytes(w), resolve_fill_.data());
  }
  out.clear();
  for (uint32_t l = 0; l < layout.linesPerTile(); ++l) {
    const uint32_t fill = resolve_fill_[l] & (cfg_.skip.fast_clear ? cache_.writtenSectors(t, l) : ~0u);
    if (fill) out.push_back({l, fill, 0});
  }
}

void RopPartition::run() {
  opaquePhase();
  res_.opaque_end = now_;
  if (approximate_)
    approximate_->run();
  else
    cycle_->run();
  resolvePhase();
  flushAccounts();
  root_.account(now_);
  res_.root_causes = root_.cycles();
  res_.end = now_;
  // Bring SystemC time up to the partition's end (it may run up to a quantum
  // ahead): the sampler samples while any partition runs, so without this the
  // grid points of the frame's last quantum would be missing from the series.
  const sc_core::sc_time end = clock_.time(now_), stamp = sc_core::sc_time_stamp();
  if (end > stamp) {
    qk_.set(end - stamp);
    qk_.sync();
  }
  done_ = true;
  done_event_.notify(sc_core::SC_ZERO_TIME);
}

}  // namespace oit::rop
