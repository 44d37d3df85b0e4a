// BlendArrayRmw: the functional read-modify-write of a pixel's blending array
// at the time the timing model decides it (lock.mode = unordered or none;
// with ordered the FrontEnd inserts in submission order instead). One per
// partition, over the FrontEnd's full-screen per-pixel state (a pixel belongs
// to one partition, so partitions never touch each other's pixels).
//  - unordered: enter() inserts into the pixel's array in place: the pixel's
//    inserts happen in the order its fragments enter the critical section.
//  - none: enter() reads the pixel's array (a private copy per fragment) and
//    inserts into the copy; complete() writes the copy back when the blend
//    ends. A write that lands after another fragment wrote the pixel since
//    this one's read overwrites that update: a lost update, counted.
// Lost updates are counted as updates written that are not in the final
// state: the pixel keeps how many updates its array holds (a write holds
// those of the array it read, plus its own), and each write adds
// (held before the write) - (held by the array it read) to the count, so the
// frame's count is writes - updates held at the end, however the races nest.
// A write is an insert whose writeBytes() is not 0 (a Discarded fragment of
// most algorithms writes nothing; slab still writes its bookkeeping).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <vector>

#include "model/OitAlgorithm.hpp"
#include "oit_rop/config/RopConfig.hpp"
#include "oit_rop/stages/FrontEnd.hpp"

namespace oit::rop {

class BlendArrayRmw {
 public:
  // `capacity`: the partition's scoreboard entries (token ids < capacity).
  BlendArrayRmw(LockMode mode, const FrontEnd::PixelState& pixels, unsigned capacity, unsigned passes);

  // The fragment of scoreboard entry `token` (at issue).
  void hold(uint32_t token, const Fragment& f) { frag_[token] = f; }
  // It enters the critical section in pass `pass`: the insert (unordered) or
  // the read and the insert into its copy (none). Returns the outcome.
  model::InsertOutcome enter(uint32_t token, unsigned pass, uint32_t tile);
  // The work of the last enter()'s insert (the BlendAlu's latency).
  model::InsertWork lastWork() const { return last_work_; }
  // Its blend ended (none: the write lands; unordered: nothing to do).
  void complete(uint32_t token) {
    if (unlocked_) land(token);
  }

  // Outcomes per pass decided here, and the lost updates (none).
  const std::vector<std::array<uint64_t, model::kOutcomeCount>>& passOutcomes() const { return outcomes_; }
  uint64_t lostUpdates() const { return uint64_t(std::max<int64_t>(0, lost_)); }

 private:
  void land(uint32_t token);

  bool unlocked_;  // lock.mode = none
  FrontEnd::PixelState px_;
  model::OitAlgorithm::InsertFn insert_;
  std::vector<Fragment> frag_;          // per token
  // none, per token: the private copy, the pixel, the updates its read held
  // and whether the insert writes.
  std::vector<uint32_t> copy_;
  std::vector<uint32_t> pixel_, read_updates_;
  std::vector<uint8_t> writes_;
  uint32_t* updates_;  // px_.updates
  std::vector<std::array<uint64_t, model::kOutcomeCount>> outcomes_;
  int64_t lost_ = 0;
  model::InsertWork last_work_;  // a write may restore updates an earlier race lost (the sum is >= 0)
};

}  // namespace oit::rop
