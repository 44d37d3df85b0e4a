#include "oit_rop/engines/CycleEngine.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "oit_rop/RopPartition.hpp"

namespace oit::rop {

CycleEngine::CycleEngine(RopPartition& partition) : p_(partition) {}

void CycleEngine::run() {
  if (p_.rmw_) {
    while (step<true>()) {
    }
  } else {
    while (step<false>()) {
    }
  }
}

template <bool Deferred>
bool CycleEngine::step() {
  RopPartition& p = p_;
  const Cycle now = p.now_;
  bool moved = false;

  // BlendAlu completions: release the lock now (end of blend) or after the
  // rest of the shader (end of shader).
  p.alu_.complete(now, [&](uint32_t t) {
    moved = true;
    const RopPartition::TokenInfo& k = p.tok_[t];
    if constexpr (Deferred) {
      if (!(k.flags & InRec::kCulled)) p.rmw_->complete(t);  // none: the write lands
    }
    p.releaseLines(k.pixel, k.outcome);  // the blend wrote its lines: they may be evicted now
    if (!p.s_.bounded && !(k.flags & InRec::kCulled) && k.outcome == uint8_t(model::InsertOutcome::Stored))
      p.nodeWrite();
    if (p.cfg_.lock.release == LockRelease::EndOfShader)
      p.tail_q_.push({now + p.cfg_.lock.shader_tail, t});
    else
      p.lock_.release(now, t);
  });
  while (!p.tail_q_.empty() && p.tail_q_.front().first <= now) {
    p.lock_.release(now, p.tail_q_.front().second);
    p.tail_q_.pop();
    moved = true;
  }

  // BlendArrayCache pipeline -> BlendAlu (in order).
  // (Rate limiters are asked only when something could pass: their credit
  // accrues the same whether or not they are asked every cycle.)
  const unsigned alu_slots = !p.cache_q_.empty() && p.cache_q_.front().ready <= now ? p.alu_.slots(now) : 0;
  unsigned to_alu = 0;
  bool alu_blocked = false;
  while (!p.cache_q_.empty() && p.cache_q_.front().ready <= now) {
    if (to_alu >= alu_slots) {
      alu_blocked = true;
      break;
    }
    const RopPartition::CacheEntry e = p.cache_q_.front();
    p.cache_q_.pop();
    const RopPartition::TokenInfo& k = p.tok_[e.token];
    const bool drop = (k.flags & InRec::kCulled) != 0;  // late cull: the blend drops it
    p.res_.culled_late += drop;
    const bool appends = !p.s_.bounded && !drop && k.outcome == uint8_t(model::InsertOutcome::Stored);
    p.alu_.issue(now, e.token, k.work, drop, p.blendStart(now, appends));
    ++to_alu;
  }

  // PixelLock -> BlendArrayCache: admitted fragments access their tile's line.
  unsigned accepted = 0;
  bool refused = false;
  while (p.lock_.hasReady() && accepted < p.cache_ports_) {
    const uint32_t t = p.lock_.frontReady();
    RopPartition::TokenInfo& k = p.tok_[t];
    if constexpr (Deferred) {
      // The insert, when the fragment first reaches the cache port. (A refused
      // access retries with the outcome it has: its lines are not resident, so
      // no fragment in flight can write its pixel meanwhile.)
      if (k.flags & InRec::kDeferredInsert) {
        const model::InsertOutcome o = p.rmw_->enter(t, p.pass_, p.tileOf(k.pixel));
        k.outcome = uint8_t(o);
        k.work = p.charged(p.rmw_->lastWork(), uint8_t(o));
        k.flags &= uint8_t(~InRec::kDeferredInsert);
        p.res_.merges_skipped += unsigned((o == model::InsertOutcome::Stored) & p.merge_skip_);
      }
    }
    // Its lines, as its kind reads and writes them (a late-culled fragment reads only).
    Cycle r = 0;
    if (!p.acquireGated(now, k.pixel, k.outcome, r)) {
      refused = true;
      break;
    }
    p.lock_.enterFront(now);
    const bool miss = r > now + p.cfg_.cache.hit_latency;
    p.cache_q_.push({t, r, miss, miss ? p.last_miss_ : WaitSplit{}});
    ++accepted;
  }

  // EarlyDepth -> PixelLock (or out, when culled early).
  const unsigned left = p.early_.leave(now, [&](uint32_t t) {
    const RopPartition::TokenInfo& k = p.tok_[t];
    if ((k.flags & InRec::kCulled) && p.early_cull_) {
      ++p.res_.culled_early;
      p.lock_.drop(now, t);
    } else {
      p.lock_.arrive(now, t);
    }
  });

  // Shader -> EarlyDepth.
  unsigned shaded = 0;
  p.shader_.finished(now, [&](uint32_t t) {
    ++shaded;
    p.early_.push(now, t, p.tileOf(p.tok_[t].pixel), (p.tok_[t].flags & InRec::kNeedsDepthRead) != 0);
  });

  // Issue from the routed input into the shader (needs a scoreboard entry).
  auto& q = p.front_.queue(p.id_);
  unsigned issued = 0;
  bool sb_full = false, draining = false;
  p.starving_ = false;
  if (q.empty()) p.refillInput();  // eagerly, so the input's state never depends on skipped cycles
  // A full scoreboard blocks a fragment at the head whatever the issue rate.
  // (Bitwise: front() of an empty Fifo is a stale slot, masked by !q.empty().)
  // (As unsigned: clang's -Wbitwise-instead-of-logical takes bool & bool for a typo.)
  const bool blocked = (unsigned(!q.empty()) & unsigned(!(q.front().flags & InRec::kPassEnd)) & unsigned(p.lock_.full())) != 0;
  const unsigned slots = blocked ? 0 : p.shader_.slots(now);
  while (issued < slots) {
    if (q.empty()) {
      p.refillInput();
      if (q.empty()) break;
    }
    const InRec& r = q.front();
    if (r.flags & InRec::kPassEnd) {
      if (p.lock_.occupancy() != 0) {
        draining = true;  // pass p+1 starts after pass p drained
        break;
      }
      q.pop();
      p.res_.pass_end.push_back(now);
      moved = true;
      if (++p.pass_ == p.front_.passes()) return false;
      continue;
    }
    if (p.lock_.full()) {
      sb_full = true;
      break;
    }
    // The partition's own lock address (FrameGeometry::lockAddress); owner: the primitive run's first record.
    const uint32_t t = p.lock_.allocate(r.lock, r.seq - r.prim_offset);
    const bool culled = (r.flags & InRec::kCulled) != 0;
    const model::InsertWork work = culled ? model::InsertWork{0, 0} : p.charged(r.work, r.outcome);
    if constexpr (Deferred) {
      if (r.flags & InRec::kDeferredInsert) {  // its outcome and rows come at lock entry
        Fifo<Fragment>& fq = p.front_.deferred(p.id_);
        p.rmw_->hold(t, fq.front());
        fq.pop();
      }
    } else {
      p.res_.merges_skipped += unsigned(!culled & (r.outcome == uint8_t(model::InsertOutcome::Stored)) & p.merge_skip_);
    }
    p.tok_[t] = RopPartition::TokenInfo{r.pixel, r.flags, r.outcome, work};
    p.shader_.issue(now, t, r.seq, p.pass_);
    q.pop();
    p.front_.popped(p.id_);
    ++p.res_.fragments;
    ++issued;
  }
  // Bitwise, not short-circuit: each of these is data-dependent and would be a
  // (often mispredicted) branch.
  moved |= (to_alu | accepted | left | shaded | issued) != 0;
  // Input waiting without a free entry (also when no issue slot this cycle).
  sb_full |= (unsigned(!issued) & unsigned(!q.empty()) & unsigned(!(q.front().flags & InRec::kPassEnd)) &
              unsigned(p.lock_.full())) != 0;

  // Status of every stage in this cycle (holds until the next evaluated cycle),
  // one byte per stage; the accounts are touched only for stages whose status
  // changed (most evaluated cycles change none or one).
  constexpr uint8_t kIdle = RopPartition::code(StageStatus::idle()), kBusy = RopPartition::code(StageStatus::busy());
  constexpr auto stall = [](Stall c) { return RopPartition::code(StageStatus::stall(c)); };
  const bool in_shader = p.shader_.inShader() != 0;
  const bool in_early = p.early_.size() != 0;
  uint8_t c0, c1, c2, c3, c4;
  if (issued) c0 = kBusy;
  else if (sb_full) c0 = stall(Stall::ScoreboardFull);
  else if (p.starving_) c0 = stall(Stall::InputStarved);
  else c0 = in_shader ? kBusy : kIdle;

  if (p.early_.headWaitsForDepth(now) && !left) c1 = stall(Stall::CacheMissWait);
  else if (left || in_early) c1 = kBusy;
  else c1 = in_shader ? stall(Stall::InputStarved) : kIdle;

  if (accepted) c2 = kBusy;
  else if (refused) c2 = stall(Stall::CacheMissWait);
  else if (p.lock_.waiting()) c2 = stall(Stall::LockWait);
  else c2 = in_shader || in_early ? stall(Stall::InputStarved) : kIdle;

  const bool occupied = p.lock_.occupancy() != 0;
  const bool head_waits = !p.cache_q_.empty() && p.cache_q_.front().ready > now;
  if (to_alu || accepted || (head_waits && !p.cache_q_.front().miss)) c3 = kBusy;
  else if (refused || head_waits) c3 = stall(Stall::CacheMissWait);
  else if (alu_blocked) c3 = stall(Stall::AluBusy);
  else c3 = occupied ? stall(Stall::InputStarved) : kIdle;

  if (to_alu || p.alu_.inFlight()) c4 = !p.s_.bounded && p.alu_.allWaitingAt(now) ? stall(Stall::AtomicWait) : kBusy;
  else c4 = occupied ? stall(Stall::InputStarved) : kIdle;
  // (Resolve stays idle through the transparent phase.)
  const uint64_t codes = uint64_t(c0) | uint64_t(c1) << 8 | uint64_t(c2) << 16 | uint64_t(c3) << 24 | uint64_t(c4) << 32;
  if (codes != (p.codes_ & 0xFFFFFFFFFFull)) p.setStatuses(codes, 5);

  // The cycle's root cause (DESIGN.md "Root causes"): a stage at its full rate
  // bounds the cycle (the blend ALU first: the sink; the input only when the
  // scoreboard still has room after its issue: else a faster input could not
  // have issued more, and what holds the entries bounds it); otherwise follow the
  // back-pressure to what holds the oldest work: the line the cache's head
  // waits for, a refused access (the latest miss stands for the memory it
  // waits on), the ordered lock, a depth tile, then the front end, the
  // scoreboard, and what is left: fixed latencies with nothing to overlap.
  if (c4 == stall(Stall::AtomicWait)) {
    p.root_.set(now, RootCause::Atomics);  // every blend in flight waits for the A-buffer's node counter
  } else if (alu_blocked | ((to_alu != 0) & (to_alu == alu_slots))) {
    p.root_.set(now, RootCause::Alu);
  } else if (issued ? (issued == slots) & !p.lock_.full() : (!sb_full & !p.starving_ & !draining & !q.empty())) {
    p.root_.set(now, RootCause::Input);
  } else if (head_waits && p.cache_q_.front().miss) {
    p.root_.setWait(now, p.cache_q_.front().wait);
  } else if (refused) {
    p.root_.setWait(now, p.refused_wait_);
  } else if (p.lock_.waiting()) {
    p.root_.set(now, RootCause::LockWait);
  } else if (c1 == stall(Stall::CacheMissWait)) {
    p.root_.setWait(now, p.last_depth_);
  } else if (p.starving_) {
    p.root_.set(now, RootCause::InputStarvation);
  } else {
    p.root_.set(now, sb_full ? RootCause::ScoreboardFull : RootCause::PipelineLatency);
  }

  // Next cycle at which any stage can move.
  Cycle next = now + 1;
  if (!moved) {
    const Cycle ev = nextEvent(refused, sb_full, draining);
    if (ev == kNever) {
      if (!p.starving_) throw std::logic_error(fmt::format("partition {}: nothing can move at cycle {}", p.id_, now));
      p.waitForFrontEnd();
      return true;
    }
    if (p.cfg_.skip.idle_cycles) next = std::max(ev, now + 1);
  }
  p.advance(next, true);
  return true;
}


Cycle CycleEngine::nextEvent(bool refused, bool sb_full, bool draining) {
  RopPartition& p = p_;
  const Cycle now = p.now_;
  Cycle next = std::min({p.shader_.nextFinish(now), p.early_.nextEvent(now), p.alu_.nextCompletion()});
  if (!p.tail_q_.empty()) next = std::min(next, p.tail_q_.front().first);
  if (!p.cache_q_.empty())
    next = std::min(next, p.cache_q_.front().ready > now ? p.cache_q_.front().ready : p.alu_.nextSlot(now));
  if (p.lock_.hasReady()) next = std::min(next, refused ? p.retry_at_ : now + 1);
  if (!p.front_.queue(p.id_).empty() && !sb_full && !draining) next = std::min(next, p.shader_.nextSlot(now));
  if (draining && p.lock_.occupancy() == 0) next = now + 1;
  return next;
}


}  // namespace oit::rop
