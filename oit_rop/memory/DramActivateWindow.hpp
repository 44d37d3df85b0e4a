// The activate-rate limits of one DRAM channel (one rank): tRRD, the least
// time between two activates (to different banks; the same bank is held
// tRAS + tRP = tRC apart by its own state), and tFAW, at most four activates
// in any window of tFAW (MEMORY.md, "Activate limits"). The controller books
// requests as they come, not always in time order (partitions up to a SystemC
// quantum apart, write batches drained from a later tick), so the window keeps
// the latest activates by time, not by booking, and places a new one at the
// earliest tick both limits allow among them: in the usual case (the new
// activate no earlier than the latest) that is max(t, last + tRRD, the
// fourth-latest + tFAW), O(1). Time is in DRAM ticks (DramTimings).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

namespace oit::rop {

class DramActivateWindow {
 public:
  // Activates remembered, the latest by time. The controller books a read when
  // it is asked, so a channel's activates may already stand far ahead of the
  // writes a batch drains from an earlier tick (one partition with 16 misses
  // waiting for the window booked 16 activates ahead); 64 covers the presets'
  // miss queues. An activate earlier than all of them (when 64 are kept) is
  // placed no earlier than the oldest kept: the time before it is taken as
  // full (never above the limits, possibly later than needed).
  static constexpr unsigned kKeep = 64;

  // trrd_l: activate to activate in one bank group (MEMORY.md "Bank groups"),
  // at least trrd; trrd between groups. trrd_l = trrd (or 0): no distinction,
  // the groups are not looked at.
  DramActivateWindow(uint64_t trrd, uint64_t tfaw, uint64_t trrd_l = 0)
      : trrd_(trrd), tfaw_(tfaw), trrd_l_(std::max(trrd, trrd_l)), grouped_(trrd_l_ > trrd_) {}
  bool limited() const { return trrd_l_ != 0 || tfaw_ != 0; }
  // The earliest tick >= t at which an activate to bank group `group` keeps
  // tRRD (tRRD_L to the same group's) to every remembered activate and leaves
  // no tFAW window with five.
  uint64_t earliest(uint64_t t, unsigned group = 0) const {
    if (n_ == 0) return t;
    const uint64_t last = at_[n_ - 1];
    if (t >= last) {
      uint64_t c = t;
      if (trrd_ && c < last + trrd_) c = last + trrd_;
      if (grouped_) c = sameGroupAfter(c, group);
      if (tfaw_ && n_ >= 4 && c < at_[n_ - 4] + tfaw_) c = at_[n_ - 4] + tfaw_;
      return c;
    }
    return earliestAmong(t, group);
  }
  // Records an activate at tick t to bank group `group` (placed by earliest()).
  void record(uint64_t t, unsigned group = 0);
  unsigned size() const { return n_; }

 private:
  uint64_t earliestAmong(uint64_t t, unsigned group) const;  // t before the latest activate
  // c moved past tRRD_L after the latest activates of `group` (c at or after every one kept).
  uint64_t sameGroupAfter(uint64_t c, unsigned group) const {
    for (unsigned j = n_; j-- > 0 && at_[j] + trrd_l_ > c;)
      if (group_[j] == group) return at_[j] + trrd_l_;  // the group's latest: the others are earlier
    return c;
  }
  // The least spacing from activate j to one in `group`.
  uint64_t spacing(unsigned j, unsigned group) const { return grouped_ && group_[j] == group ? trrd_l_ : trrd_; }
  uint64_t trrd_, tfaw_, trrd_l_;
  bool grouped_;
  std::array<uint64_t, kKeep> at_{};  // ascending
  std::array<uint8_t, kKeep> group_{};  // bank group of each (grouped_ only)
  unsigned n_ = 0;
};

}  // namespace oit::rop
