// NodeCounter: the A-buffer's global node counter (Yang et al. 2010), one for
// the whole GPU: every stored fragment takes one atomic increment, and the
// L2's atomic unit serves abuffer.atomics_per_clock of them per clock for all
// partitions together, so its contention is part of the insert's cost.
// Partitions run up to a quantum apart, so a booking may come for a cycle
// before bookings already made: each cycle's capacity is booked
// earliest-free-first over a window of cycles (a calendar), not in call
// order, and a partition behind fills the gaps the others left. The window
// keeps `lookback` cycles behind the latest request (the shared levels' ports
// keep as many: 2 x quantum + 4096); a request older than it is taken as
// arriving at its oldest cycle. (A fixed 8,192 held a partition a quantum of
// 100,000 behind until the other's time less 8,192 for every atomic: the
// A-buffer's frame +69 %, bench/RESULTS-quantum.md.)
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "oit_rop/stages/PipelineQueues.hpp"

namespace oit::rop {

class NodeCounter {
 public:
  // `lookback`: how far behind the latest request another may come (at
  // least kMinWindow / 2 is kept).
  NodeCounter(double atomics_per_clock, unsigned latency, Cycle lookback = 0)
      : cap_(int64_t(atomics_per_clock * kOne + 0.5)),
        latency_(latency),
        window_(std::max<Cycle>(kMinWindow, std::bit_ceil(2 * lookback))),
        ring_(window_, 0) {
    if (!(atomics_per_clock > 0) || cap_ < 1) throw std::invalid_argument("abuffer.atomics_per_clock must be > 0");
  }
  // One increment asked at cycle `at`: the cycle its index returns (served
  // at the first cycle from `at` with capacity left, plus the latency).
  Cycle grant(Cycle at) {
    retireBefore(at > window_ / 2 ? at - window_ / 2 : 0);
    Cycle c = std::max(at, base_);
    int64_t need = kOne;  // one atomic = kOne units of a cycle's capacity cap_
    for (;; ++c) {
      if (c >= base_ + window_) retireBefore(c - window_ / 2);
      int64_t& used = ring_[c & (window_ - 1)];
      const int64_t take = std::min(need, cap_ - used);
      if (take > 0) {
        used += take;
        need -= take;
        if (need == 0) break;
      }
    }
    ++atomics_;
    waited_ += c - at;
    return c + latency_;
  }
  uint64_t atomics() const { return atomics_; }
  uint64_t waitCycles() const { return waited_; }  // cycles the increments waited for capacity

 private:
  static constexpr int64_t kOne = int64_t(1) << 20;
  static constexpr Cycle kMinWindow = 1u << 14;  // cycles of bookings kept at least (over the default quantum's lookback)
  void retireBefore(Cycle c) {
    if (c <= base_) return;
    const Cycle end = std::min(c, base_ + window_);
    for (Cycle i = base_; i < end; ++i) ring_[i & (window_ - 1)] = 0;
    base_ = c;
  }
  int64_t cap_;
  unsigned latency_;
  Cycle window_;  // a power of two
  std::vector<int64_t> ring_;
  Cycle base_ = 0;
  uint64_t atomics_ = 0, waited_ = 0;
};

}  // namespace oit::rop
