// Building blocks of the approximate engine (sim.engine = approximate,
// DESIGN.md "Approximate engine"): a partition visits each fragment once, in
// issue order, and computes its stage times from the free times of the
// resources it meets instead of evaluating cycles.
//
// StageTimeline: one stage's accounts built from the intervals the fragments
// spend in it (busy, or a stall by cause). Intervals arrive roughly in time
// order; the part of an interval before the timeline's cursor (time already
// accounted) is dropped, so busy + stalls + idle = total holds by
// construction, and gaps between intervals count as input-starved.
//
// ReleaseTable: the ordered pixel lock as free times. A fragment may enter
// its lock address when every older fragment of the address has released it;
// fragments are visited in submission order, so that is the latest release so
// far. With owners (lock.per_primitive at quad/tile granularity), fragments of
// the owner that holds the address wait only for the owners before it.
//
// ReleaseCalendar: the release cycles of the fragments in flight (the
// scoreboard), as a calendar of per-cycle counts. The engine asks two things
// of it: retire everything due by now (time only moves forward) and, when
// every entry is in use, the earliest release. A binary heap did both in
// O(log n) with unpredictable branches (~40 % of the engine's time at 2,048
// entries); the calendar keeps the next kWindow cycles as counts with a
// bitmap and its earliest cycle exact (a retire with nothing due is O(1)),
// and the rare later releases in a small heap. The engine retires lazily:
// a full scoreboard drops due cycles (dropDue) or pops, and retire() runs
// only where the exact count is read (a yield, a new peak).
//
// InOrderBlockers: an in-order stage (the cycle engine's EarlyDepth) seen
// from visits in issue order. A fragment leaves such a stage no earlier than
// every fragment that arrived before it; arrivals (issue + shader latency)
// are not in visit order, so the engine keeps the fragments that left later
// than their own latency allowed (blockers: a head waiting for its depth
// tile) as a staircase of (arrival, leave), leave rising with arrival, and a
// fragment leaves no earlier than the latest leave of those that arrived at
// or before its own arrival. (Those visited later but arriving earlier are
// not seen: a shorter shader latency behind a blocker is missed.)
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <vector>

#include "oit_rop/TimingStats.hpp"
#include "oit_rop/Types.hpp"

namespace oit::rop {

class StageTimeline {
 public:
  explicit StageTimeline(Cycle start = 0) : cursor_(start) {}
  // [from, to) with status s; the part before the cursor is already accounted.
  // A gap between the cursor and `from` counts as `gap`.
  void add(StageCycles& acc, Cycle from, Cycle to, StageStatus s, StageStatus gap = StageStatus::stall(Stall::InputStarved)) {
    if (to <= cursor_) return;
    if (from > cursor_) {
      acc.add(gap, from - cursor_);
      cursor_ = from;
    }
    acc.add(s, to - cursor_);
    cursor_ = to;
  }
  // add() with the gap left out: the gaps are the cycles between the start
  // and the cursor that no interval covered, accounted at once by addGaps()
  // (a subtraction at the end instead of a test and an add per interval).
  void addLeavingGap(StageCycles& acc, Cycle from, Cycle to, StageStatus s) {
    if (to <= cursor_) return;
    acc.add(s, to - std::max(from, cursor_));
    cursor_ = to;
  }
  // Accounts the gaps addLeavingGap() left, up to the cursor, as input-starved:
  // `start` is the timeline's start, `total_at_start` acc's total then.
  void addGaps(StageCycles& acc, Cycle start, uint64_t total_at_start) const {
    const uint64_t covered = acc.total() - total_at_start;
    acc.add(StageStatus::stall(Stall::InputStarved), (cursor_ - start) - covered);
  }
  // Accounts up to `end` (a gap counts as `tail`); no-op when already there.
  void close(StageCycles& acc, Cycle end, StageStatus tail) {
    if (end > cursor_) {
      acc.add(tail, end - cursor_);
      cursor_ = end;
    }
  }
  Cycle cursor() const { return cursor_; }

