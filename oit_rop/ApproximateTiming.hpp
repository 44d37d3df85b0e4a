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
#pragma once

#include <algorithm>
#include <cstdint>
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
  // The fragment last asked about at `address` releases it at `release`.
  void released(uint32_t address, Cycle release) { last_[address] = std::max(last_[address], release); }

 private:
  static constexpr uint32_t kNoOwner = ~uint32_t(0);
  std::vector<Cycle> last_;      // latest release of any visit so far
  std::vector<Cycle> before_;    // grouped: latest release of the holders before the current one
  std::vector<uint32_t> owner_;  // grouped: the current holder
};

}  // namespace oit::rop
