#include "oit_rop/engines/ApproximateEngine.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <stdexcept>
#include <vector>

#include "oit_rop/RopPartition.hpp"
#include "oit_rop/memory/PortCalendar.hpp"

namespace oit::rop {

void ApproximateEngine::run() {
  RopPartition& p = p_;
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
  p.flushAccounts();  // every stage idle up to here; the timelines account the phase
  const Cycle start = p.now_;  // the phase's first cycle
  // Root causes (DESIGN.md "Root causes", approximate engine): the partition's
  // time moves from issue to issue. A span the input's rate decides is the
  // input's (the ALU's when its blends are booked beyond it); a span a full
  // scoreboard or a pass's drain decides is shared out in proportion to the
  // delays the fragments met since the last such span (DelayShares).
  p.root_.account(p.now_);
  DelayShares shares;
  shares.setBusShare(BusShareFn::of(p.memory_));
  // A wait's span is split once the issues have passed its block of bus
  // record and a quantum (other partitions book up to a quantum behind):
  // requests booked later put their data after their own issue.
  const Cycle settle_lag = (Cycle(1) << MemorySystem::kBusyBlockShift) + p.quantum_;
  Cycle charged = p.now_;  // root causes accounted up to here
  Cycle alu_run_from = 0, alu_run_to = 0;  // the latest run of blends that queued for ALU slots
  Cycle miss_from = 0, miss_to = 0;  // the latest miss's wait in the visit frame (hits under it)
  Cycle refused_to = 0;  // when the latest access the miss queue refused got its entry
  Cycle alu_work_to = 0;  // the latest end of a blend's work (the ALU busy up to there)
  const Cycle atomic_latency = p.cfg_.abuffer.atomic_latency;
  std::array<StageTimeline, kStages> tl;
  tl.fill(StageTimeline(start));
  std::array<StageCycles, kStages> acc;
  std::array<uint64_t, kStages> total_at_start;  // stages 1-4 account their gaps at the end
  for (size_t i = 0; i < kStages; ++i) {
    acc[i] = p.res_.accounts.stage[i];
    total_at_start[i] = acc[i].total();
  }
  constexpr StageStatus kBusy = StageStatus::busy();
  const bool grouped = p.cfg_.lock.per_primitive && p.cfg_.lock.granularity != LockGranularity::Pixel;
  // Lock addresses are local tile x addresses per tile + offset, and local
  // tile numbers run to the largest of the partition's own (not its count:
  // with tiles_x not a multiple of the partitions, a row holds fewer than
  // ceil(tiles_x / N) of them). Sized by the count, 3 or 6 partitions wrote
  // past the table's end.
  uint32_t local_tiles = 0;
  for (uint32_t t : p.owned_) local_tiles = std::max(local_tiles, p.geo_.localOf(t) + 1);
  ReleaseTable locks(size_t(local_tiles) * p.geo_.lock_per_tile, grouped);
  const unsigned cap = p.cfg_.lock.capacity;
  scoreboard_.reset(p.now_);
  waiting_.reset(p.now_);
  // Issue and blend slots in 1/kOne cycles (rates need not be integers).
  const int64_t in_step = std::max<int64_t>(1, int64_t(double(kOne) / p.cfg_.input.fragments_per_clock));
  const double alu_rate = std::max(1e-6, double(p.cfg_.alu.blends_per_clock) * p.s_.format_rate);
  // Blend slots by time: each fragment takes the earliest slot at or after
  // the cycle its line is there (the cycle engine's ALU serves fragments in
  // the order they enter the cache stage, i.e. the order their locks admit
  // them). Handed out in visit (issue) order, a fragment that waited long for
  // its lock pushed every younger one's blend behind its own: dgpu, particles
  // 640x360, mlab k = 2 came out +41.8 % (DESIGN.md).
  PortCalendar alu_slots(alu_rate, 0);
  int64_t issue_fx = int64_t(p.now_) << kShift;
  const Cycle tail = p.cfg_.lock.release == LockRelease::EndOfShader ? p.cfg_.lock.shader_tail : 0;
  const Cycle depth_latency = p.cfg_.early_depth.latency, hit_latency = p.cfg_.cache.hit_latency;
  // A culled fragment leaves at early depth when early culling is on: its
  // flag masked by this (one test per visit instead of two).
  const uint8_t leaves_early = p.early_cull_ ? InRec::kCulled : 0;
  // What a fragment that reaches the lock does follows from its kind,
  // culled x 4 + outcome: its blend latency, the lines it touches
  // (FragmentLines) and whether it appends an A-buffer node. Visits are tallied by kind, and
  // the skips' counts follow from the tallies after the phase; the blend's
  // latency adds the work the insert reported (InRec::work).
  constexpr unsigned kKinds = 8;
  static_assert(InRec::kCulledKind == 4, "a culled fragment is kind 4: culled x 4 + outcome 0");
  std::array<uint64_t, kKinds> visits{};
  std::array<uint8_t, kKinds> appends{};
  for (unsigned k = 0; k < kKinds; ++k) {
    const bool culled = k >= 4;
    const unsigned outcome = k & 3;
    appends[k] = !p.s_.bounded && !culled && outcome == unsigned(model::InsertOutcome::Stored);
  }
  ShaderInput::Draw latency = p.shader_.draw(p.pass_);
  LockStats ls = lock_stats_;
  uint64_t culled_early = 0, fragments = 0, depth_reads_needed = 0;
  Cycle last_release = p.now_, last_finish = p.now_;
  // The latest issue: the calendars' time. The partition's time (p.now_, at
  // which the memory side is asked) is at least that, and ahead of it while a
  // miss the miss queue refused waits for an entry (below).
  Cycle visit_now = p.now_;
  StageStatus gap0 = kBusy;  // stage 0 before the next issue: rate-limited (busy), starved or scoreboard full
  std::vector<Cycle> fill_ready(p.geo_.tiles(), 0);  // per tile: when its last fill arrives (fragment time)
  PortCalendar ed_exit(p.cfg_.input.fragments_per_clock, 0);  // its leaves at its rate, for fragments held
  InOrderBlockers ed_blockers;  // EarlyDepth's order (a pass drains before the next starts: per pass is per phase)
  // The input queue through a cursor: its head goes back to the queue before
  // anything else may read it (a refill, a yield, a waiting front end), and a
  // new cursor is taken after anything may have pushed to it.
  auto& q = p.front_.queue(p.id_);
  auto in = q.cursor();
  // The partition's time to t (later than now): p.advance() yields at a
  // quantum boundary, and then the sampler reads the calendars (retired up to
  // calendars_at first) and the front end the queue (the cursor's head back).
  // Always inlined: per fragment (small scene: 2,185.0 instructions per record
  // with it, 2,189.9 without, 2,185.5 as two written-out copies).
  auto moveTo = [&](Cycle t, Cycle calendars_at) __attribute__((always_inline)) {
    if (t <= p.now_) return;
    if (t >= p.next_sync_) {
      retireCalendars(calendars_at);
      q.setHead(in);
      p.advance(t, false);
      in = q.cursor();
    } else {
      p.advance(t, false);
    }
  };
  for (;;) {
    if (in.empty()) {
      q.setHead(in);
      p.refillInput();
      in = q.cursor();
      if (in.empty()) {
        if (!p.starving_) throw std::logic_error(fmt::format("partition {}: input ended without its pass end", p.id_));
        retireCalendars(visit_now);
        const Cycle wait_from = p.now_;
        p.waitForFrontEnd();
        visit_now += p.now_ - wait_from;  // the wait in the visits' frame (the partition's time may lead it)
        if (visit_now > charged) p.root_.add(RootCause::InputStarvation, visit_now - charged);
        charged = std::max(charged, visit_now);
        in = q.cursor();
        issue_fx = std::max(issue_fx, int64_t(visit_now) << kShift);
        gap0 = StageStatus::stall(Stall::InputStarved);
        continue;
      }
    }
    const InRec r = in.front();  // a copy: p.advance() lets other partitions refill (and grow) the queue
    // The record further ahead, its lock entry and cache line index nearer.
    // Slots past the tail hold older records of this partition (or zeros):
    // their lock addresses and tiles are in the tables too, so no test of the
    // queue's size is needed for a hint.
    __builtin_prefetch(&in.at(2 * kLookahead));
    const InRec& ahead = in.at(kLookahead);
    locks.prefetch(ahead.lock);
    p.cache_.prefetch(p.tileOf(ahead.pixel));
    if (r.flags & InRec::kPassEnd) [[unlikely]] {
      // Pass p+1 starts after pass p drained.
      in.pop();
      q.setHead(in);
      retireCalendars(p.now_);
      if (last_release > p.now_) p.advance(last_release, false);
      visit_now = p.now_;
      if (p.now_ > charged) shares.chargeTo(p.root_, p.now_ - charged, RootCause::PipelineLatency);
      shares.finish(p.root_);
      charged = std::max(charged, p.now_);
      in = q.cursor();
      issue_fx = std::max(issue_fx, int64_t(p.now_) << kShift);
      scoreboard_.reset(p.now_);
      waiting_.reset(p.now_);
      p.res_.pass_end.push_back(p.now_);
      gap0 = StageStatus::idle();
      if (++p.pass_ == p.front_.passes()) break;
      latency = p.shader_.draw(p.pass_);
      continue;
    }
    // Scoreboard entry: when every one is in use, the earliest release frees one.
    // The calendars retire lazily: only when the sampler may read them (before
    // a yield), for a new peak, and here: releases at or before visit_now (which
    // free nothing later than fx) are dropped a cycle at a time until the
    // scoreboard is not full or its earliest release is still in flight.
    int64_t fx = issue_fx;
    const Cycle by_rate = Cycle(issue_fx >> kShift);
    bool sb_delayed = false;  // a full scoreboard decided the issue
    while (scoreboard_.size() >= cap) {
      if (scoreboard_.dropDue(visit_now)) continue;
      const int64_t freed = int64_t(scoreboard_.popEarliest()) << kShift;
      if (freed > fx) {
        fx = freed;
        sb_delayed = true;
        gap0 = StageStatus::stall(Stall::ScoreboardFull);
      }
    }
    const Cycle issue = Cycle(fx >> kShift);
    visit_now = std::max(visit_now, issue);
    issue_fx = fx + in_step;
    if (issue > charged) {
      // Up to the input's slot: the input's (the ALU's where blends queue for
      // it then: the sink at its rate); then the scoreboard's. When a full
      // scoreboard decided the issue, all of it is the scoreboard's: a faster
      // input could not have issued sooner (the cycle engine's rule too).
      const Cycle rate_end = sb_delayed ? charged : std::clamp(by_rate, charged, issue);
      const Cycle alu = std::min(rate_end, alu_run_to) > std::max(charged, alu_run_from)
                            ? std::min(rate_end, alu_run_to) - std::max(charged, alu_run_from) : 0;
      p.root_.add(RootCause::Alu, alu);
      p.root_.add(RootCause::Input, rate_end - charged - alu);
      shares.chargeTo(p.root_, issue - rate_end, RootCause::ScoreboardFull);
      if (issue > settle_lag) shares.settle(p.root_, issue - settle_lag);
      charged = issue;
    }
    moveTo(issue, p.now_);
    tl[0].add(acc[0], issue, issue + 1, kBusy, gap0);
    gap0 = kBusy;
    alu_slots.retireBefore(issue);  // no blend of this or a later fragment starts before its issue

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
      early = std::max(early, p.early_.depthTileReady(issue, p.tileOf(r.pixel)) + (finish - issue));
    }
    // EarlyDepth is in order: not before a fragment that arrived earlier and
    // waits for its depth tile (the wait is that tile's, as the cycle
    // engine's back-pressure walk charges it).
    if (!ed_blockers.empty()) {
      const Cycle held = ed_blockers.heldUntil(finish, issue);
      if (held >= early) {  // held: it leaves at the stage's rate from the head's leave on
        Cycle slot_end;
        ed_exit.retireBefore(issue);
        ed_exit.book(held, 1, early, slot_end);
      }
    }
    if (early > passed) {
      shares.addLike(early - passed, issue, issue + (early - finish), p.last_depth_);
      ed_blockers.add(finish, early);
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
        waiting_.push(enter);
        shares.add(RootCause::LockWait, free - early);
        // (Only a wait is an interval: stages 1-4 account their gaps at the end.)
        tl[2].addLeavingGap(acc[2], early, enter, StageStatus::stall(Stall::LockWait));
      }
      const unsigned kind = r.outcome & (kKinds - 1);  // culled x 4 + outcome (InRec::kCulledKind)
      ++visits[kind];
      // Its lines, as its kind reads and writes them (a late-culled fragment reads only).
      const uint32_t tile = p.tileOf(r.pixel);
      const std::span<const LineTouch> lines = p.linesOf(r.pixel, uint8_t(kind));
      const Cycle lock_enter = enter;
      // Into the cache the next cycle when admitted on arrival, in the release's
      // own cycle when admitted at one (the cycle engine's stage order).
      enter += free > early ? 0 : 1;
      // The cache in the visit's frame too (see early depth). A miss's fill
      // counts from the fragment's lock entry; a hit on a line whose fill was
      // in flight waits for that fill's own time (fill_ready), not shifted by
      // its lock wait, which already covered the older fragment that missed.
      // A miss the miss queue refuses goes below when an entry frees
      // (at_cache), and the partition's time moves there first: on a
      // miss-queue-bound frame at_cache runs up to ~16 k cycles ahead of the
      // issues, and booked there while the partitions' times stayed at their
      // issues, the fills reached the l2 and DRAM out of time order (1,190
      // cycles late on average) and took 394 cycles instead of the cycle
      // engine's 244 (DESIGN.md, "The continuum paper's Titan X point").
      Cycle at_cache = issue;
      bool missed;
      p.memory_.resetProbe();
      uint64_t misses = p.cache_.stats().misses;
      Cycle got = p.cache_.touch(at_cache, tile, lines, missed);
      while (got == kNever) [[unlikely]] {  // the miss queue lacks entries: retry when enough free
        if (p.cache_.refusedBySet())  // touch() pins no line
          throw std::logic_error(fmt::format("partition {}: set refused in the approximate engine", p.id_));
        // Waiting for a miss-queue entry is waiting for the miss that frees
        // it (MissWaits, the cycle engine's rule), for the tail of that
        // miss's wait: the cycle engine's in-order cache stage has one
        // refused access at its head, from when the one before it got its
        // entry (refused_to) to this entry's freeing, and charges it that
        // part of the miss's split. Here every refused access waits from its
        // own issue, the waits overlapping (DelayShares adds them up), so its
        // cycles go in the proportions of that tail. (Until session 21: the
        // proportions of the latest miss's whole wait, mostly its unloaded
        // access at the front: dram_latency 4.5 % of the activate-bound frame,
        // test_bounds.cpp DramActivateLimitFrame, against 0.4 % on the cycle
        // engine.) No miss kept frees it (a fast-clear fill does): the latest miss's.
        const Cycle frees = std::max(at_cache + 1, p.cache_.missQueueFreesAt());
        if (const MissWait* m = p.miss_waits_.freeingMiss(frees)) {
          Cycle head = std::max({at_cache, m->from, refused_to});
          if (head >= frees) head = m->from;  // (an earlier refused access waited past it: the whole wait)
          shares.addLike(frees - at_cache, head, head < frees ? frees : m->ready, m->wait);
        } else {
          shares.addLike(frees - at_cache, miss_from, miss_to, p.last_miss_);
        }
        at_cache = frees;
        refused_to = std::max(refused_to, frees);
        moveTo(at_cache, visit_now);
        p.memory_.resetProbe();
        misses = p.cache_.stats().misses;
        got = p.cache_.touch(at_cache, tile, lines, missed);
      }
      enter += at_cache - issue;  // waited for a miss-queue entry
      Cycle ready = enter + hit_latency;
      if (missed) {
        ready = got + (enter - at_cache);
        fill_ready[tile] = ready;
        if (p.cache_.stats().misses != misses) {
          p.last_miss_ = splitWait(at_cache, got, p.memory_.probe(), p.miss_rest_);
          p.miss_waits_.add(at_cache, got, p.last_miss_);
        } else {
          p.last_miss_ = WaitSplit{at_cache, at_cache, at_cache, RootCause::RopCacheMiss};
        }
        miss_from = at_cache;
        miss_to = got;
        shares.addWait(at_cache, got, p.last_miss_);
      } else if (got > at_cache + hit_latency) {
        const Cycle before = ready;
        ready = std::max(ready, fill_ready[tile]);
        shares.addLike(ready - before, miss_from, miss_to, p.last_miss_);
      }
      const Cycle pass_on = std::max(enter, lock_enter + 1) - 1;  // the lock stage's last cycle with it
      if (pass_on > lock_enter) tl[2].addLeavingGap(acc[2], lock_enter, pass_on, StageStatus::stall(Stall::CacheMissWait));
      tl[2].addLeavingGap(acc[2], pass_on, pass_on + 1, kBusy);
      const bool miss = ready > enter + hit_latency;
      tl[3].addLeavingGap(acc[3], enter, ready, miss ? StageStatus::stall(Stall::CacheMissWait) : kBusy);
      Cycle at, slot_end;
      alu_slots.book(ready, 1, at, slot_end);
      if (at > ready) {
        shares.add(RootCause::Alu, at - ready);
        // Blends queue for the ALU's rate over [alu_run_from, alu_run_to): extend the run or start one.
        if (ready > alu_run_to) alu_run_from = ready;
        alu_run_to = std::max(alu_run_to, at);
      }
      if (at > ready) tl[3].addLeavingGap(acc[3], ready, at, StageStatus::stall(Stall::AluBusy));
      const bool culled_kind = kind >= 4;
      const model::InsertWork work = culled_kind ? model::InsertWork{0, 0} : p.charged(r.work, r.outcome);
      p.alu_.count(work, culled_kind);
      const Cycle blend_start = p.blendStart(at, appends[kind]);
      const Cycle done = blend_start + p.alu_.latency(work);
      if (blend_start > at) {
        tl[4].addLeavingGap(acc[4], at, blend_start, StageStatus::stall(Stall::AtomicWait));
        // The A-buffer's node counter: its queueing (the counter's rate,
        // shared by the partitions) delays the blend; its latency, a fixed
        // one like the blend's own, only where no earlier blend's work
        // overlaps it (the cycle engine's atomic_wait: the cycles where every
        // blend in flight waits for its atomic).
        const Cycle served = blend_start - atomic_latency;
        const Cycle exposed_from = std::max(served, alu_work_to);
        shares.add(RootCause::Atomics,
                   (served > at ? served - at : 0) + (blend_start > exposed_from ? blend_start - exposed_from : 0));
      }
      tl[4].addLeavingGap(acc[4], blend_start, done, kBusy);
      alu_work_to = std::max(alu_work_to, done);
      if (appends[kind]) p.nodeWrite();
      release = done + tail;
      locks.released(r.lock, release);
    }
    last_release = std::max(last_release, release);
    scoreboard_.push(release);
    if (scoreboard_.size() > ls.peak_occupancy) {  // perhaps a new peak: count only those in flight
      scoreboard_.retire(visit_now);
      ls.peak_occupancy = std::max(ls.peak_occupancy, uint32_t(scoreboard_.size()));
    }
    in.pop();
    if (p.front_.hasWaiters()) {
      q.setHead(in);
      p.front_.popped(p.id_);
    }
    ++fragments;
  }
  if (p.now_ > charged) shares.chargeTo(p.root_, p.now_ - charged, RootCause::PipelineLatency);
  shares.finish(p.root_);
  p.root_.skipTo(p.now_);
  // Shader busy until the last fragment left it; then every stage idle to the drain.
  tl[0].close(acc[0], last_finish, kBusy);
  for (size_t i = 0; i < kStages; ++i) {
    if (i > 0) tl[i].addGaps(acc[i], start, total_at_start[i]);
    tl[i].close(acc[i], p.now_, StageStatus::idle());
    p.res_.accounts.stage[i] = acc[i];
    p.since_[i] = p.now_;  // (Resolve: idle through the phase, accounted when its status changes)
  }
  for (unsigned k = 0; k < kKinds; ++k) {  // every visit arrived at the lock and entered it
    ls.arrivals += visits[k];
    ls.entries += visits[k];
  }
  lock_stats_ = ls;
  for (unsigned k = 0; k < kKinds; ++k) {
    const bool culled = k >= 4;
    if (culled) p.res_.culled_late += visits[k];
  }
  if (p.merge_skip_) p.res_.merges_skipped += visits[unsigned(model::InsertOutcome::Stored)];
  p.res_.culled_early += culled_early;
  p.res_.fragments += fragments;
  p.early_.countTests(fragments, fragments - depth_reads_needed);
  scoreboard_.reset(p.now_);
  waiting_.reset(p.now_);
}


}  // namespace oit::rop
