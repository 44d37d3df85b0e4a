// ApproximateEngine (sim.engine = approximate): the transparent passes with
// one visit per fragment, in issue order, its stage times computed from when
// the resources it needs are free (building blocks in ApproximateTiming.hpp;
// what it models and how far it is from the CycleEngine: DESIGN.md).
#pragma once

#include <cstdint>

#include "oit_rop/engines/ApproximateTiming.hpp"
#include "oit_rop/stages/PixelLock.hpp"

namespace oit::rop {

class RopPartition;

class ApproximateEngine {
 public:
  explicit ApproximateEngine(RopPartition& partition) : p_(partition) {}
  // Every transparent pass of the partition, from its current cycle.
  void run();
  // The sampler's and the report's values (as PixelLock's in the cycle engine).
  const LockStats& lockStats() const { return lock_stats_; }
  uint32_t occupancy() const { return uint32_t(scoreboard_.size()); }
  uint32_t lockWaiters() const { return uint32_t(waiting_.size()); }

 private:
  void retireCalendars(Cycle now) {  // both calendars up to now (they retire lazily)
    scoreboard_.retire(now);
    waiting_.retire(now);
  }
  RopPartition& p_;
  // Releases of the fragments in flight and lock-entry cycles of those
  // waiting for the lock.
  ReleaseCalendar scoreboard_, waiting_;
  LockStats lock_stats_;
};

}  // namespace oit::rop