 private:
  Cycle cursor_;
};

class ReleaseTable {
 public:
  // grouped: owners matter (else every visit waits for all before it).
  ReleaseTable(size_t addresses, bool grouped)
      : last_(addresses, 0), before_(grouped ? addresses : 0, 0), owner_(grouped ? addresses : 0, kNoOwner) {}
  // The cycle a fragment of `owner` (the first record of its primitive run)
  // may enter `address`: after every release of the owners before it.
  Cycle enterAfter(uint32_t address, uint32_t owner) {
    if (owner_.empty()) return last_[address];
    if (owner_[address] != owner) {  // a new holder: it waits for everything so far
      owner_[address] = owner;
      before_[address] = last_[address];
    }
    return before_[address];
  }
  // enterAfter() of a table without owners (grouped = false): the latest release so far.
  Cycle lastRelease(uint32_t address) const { return last_[address]; }
  // A fragment a few visits ahead will ask about `address`: its entry is a
  // cache miss (the table spans the partition's pixels), so fetch it now.
  // (A hint: `address` may be a stale slot's, 0 on an empty table.)
  void prefetch(uint32_t address) const { __builtin_prefetch(last_.data() + address); }
  // The fragment last asked about at `address` releases it at `release`.
  void released(uint32_t address, Cycle release) { last_[address] = std::max(last_[address], release); }

 private:
  static constexpr uint32_t kNoOwner = ~uint32_t(0);
  std::vector<Cycle> last_;      // latest release of any visit so far
  std::vector<Cycle> before_;    // grouped: latest release of the holders before the current one
  std::vector<uint32_t> owner_;  // grouped: the current holder
};

class ReleaseCalendar {
 public:
  static constexpr unsigned kWindow = 16384;  // cycles held as counts; later releases wait in a heap

  // Empty, every cycle before `now` + 1 retired.
  void reset(Cycle now) {
    for (size_t w = 0; w < kWords; ++w)
      for (uint64_t b = bits_[w]; b; b &= b - 1) counts_[w * 64 + size_t(std::countr_zero(b))] = 0;
    bits_.fill(0);
    later_.clear();
    base_ = now + 1;
    next_ = kNone;
    size_ = due_ = 0;
  }
  size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }

  void push(Cycle t) {
    ++size_;
    if (t < base_) {
      ++due_;  // already due: dropped by the next retire(), or popped first by popEarliest()
    } else if (t - base_ < kWindow) {
      add(t);
    } else {
      later_.push_back(t);
      std::push_heap(later_.begin(), later_.end(), std::greater<Cycle>());
    }
  }

  // Drops every entry released at or before `now` (never called with a
  // `now` below an earlier one's).
  void retire(Cycle now) {
    size_ -= due_;
    due_ = 0;
    if (now < base_) return;
    if (now < next_) {  // nothing in the counts is due (the common call: O(1))
      base_ = now + 1;
      if (!later_.empty()) pullLater();
      return;
    }
    if (now - base_ >= kWindow) {  // every count is due
      for (size_t w = 0; w < kWords; ++w)
        for (uint64_t b = bits_[w]; b; b &= b - 1) {
          const size_t i = w * 64 + size_t(std::countr_zero(b));
          size_ -= counts_[i];
          counts_[i] = 0;
        }
      bits_.fill(0);
    } else {
      for (Cycle c = next_; c <= now;) {  // word by word over [next_, now]
        const size_t i = size_t(c & kMask), w = i / 64, lo = i % 64;
        const size_t hi = size_t(std::min<Cycle>(63, lo + (now - c)));  // last bit of this word in range
        const uint64_t span = (~uint64_t(0) << lo) & (~uint64_t(0) >> (63 - hi));
        for (uint64_t b = bits_[w] & span; b; b &= b - 1) {
          const size_t j = w * 64 + size_t(std::countr_zero(b));
          size_ -= counts_[j];
          counts_[j] = 0;
        }
        bits_[w] &= ~span;
        c += hi - lo + 1;
      }
    }
    base_ = now + 1;
    next_ = findFrom(base_);
    if (!later_.empty()) pullLater();
  }

  // Drops the releases of the earliest cycle if it is at or before `now`
  // (and those pushed already due); false when nothing is due. A full
  // scoreboard calls it before popEarliest(): a bucket at a time is cheaper
  // than popping its releases one by one.
  bool dropDue(Cycle now) {
    if (due_) {
      size_ -= due_;
      due_ = 0;
      return true;
    }
    if (next_ > now) return false;  // also kNone
    const size_t i = size_t(next_ & kMask);
    size_ -= counts_[i];
    counts_[i] = 0;
    bits_[i / 64] &= ~(uint64_t(1) << (i % 64));
    next_ = findFrom(next_ + 1);
    return true;
  }

  // Removes and returns the earliest release; an entry already due returns
  // the last retired cycle (every caller compares it with a later time).
  Cycle popEarliest() {
    if (size_ == 0) throw std::logic_error("ReleaseCalendar::popEarliest on an empty calendar");
    --size_;
    if (due_) {
      --due_;
      return base_ - 1;
    }
    if (next_ != kNone) {
      const Cycle t = next_;
      const size_t i = size_t(t & kMask);
      if (--counts_[i] == 0) {
        bits_[i / 64] &= ~(uint64_t(1) << (i % 64));
        next_ = findFrom(t + 1);
      }
      return t;
    }
    std::pop_heap(later_.begin(), later_.end(), std::greater<Cycle>());
    const Cycle t = later_.back();
    later_.pop_back();
    return t;
  }

