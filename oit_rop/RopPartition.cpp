#include "oit_rop/RopPartition.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

namespace oit::rop {

namespace {
constexpr unsigned kResolvePrefetch = 8;  // tiles whose lines are fetched ahead of the resolve
constexpr Cycle kPostedWindow = 1024;     // posted DRAM writes may run this far ahead
constexpr uint32_t kNodeBytes = 12;       // A-buffer node as published: rgba8 + z32 + next32
uint8_t dummy_data[1];
}  // namespace

RopPartition::RopPartition(sc_core::sc_module_name name, unsigned id, const PartitionSetup& setup,
                           MemorySystem& memory)
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
      cache_(cfg_.cache, setup.map.line_bytes, geo_.tiles(), setup.map.blend_arrays, memory, cfg_.skip.fast_clear,
             geo_.local),
      alu_(cfg_.alu, setup.format_rate, std::max(1u, setup.array_rows)),
      tok_(cfg_.lock.capacity),
      cache_q_(256),
      tail_q_(256) {
  cache_ports_ = std::max(1u, unsigned(std::ceil(double(cfg_.alu.blends_per_clock))));
  early_cull_ = cfg_.early_depth.enabled && cfg_.skip.early_depth;
  for (unsigned o = 0; o < model::kOutcomeCount; ++o)
    rows_of_[o] = uint8_t(BlendAlu::rowsFor(model::InsertOutcome(o), s_.array_rows, cfg_.skip.lazy_merge));
  merge_skip_ = cfg_.skip.lazy_merge && s_.array_rows > 1;
  payload_.set_extension(new DramExtension);  // owned (and freed) by the payload
  payload_.set_data_ptr(dummy_data);
  node_addr_ = setup.map.node_pool + (uint64_t(id) << 36);
  for (size_t i = 0; i < kStageCount; ++i) codes_ |= uint64_t(code(status_[i])) << (8 * i);
  approximate_ = cfg_.sim.engine == SimEngine::Approximate;
  SC_THREAD(run);
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
  dram->b_transport(payload_, delay);
  if (!payload_.is_response_ok()) throw std::runtime_error("DramSystem refused a transfer");
  if (write) last_write_done_ = std::max(last_write_done_, ext->done);
  return ext->done;
}

void RopPartition::advance(Cycle next, bool count_skip) {
  // Stage accounting is lazy (setStatus adds a status's span when it changes).
  const Cycle span = next - now_;
  if (count_skip && span > 1) res_.skipped_idle += span - 1;
  now_ = next;
  if (now_ >= next_sync_) {
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
}

void RopPartition::setAll(StageStatus v) {
  for (size_t i = 0; i < kStageCount; ++i) setStatus(Stage(i), v);
}

void RopPartition::setStatuses(uint64_t codes, unsigned stages) {
  for (unsigned i = 0; i < stages; ++i) {
    const uint8_t c = uint8_t(codes >> (8 * i));
    if (c != uint8_t(codes_ >> (8 * i))) setStatus(Stage(i), decode(c));
  }
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
      access(now_, s_.map.blend_arrays + uint64_t(t) * s_.map.line_bytes, s_.map.line_bytes, true,
             Surface::BlendArrays);
  const uint64_t n = front_.opaquePerPartition()[id_];
  if (n == 0) return;
  // The opaque pre-pass: its fragments enter at the input rate (depth test and
  // colour in the ROP's Z/colour path); the depth and colour of every tile
  // where an opaque fragment landed are written once, spread over the phase.
  const Cycle start = now_;
  const Cycle cycles = Cycle(std::ceil(double(n) / cfg_.input.fragments_per_clock));
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

void RopPartition::release(uint32_t t) {
  lock_.release(now_, t);
}

void RopPartition::nodeWrite() {
  // Nodes are appended to the partition's pool region; consecutive appends
  // coalesce into burst-sized DRAM writes.
  node_pending_ += kNodeBytes;
  res_.node_bytes_written += kNodeBytes;
  const uint32_t burst = std::max(1u, cfg_.dram.burst_bytes);
  while (node_pending_ >= burst) {
    access(now_, node_addr_, burst, true, Surface::BlendArrays);
    node_addr_ += burst;
    node_pending_ -= burst;
  }
}

void RopPartition::releaseLine(uint32_t tile) {
  if (cache_.release(tile)) retry_at_ = 0;  // the refused access's set has a line out of use now
}

void RopPartition::refillInput() {
  auto& q = front_.queue(id_);
  while (q.empty() && front_.canRefill()) front_.refill();
  starving_ = q.empty() && !front_.exhausted();
}

bool RopPartition::acquireGated(Cycle now, uint32_t tile, bool write, Cycle& ready) {
  // While every miss-queue entry is busy a retry would be refused again: no call
  // until the first entry frees, so the refusals counted (cache.miss_queue_full:
  // one per access that had to wait) and the cycle the access goes through do
  // not depend on how often the partition is evaluated (skip.idle_cycles).
  // A set with every way in use is retried after the release that frees one
  // of its lines (releaseLine), also independent of how often we ask.
  if (now < retry_at_) return false;
  ready = cache_.acquire(now, tile, write);
  if (ready != kNever) return true;
  retry_at_ = cache_.refusedBySet() ? kNever : cache_.missQueueFreesAt();
  return false;
}

bool RopPartition::transparentStep() {
  const Cycle now = now_;
  bool moved = false;

  // BlendAlu completions: release the lock now (end of blend) or after the
  // rest of the shader (end of shader).
  alu_.complete(now, [&](uint32_t t) {
    moved = true;
    const TokenInfo& k = tok_[t];
    releaseLine(k.tile);  // the blend wrote the line: it may be evicted now
    if (!s_.bounded && !(k.flags & InRec::kCulled) && k.outcome == uint8_t(model::InsertOutcome::Stored))
      nodeWrite();
    if (cfg_.lock.release == LockRelease::EndOfShader)
      tail_q_.push({now + cfg_.lock.shader_tail, t});
    else
      release(t);
  });
  while (!tail_q_.empty() && tail_q_.front().first <= now) {
    release(tail_q_.front().second);
    tail_q_.pop();
    moved = true;
  }

  // BlendArrayCache pipeline -> BlendAlu (in order).
  // (Rate limiters are asked only when something could pass: their credit
  // accrues the same whether or not they are asked every cycle.)
  const unsigned alu_slots = !cache_q_.empty() && cache_q_.front().ready <= now ? alu_.slots(now) : 0;
  unsigned to_alu = 0;
  bool alu_blocked = false;
  while (!cache_q_.empty() && cache_q_.front().ready <= now) {
    if (to_alu >= alu_slots) {
      alu_blocked = true;
      break;
    }
    const CacheEntry e = cache_q_.front();
    cache_q_.pop();
    const TokenInfo& k = tok_[e.token];
    const bool drop = (k.flags & InRec::kCulled) != 0;  // late cull: the blend drops it
    res_.culled_late += drop;
    alu_.issue(now, e.token, drop ? 0u : k.rows, drop);
    ++to_alu;
  }

  // PixelLock -> BlendArrayCache: admitted fragments access their tile's line.
  unsigned accepted = 0;
  bool refused = false;
  while (lock_.hasReady() && accepted < cache_ports_) {
    const uint32_t t = lock_.frontReady();
    const TokenInfo& k = tok_[t];
    const bool write = !(k.flags & InRec::kCulled) && k.outcome != uint8_t(model::InsertOutcome::Discarded);
    Cycle r = 0;
    if (!acquireGated(now, k.tile, write, r)) {
      refused = true;
      break;
    }
    lock_.enterFront(now);
    const bool miss = r > now + cfg_.cache.hit_latency;
    cache_q_.push({t, r, miss});
    ++accepted;
  }

  // EarlyDepth -> PixelLock (or out, when culled early).
  const unsigned left = early_.leave(now, [&](uint32_t t) {
    const TokenInfo& k = tok_[t];
    if ((k.flags & InRec::kCulled) && early_cull_) {
      ++res_.culled_early;
      lock_.drop(now, t);
    } else {
      lock_.arrive(now, t);
    }
  });

  // Shader -> EarlyDepth.
  unsigned shaded = 0;
  shader_.finished(now, [&](uint32_t t) {
    ++shaded;
    early_.push(now, t, tok_[t].tile, (tok_[t].flags & InRec::kNeedsDepthRead) != 0);
  });

  // Issue from the routed input into the shader (needs a scoreboard entry).
  auto& q = front_.queue(id_);
  unsigned issued = 0;
  bool sb_full = false, draining = false;
  starving_ = false;
  if (q.empty()) refillInput();  // eagerly, so the input's state never depends on skipped cycles
  // A full scoreboard blocks a fragment at the head whatever the issue rate.
  // (Bitwise: front() of an empty Fifo is a stale slot, masked by !q.empty().)
  const bool blocked = !q.empty() & !(q.front().flags & InRec::kPassEnd) & lock_.full();
  const unsigned slots = blocked ? 0 : shader_.slots(now);
  while (issued < slots) {
    if (q.empty()) {
      refillInput();
      if (q.empty()) break;
    }
    const InRec& r = q.front();
    if (r.flags & InRec::kPassEnd) {
      if (lock_.occupancy() != 0) {
        draining = true;  // pass p+1 starts after pass p drained
        break;
      }
      q.pop();
      res_.pass_end.push_back(now);
      moved = true;
      if (++pass_ == front_.passes()) return false;
      continue;
    }
    if (lock_.full()) {
      sb_full = true;
      break;
    }
    // The partition's own lock address (FrameGeometry::lockAddress); owner: the primitive run's first record.
    const uint32_t t = lock_.allocate(r.lock, r.seq - r.prim_offset);
    const bool culled = (r.flags & InRec::kCulled) != 0;
    // Table and selects instead of rowsFor()'s switch: the outcome is random per fragment.
    const uint8_t rows = culled ? 0 : rows_of_[r.outcome & 3];
    res_.merges_skipped += unsigned(!culled & (r.outcome == uint8_t(model::InsertOutcome::Stored)) & merge_skip_);
    tok_[t] = TokenInfo{r.tile, r.flags, r.outcome, rows};
    shader_.issue(now, t, r.seq, pass_);
    q.pop();
    front_.popped(id_);
    ++res_.fragments;
    ++issued;
  }
  // Bitwise, not short-circuit: each of these is data-dependent and would be a
  // (often mispredicted) branch.
  moved |= (to_alu | accepted | left | shaded | issued) != 0;
  // Input waiting without a free entry (also when no issue slot this cycle).
  sb_full |= !issued & !q.empty() & !(q.front().flags & InRec::kPassEnd) & lock_.full();

  // Status of every stage in this cycle (holds until the next evaluated cycle),
  // one byte per stage; the accounts are touched only for stages whose status
  // changed (most evaluated cycles change none or one).
  constexpr uint8_t kIdle = code(StageStatus::idle()), kBusy = code(StageStatus::busy());
  constexpr auto stall = [](Stall c) { return code(StageStatus::stall(c)); };
  const bool in_shader = shader_.inShader() != 0;
  const bool in_early = early_.size() != 0;
  uint8_t c0, c1, c2, c3, c4;
  if (issued) c0 = kBusy;
  else if (sb_full) c0 = stall(Stall::ScoreboardFull);
  else if (starving_) c0 = stall(Stall::InputStarved);
  else c0 = in_shader ? kBusy : kIdle;

  if (early_.headWaitsForDepth(now) && !left) c1 = stall(Stall::CacheMissWait);
  else if (left || in_early) c1 = kBusy;
  else c1 = in_shader ? stall(Stall::InputStarved) : kIdle;

  if (accepted) c2 = kBusy;
  else if (refused) c2 = stall(Stall::CacheMissWait);
  else if (lock_.waiting()) c2 = stall(Stall::LockWait);
  else c2 = in_shader || in_early ? stall(Stall::InputStarved) : kIdle;

  const bool occupied = lock_.occupancy() != 0;
  const bool head_waits = !cache_q_.empty() && cache_q_.front().ready > now;
  if (to_alu || accepted || (head_waits && !cache_q_.front().miss)) c3 = kBusy;
  else if (refused || head_waits) c3 = stall(Stall::CacheMissWait);
  else if (alu_blocked) c3 = stall(Stall::AluBusy);
  else c3 = occupied ? stall(Stall::InputStarved) : kIdle;

  if (to_alu || alu_.inFlight()) c4 = kBusy;
  else c4 = occupied ? stall(Stall::InputStarved) : kIdle;
  // (Resolve stays idle through the transparent phase.)
  const uint64_t codes = uint64_t(c0) | uint64_t(c1) << 8 | uint64_t(c2) << 16 | uint64_t(c3) << 24 | uint64_t(c4) << 32;
  if (codes != (codes_ & 0xFFFFFFFFFFull)) setStatuses(codes, 5);

  // Next cycle at which any stage can move.
  Cycle next = now + 1;
  if (!moved) {
    const Cycle ev = nextEvent(refused, sb_full, draining);
    if (ev == kNever) {
      if (!starving_) throw std::logic_error(fmt::format("partition {}: nothing can move at cycle {}", id_, now));
      waitForFrontEnd();
      return true;
    }
    if (cfg_.skip.idle_cycles) next = std::max(ev, now + 1);
  }
  advance(next, true);
  return true;
}

Cycle RopPartition::nextEvent(bool refused, bool sb_full, bool draining) {
  const Cycle now = now_;
  Cycle next = std::min({shader_.nextFinish(now), early_.nextEvent(now), alu_.nextCompletion()});
  if (!tail_q_.empty()) next = std::min(next, tail_q_.front().first);
  if (!cache_q_.empty())
    next = std::min(next, cache_q_.front().ready > now ? cache_q_.front().ready : alu_.nextSlot(now));
  if (lock_.hasReady()) next = std::min(next, refused ? retry_at_ : now + 1);
  if (!front_.queue(id_).empty() && !sb_full && !draining) next = std::min(next, shader_.nextSlot(now));
  if (draining && lock_.occupancy() == 0) next = now + 1;
  return next;
}

void RopPartition::approximatePhase() {
  // One visit per fragment in issue order (= submission order within the
  // partition). Each stage's time follows from when the fragment reaches it
  // and when the resource it needs is free: scoreboard entry (earliest
  // release among those in flight), shader latency (the same draw as the
  // cycle engine), depth tile (EarlyDepth's buffer and DRAM), lock address
  // (ReleaseTable), cache line (BlendArrayCache and DRAM), blend slot (ALU
  // throughput, in issue order). Differences from the cycle engine: DESIGN.md.
  //
  // The loop keeps its state (timelines, stage accounts, counters, settings)
  // in locals and writes it back after the phase: every store through a
  // pointer (a table entry, a unit's statistic) may alias a member of the same
  // type, so state kept in members was reloaded after each such store.
  constexpr unsigned kShift = RateLimiter::kShift;
  constexpr int64_t kOne = RateLimiter::kOne;
  constexpr size_t kLookahead = 8;  // records ahead whose lock entry is prefetched
  constexpr size_t kStages = 5;     // every stage but the resolve
  flushAccounts();  // every stage idle up to here; the timelines account the phase
  const Cycle start = now_;
  std::array<StageTimeline, kStages> tl;
  tl.fill(StageTimeline(start));
  std::array<StageCycles, kStages> acc;
  std::array<uint64_t, kStages> total_at_start;  // stages 1-4 account their gaps at the end
  for (size_t i = 0; i < kStages; ++i) {
    acc[i] = res_.accounts.stage[i];
    total_at_start[i] = acc[i].total();
  }
  constexpr StageStatus kBusy = StageStatus::busy();
  const bool grouped = cfg_.lock.per_primitive && cfg_.lock.granularity != LockGranularity::Pixel;
  ReleaseTable locks(owned_.size() * geo_.lock_per_tile, grouped);
  const unsigned cap = cfg_.lock.capacity;
  approx_sb_.reset(now_);
  approx_waiting_.reset(now_);
  // Issue and blend slots in 1/kOne cycles (rates need not be integers).
  const int64_t in_step = std::max<int64_t>(1, int64_t(double(kOne) / cfg_.input.fragments_per_clock));
  const double alu_rate = std::max(1e-6, double(cfg_.alu.blends_per_clock) * s_.format_rate);
  const int64_t alu_step = std::max<int64_t>(1, int64_t(double(kOne) / alu_rate));
  int64_t issue_fx = int64_t(now_) << kShift, alu_fx = 0;
  const Cycle tail = cfg_.lock.release == LockRelease::EndOfShader ? cfg_.lock.shader_tail : 0;
  const Cycle depth_latency = cfg_.early_depth.latency, hit_latency = cfg_.cache.hit_latency;
  // A culled fragment leaves at early depth when early culling is on: its
  // flag masked by this (one test per visit instead of two).
  const uint8_t leaves_early = early_cull_ ? InRec::kCulled : 0;
  // What a fragment that reaches the lock does follows from its kind,
  // culled x 4 + outcome: its blend latency, whether it writes its line and
  // whether it appends an A-buffer node. Visits are tallied by kind, and
  // the ALU's counts and the skips' follow from the tallies after the phase.
  constexpr unsigned kKinds = 8;
  static_assert(InRec::kCulledKind == 4, "a culled fragment is kind 4: culled x 4 + outcome 0");
  std::array<uint64_t, kKinds> visits{};
  std::array<Cycle, kKinds> blend_latency{};
  std::array<uint8_t, kKinds> writes{}, appends{};
  for (unsigned k = 0; k < kKinds; ++k) {
    const bool culled = k >= 4;
    const unsigned outcome = k & 3;
    blend_latency[k] = alu_.latencyOf(culled ? 0u : rows_of_[outcome]);
    writes[k] = !culled && outcome != unsigned(model::InsertOutcome::Discarded);
    appends[k] = !s_.bounded && !culled && outcome == unsigned(model::InsertOutcome::Stored);
  }
  ShaderInput::Draw latency = shader_.draw(pass_);
  LockStats ls = approx_lock_;
  uint64_t culled_early = 0, fragments = 0, depth_reads_needed = 0;
  Cycle last_release = now_, last_finish = now_;
  StageStatus gap0 = kBusy;  // stage 0 before the next issue: rate-limited (busy), starved or scoreboard full
  std::vector<Cycle> fill_ready(geo_.tiles(), 0);  // per tile: when its last fill arrives (fragment time)
  // The input queue through a cursor: its head goes back to the queue before
  // anything else may read it (a refill, a yield, a waiting front end), and a
  // new cursor is taken after anything may have pushed to it.
  auto& q = front_.queue(id_);
  auto in = q.cursor();
  for (;;) {
    if (in.empty()) {
      q.setHead(in);
      refillInput();
      in = q.cursor();
      if (in.empty()) {
        if (!starving_) throw std::logic_error(fmt::format("partition {}: input ended without its pass end", id_));
        retireCalendars();
        waitForFrontEnd();
        in = q.cursor();
        issue_fx = std::max(issue_fx, int64_t(now_) << kShift);
        gap0 = StageStatus::stall(Stall::InputStarved);
        continue;
      }
    }
    const InRec r = in.front();  // a copy: advance() lets other partitions refill (and grow) the queue
    // The record further ahead, its lock entry and cache line index nearer.
    // Slots past the tail hold older records of this partition (or zeros):
    // their lock addresses and tiles are in the tables too, so no test of the
    // queue's size is needed for a hint.
    __builtin_prefetch(&in.at(2 * kLookahead));
    const InRec& ahead = in.at(kLookahead);
    locks.prefetch(ahead.lock);
    cache_.prefetch(ahead.tile);
    if (r.flags & InRec::kPassEnd) [[unlikely]] {
      // Pass p+1 starts after pass p drained.
      in.pop();
      q.setHead(in);
      retireCalendars();
      if (last_release > now_) advance(last_release, false);
      in = q.cursor();
      issue_fx = std::max(issue_fx, int64_t(now_) << kShift);
      approx_sb_.reset(now_);
      approx_waiting_.reset(now_);
      res_.pass_end.push_back(now_);
      gap0 = StageStatus::idle();
      if (++pass_ == front_.passes()) break;
      latency = shader_.draw(pass_);
      continue;
    }
    // Scoreboard entry: when every one is in use, the earliest release frees one.
    // The calendars retire lazily: only when the sampler may read them (before
    // a yield), for a new peak, and here: releases at or before now_ (which
    // free nothing later than fx) are dropped a cycle at a time until the
    // scoreboard is not full or its earliest release is still in flight.
    int64_t fx = issue_fx;
    while (approx_sb_.size() >= cap) {
      if (approx_sb_.dropDue(now_)) continue;
      const int64_t freed = int64_t(approx_sb_.popEarliest()) << kShift;
      if (freed > fx) {
        fx = freed;
        gap0 = StageStatus::stall(Stall::ScoreboardFull);
      }
    }
    const Cycle issue = Cycle(fx >> kShift);
    issue_fx = fx + in_step;
    if (issue > now_) {
      if (issue >= next_sync_) {  // advance() yields: the sampler reads the calendars, the front end the queue
        retireCalendars();
        q.setHead(in);
        advance(issue, false);
        in = q.cursor();
      } else {
        advance(issue, false);
      }
    }
    tl[0].add(acc[0], issue, issue + 1, kBusy, gap0);
    gap0 = kBusy;

    const Cycle finish = issue + latency(r.seq);
    last_finish = std::max(last_finish, finish);
    const Cycle passed = finish + depth_latency;
    // Memory-side resources (depth-tile buffer, blend-array cache, DRAM) see
    // the fragment at its visit (issue) cycle, so their requests are booked in
    // time order; the latency they return counts from the fragment's own time.
    // (Its counts tallied: every visit is tested, those without a read were
    // decided by the HiZ.)
    Cycle early = passed;
    if (r.flags & InRec::kNeedsDepthRead) {
      ++depth_reads_needed;
      early = std::max(early, early_.depthTileReady(issue, r.tile) + (finish - issue));
    }
    tl[1].addLeavingGap(acc[1], finish, passed, kBusy);
    if (early > passed) tl[1].addLeavingGap(acc[1], passed, early, StageStatus::stall(Stall::CacheMissWait));
    Cycle release = early;  // culled early: the entry frees when the fragment leaves early depth
    if (r.flags & leaves_early) {
      ++culled_early;
    } else {
      const Cycle free = grouped ? locks.enterAfter(r.lock, r.seq - r.prim_offset) : locks.lastRelease(r.lock);
      Cycle enter = early;
      if (free > early) {
        ++ls.conflicts;
        ls.wait_cycles += free - early;
        ls.longest_wait = std::max<uint64_t>(ls.longest_wait, free - early);
        enter = free;
        approx_waiting_.push(enter);
        // (Only a wait is an interval: stages 1-4 account their gaps at the end.)
        tl[2].addLeavingGap(acc[2], early, enter, StageStatus::stall(Stall::LockWait));
      }
      const unsigned kind = r.outcome & (kKinds - 1);  // culled x 4 + outcome (InRec::kCulledKind)
      ++visits[kind];
      const bool write = writes[kind];
      const Cycle lock_enter = enter;
      // Into the cache the next cycle when admitted on arrival, in the release's
      // own cycle when admitted at one (the cycle engine's stage order).
      enter += free > early ? 0 : 1;
      // The cache in the visit's frame too (see early depth). A miss's fill
      // counts from the fragment's lock entry; a hit on a line whose fill was
      // in flight waits for that fill's own time (fill_ready), not shifted by
      // its lock wait, which already covered the older fragment that missed.
      Cycle at_cache = issue;
      bool missed;
      Cycle got = cache_.touch(at_cache, r.tile, write, missed);
      while (got == kNever) [[unlikely]] {  // the miss queue is full: retry when its first entry frees
        if (cache_.refusedBySet())  // touch() pins no line
          throw std::logic_error(fmt::format("partition {}: set refused in the approximate engine", id_));
        at_cache = std::max(at_cache + 1, cache_.missQueueFreesAt());
        got = cache_.touch(at_cache, r.tile, write, missed);
      }
      enter += at_cache - issue;  // waited for a miss-queue entry
      Cycle ready = enter + hit_latency;
      if (missed) {
        ready = got + (enter - at_cache);
        fill_ready[r.tile] = ready;
      } else if (got > at_cache + hit_latency) {
        ready = std::max(ready, fill_ready[r.tile]);
      }
      const Cycle pass_on = std::max(enter, lock_enter + 1) - 1;  // the lock stage's last cycle with it
      if (pass_on > lock_enter) tl[2].addLeavingGap(acc[2], lock_enter, pass_on, StageStatus::stall(Stall::CacheMissWait));
      tl[2].addLeavingGap(acc[2], pass_on, pass_on + 1, kBusy);
      const bool miss = ready > enter + hit_latency;
      tl[3].addLeavingGap(acc[3], enter, ready, miss ? StageStatus::stall(Stall::CacheMissWait) : kBusy);
      const int64_t slot = std::max(alu_fx, int64_t(ready) << kShift);
      alu_fx = slot + alu_step;
      const Cycle at = Cycle(slot >> kShift);
      if (at > ready) tl[3].addLeavingGap(acc[3], ready, at, StageStatus::stall(Stall::AluBusy));
      const Cycle done = at + blend_latency[kind];
      tl[4].addLeavingGap(acc[4], at, done, kBusy);
      if (appends[kind]) nodeWrite();
      release = done + tail;
      locks.released(r.lock, release);
    }
    last_release = std::max(last_release, release);
    approx_sb_.push(release);
    if (approx_sb_.size() > ls.peak_occupancy) {  // perhaps a new peak: count only those in flight
      approx_sb_.retire(now_);
      ls.peak_occupancy = std::max(ls.peak_occupancy, uint32_t(approx_sb_.size()));
    }
    in.pop();
    if (front_.hasWaiters()) {
      q.setHead(in);
      front_.popped(id_);
    }
    ++fragments;
  }
  // Shader busy until the last fragment left it; then every stage idle to the drain.
  tl[0].close(acc[0], last_finish, kBusy);
  for (size_t i = 0; i < kStages; ++i) {
    if (i > 0) tl[i].addGaps(acc[i], start, total_at_start[i]);
    tl[i].close(acc[i], now_, StageStatus::idle());
    res_.accounts.stage[i] = acc[i];
    since_[i] = now_;  // (Resolve: idle through the phase, accounted when its status changes)
  }
  for (unsigned k = 0; k < kKinds; ++k) {  // every visit arrived at the lock and entered it
    ls.arrivals += visits[k];
    ls.entries += visits[k];
  }
  approx_lock_ = ls;
  for (unsigned k = 0; k < kKinds; ++k) {
    const bool culled = k >= 4;
    alu_.countMany(culled ? 0u : rows_of_[k & 3], culled, visits[k]);
    if (culled) res_.culled_late += visits[k];
  }
  if (merge_skip_) res_.merges_skipped += visits[unsigned(model::InsertOutcome::Stored)];
  res_.culled_early += culled_early;
  res_.fragments += fragments;
  early_.countTests(fragments, fragments - depth_reads_needed);
  approx_sb_.reset(now_);
  approx_waiting_.reset(now_);
}

void RopPartition::waitForFrontEnd() {
  // Another partition's backlog is at the high watermark: wait until it drains.
  advance(now_ + 1, true);
  front_.addWaiter();
  wait(front_.drained());
  const Cycle t = clock_.cycle(sc_core::sc_time_stamp());
  if (t > now_) advance(t, false);
}

void RopPartition::resolvePhase() {
  setAll(StageStatus::idle());
  if (node_pending_) {  // flush the node write-combiner
    access(now_, node_addr_, uint32_t(node_pending_), true, Surface::BlendArrays);
    node_addr_ += node_pending_;
    node_pending_ = 0;
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
  Fifo<ResolveEntry> pf(16);
  size_t next_issue = 0;
  bool computing = false;
  uint32_t computing_tile = 0;
  Cycle compute_done = 0;
  for (;;) {
    const Cycle now = now_;
    bool moved = false;
    if (computing && now >= compute_done) {
      releaseLine(computing_tile);
      access(now, s_.map.colour + uint64_t(computing_tile) * s_.map.tile4_bytes, s_.map.tile4_bytes, true,
             Surface::Resolve);
      computing = false;
      moved = true;
      ++res_.tiles_resolved;
    }
    unsigned acquired = 0;
    bool refused = false;
    while (next_issue < tiles.size() && pf.size() < kResolvePrefetch && acquired < cache_ports_) {
      Cycle r = 0;
      if (!acquireGated(now, tiles[next_issue], false, r)) {
        refused = true;
        break;
      }
      // The tile's other inputs are fetched with its line, and the resolve of
      // the tile waits for all of them: the opaque colour it composites over
      // (where an opaque fragment landed) and, for the A-buffer, its node
      // lists (every node of the tile read once).
      const uint32_t t = tiles[next_issue];
      Cycle data = r;
      if (front_.opaqueLanded()[t] != 0)
        data = std::max(data, access(now, s_.map.colour + uint64_t(t) * s_.map.tile4_bytes, s_.map.tile4_bytes,
                                     false, Surface::Colour));
      if (!s_.bounded) {
        const uint64_t nodes = front_.tileNodes()[t];
        if (nodes) {
          const uint64_t bytes = nodes * kNodeBytes;
          data = std::max(data, access(now, s_.map.node_pool + (uint64_t(id_) << 36) + (uint64_t(t) << 12) % (uint64_t(1) << 35),
                                       uint32_t(std::min<uint64_t>(bytes, 0xFFFFFFFFu)), false, Surface::BlendArrays));
          res_.node_bytes_read += bytes;
        }
      }
      pf.push({t, data});
      ++next_issue;
      ++acquired;
      moved = true;
    }
    bool window_blocked = false;
    if (!computing && !pf.empty() && pf.front().ready <= now) {
      if (last_write_done_ > now + kPostedWindow) {
        window_blocked = true;
      } else {
        const uint32_t t = pf.front().tile;
        pf.pop();
        uint64_t work = geo_.tilePixels();
        if (!s_.bounded) work = std::max<uint64_t>(work, front_.tileNodes()[t]);  // list traversal
        computing = true;
        computing_tile = t;
        compute_done = now + std::max<Cycle>(1, Cycle(std::ceil(double(work) / px_per_clock)));
        moved = true;
      }
    }
    if (!computing && pf.empty() && next_issue == tiles.size()) break;
    if (computing) setStatus(Stage::Resolve, StageStatus::busy());
    else if (window_blocked) setStatus(Stage::Resolve, StageStatus::stall(Stall::DramBandwidth));
    else setStatus(Stage::Resolve, StageStatus::stall(Stall::CacheMissWait));
    Cycle next = now + 1;
    if (!moved && cfg_.skip.idle_cycles) {
      next = kNever;
      if (computing) next = std::min(next, compute_done);
      if (!pf.empty() && pf.front().ready > now) next = std::min(next, pf.front().ready);
      if (window_blocked) next = std::min(next, last_write_done_ - kPostedWindow);
      if (refused) next = std::min(next, retry_at_);
      if (!computing && !pf.empty() && pf.front().ready <= now && !window_blocked) next = now + 1;
      next = std::max(next == kNever ? now + 1 : next, now + 1);
    }
    advance(next, true);
  }
  // The frame ends when the last posted write reached DRAM.
  setStatus(Stage::Resolve, StageStatus::stall(Stall::DramBandwidth));
  const Cycle end = std::max(now_, last_write_done_);
  if (end > now_) {
    if (cfg_.skip.idle_cycles)
      advance(end, true);
    else
      while (now_ < end) advance(now_ + 1, true);
  }
  setStatus(Stage::Resolve, StageStatus::idle());
}

void RopPartition::run() {
  opaquePhase();
  res_.opaque_end = now_;
  if (approximate_)
    approximatePhase();
  else
    while (transparentStep()) {
    }
  resolvePhase();
  flushAccounts();
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
