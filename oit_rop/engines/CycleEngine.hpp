// CycleEngine (sim.engine = cycle, the reference): moves a partition's
// transparent fragments through its stages cycle by cycle. Each evaluated
// cycle runs the stages back to front (BlendAlu completions and lock releases,
// cache -> ALU, lock -> cache, early depth -> lock, shader -> early depth,
// input -> shader) and records every stage's status (busy, a stall by cause,
// idle); when nothing can move it jumps to the next cycle at which something
// can (skip.idle_cycles), the skipped span keeping every status (DESIGN.md).
// With lock.mode unordered or none (Deferred), a fragment's insert happens
// when it reaches the cache port out of the lock (BlendArrayRmw::enter) and,
// for none, its write when its blend completes; ordered runs the loop without
// those steps (a separate instantiation: its speed is unchanged).
#pragma once

#include "oit_rop/Types.hpp"

namespace oit::rop {

class RopPartition;

class CycleEngine {
 public:
  explicit CycleEngine(RopPartition& partition);
  // Every transparent pass of the partition, from its current cycle until the
  // last pass drained.
  void run();

 private:
  template <bool Deferred>
  bool step();  // one cycle; false when every pass drained
  Cycle nextEvent(bool refused, bool sb_full, bool draining);

  RopPartition& p_;
};

}  // namespace oit::rop