 private:
  static constexpr size_t kWords = kWindow / 64;
  static constexpr Cycle kMask = kWindow - 1;
  static constexpr Cycle kNone = ~Cycle(0);
  static_assert((kWindow & (kWindow - 1)) == 0 && kWindow >= 64);
  void add(Cycle t) {  // base_ <= t < base_ + kWindow
    const size_t i = size_t(t & kMask);
    ++counts_[i];
    bits_[i / 64] |= uint64_t(1) << (i % 64);
    next_ = std::min(next_, t);
  }
  // The earliest cycle in [from, base_ + kWindow) with a count, kNone if none
  // (base_ <= from): the bitmap from from's bit round to base_'s.
  Cycle findFrom(Cycle from) const {
    const Cycle end = base_ + kWindow;
    if (from >= end) return kNone;
    const size_t i0 = size_t(from & kMask);
    const Cycle left = end - from;  // cycles to look at, <= kWindow
    for (size_t k = 0; k <= kWords; ++k) {
      const size_t w = (i0 / 64 + k) % kWords;
      uint64_t b = bits_[w];
      if (k == 0) b &= ~uint64_t(0) << (i0 % 64);
      if (b) {
        const Cycle d = (Cycle(w * 64 + size_t(std::countr_zero(b))) - Cycle(i0)) & kMask;
        return d < left ? from + d : kNone;
      }
    }
    return kNone;
  }
  // Moves the heap's releases that base_'s advance brought into the window.
  void pullLater() {
    while (!later_.empty() && later_.front() < base_ + kWindow) {
      std::pop_heap(later_.begin(), later_.end(), std::greater<Cycle>());
      const Cycle t = later_.back();
      later_.pop_back();
      if (t < base_) --size_;
      else add(t);
    }
  }
  std::array<uint32_t, kWindow> counts_{};
  std::array<uint64_t, kWords> bits_{};
  std::vector<Cycle> later_;  // min-heap of releases at base_ + kWindow or later
  Cycle base_ = 1;            // cycles before it are retired; the counts hold [base_, base_ + kWindow)
  Cycle next_ = kNone;        // the earliest cycle with a count (kNone: none)
  size_t size_ = 0, due_ = 0;
};

class InOrderBlockers {
 public:
  bool empty() const { return first_ == steps_.size(); }
  // The latest leave of the blockers that arrived at or before `arrival`
  // (0: none). Blockers that left at or before `floor` are dropped first (no
  // later visit can arrive before `floor` and be held by them).
  Cycle heldUntil(Cycle arrival, Cycle floor) {
    while (first_ < steps_.size() && steps_[first_].leave <= floor) ++first_;
    if (first_ == steps_.size()) {
      steps_.clear();
      first_ = 0;
      return 0;
    }
    // Leaves rise with arrivals: the last step at or before `arrival` holds it.
    for (size_t i = steps_.size(); i-- > first_;)
      if (steps_[i].arrival <= arrival) return steps_[i].leave;
    return 0;
  }
  // A fragment that arrived at `arrival` left at `leave`, later than its own
  // latency allowed.
  void add(Cycle arrival, Cycle leave) {
    size_t i = steps_.size();  // the insertion point: after every step arriving at or before it
    while (i > first_ && steps_[i - 1].arrival > arrival) --i;
    if (i > first_ && steps_[i - 1].leave >= leave) return;  // an earlier arrival leaves as late
    size_t j = i;  // later arrivals that leave no later are held by it: dropped
    while (j < steps_.size() && steps_[j].leave <= leave) ++j;
    steps_.erase(steps_.begin() + ptrdiff_t(i), steps_.begin() + ptrdiff_t(j));
    steps_.insert(steps_.begin() + ptrdiff_t(i), Step{arrival, leave});
    if (first_ > 64 && first_ * 2 > steps_.size()) {  // compact the dropped front
      steps_.erase(steps_.begin(), steps_.begin() + ptrdiff_t(first_));
      first_ = 0;
    }
  }
  size_t size() const { return steps_.size() - first_; }

 private:
  struct Step {
    Cycle arrival, leave;
  };
  std::vector<Step> steps_;
  size_t first_ = 0;
};

}  // namespace oit::rop
