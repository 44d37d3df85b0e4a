// PortCalendar: a port that moves `bytes_per_clock` bytes per core cycle, as
// a calendar of the capacity booked in each cycle. A request takes the
// earliest free capacity from its own cycle on, so one booked out of time
// order (a partition up to a quantum behind another, DESIGN.md) fills the
// gaps the earlier bookings left instead of queueing behind the latest of
// them. (The shared cache levels' slice ports; MEMORY.md, "Shared cache
// levels". Booking behind the last reservation, as the DRAM bus does, made a
// bandwidth-bound frame of two partitions 44 % slower at a quantum of 200
// than in lockstep.)
//
// Capacity is kept in 2^-16 parts of a cycle of the port, per cycle, in a
// ring that covers the cycles from the latest request's cycle minus
// `lookback` to the furthest booking (it grows when bookings run further
// ahead); a full-cycle bitmap lets a request skip a backlog 64 cycles at a
// time. A request older than the ring (more than `lookback` behind the
// latest, or before the floor set by retireBefore) is taken as arriving at
// the ring's oldest cycle. With `lookback` 0 only retireBefore moves the ring.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "oit_rop/Types.hpp"

namespace oit::rop {

class PortCalendar {
 public:
  // The lookback of the calendars the partitions share (the l2's and l3's
  // ports, the A-buffer's node counter): partitions run up to a quantum
  // apart, and a level's later requests (an l2 miss after its lookup) a
  // little further, so they keep twice that and more.
  static Cycle sharedLookback(uint64_t quantum_cycles) {
    return 2 * (quantum_cycles > 1 ? quantum_cycles : 1) + 4096;
  }
  PortCalendar(double bytes_per_clock, Cycle lookback);
  // Books `bytes` from cycle `now` on; `start`: the first cycle moving them,
  // `end`: the cycle after the last (the transfer is done at `end`).
  void book(Cycle now, uint32_t bytes, Cycle& start, Cycle& end) {
    if (now > latest_) {
      latest_ = now;
      if (lookback_ != 0 && latest_ > lookback_) retireBefore(latest_ - lookback_);
    }
    const Cycle c = now > base_ ? now : base_;
    const uint64_t need = (uint64_t(bytes) * parts_per_byte_ + 0xFFFF) >> 16;  // parts of a cycle
    // Inline: the whole request fits into the capacity left in its first
    // cycle (a blend slot, a depth-test slot: a fraction of a cycle each).
    if (need == 0) {
      start = end = c;
      return;
    }
    if (c <= base_ + mask_ && need <= kFull - used_[c & mask_]) {
      uint32_t& u = used_[c & mask_];
      u += uint32_t(need);
      if (u == kFull) setFull(c);
      start = c;
      end = c + 1;
      return;
    }
    bookFrom(c, need, start, end);
  }
  // Capacity booked in cycle c, in 2^-16 parts of the cycle (tests).
  uint32_t used(Cycle c) const;
  // No request will come before cycle c: the ring may drop the cycles before
  // it (a caller that knows its requests' floor; with lookback 0 the only way
  // the ring moves on).
  void retireBefore(Cycle c) {
    if (c <= base_) return;
    if (c - base_ <= 4) {  // a retire per fragment moves a cycle or two: cleared here, no call
      for (Cycle x = base_; x < c; ++x) {
        used_[x & mask_] = 0;
        full_[(x & mask_) >> 6] &= ~(uint64_t(1) << (x & 63));
      }
      base_ = c;
      return;
    }
    advanceBase(c);
  }

 private:
  static constexpr uint32_t kFull = 1u << 16;  // one cycle of the port
  void grow(Cycle last);
  void bookFrom(Cycle c, uint64_t need, Cycle& start, Cycle& end);  // book()'s general case (need > 0)
  void advanceBase(Cycle base);  // base > base_
  void clearRange(std::size_t first, std::size_t n);  // the ring's slots [first, first + n), no wrap
  bool full(Cycle c) const { return (full_[(c & mask_) >> 6] >> (c & 63)) & 1; }
  void setFull(Cycle c) { full_[(c & mask_) >> 6] |= uint64_t(1) << (c & 63); }

  uint64_t parts_per_byte_;  // 2^16 / bytes_per_clock, x 2^16 (for precision)
  Cycle lookback_;
  Cycle base_ = 0;    // the oldest cycle the ring holds
  Cycle latest_ = 0;  // the latest request's cycle
  std::vector<uint32_t> used_;   // per cycle: capacity booked
  std::vector<uint64_t> full_;   // per cycle: bit set when no capacity is left
  uint64_t mask_ = 0;            // ring size - 1 (a power of two, a multiple of 64)
};

}  // namespace oit::rop
