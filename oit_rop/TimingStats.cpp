#include "oit_rop/TimingStats.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace oit::rop {

const char* stageKey(Stage s) {
  switch (s) {
    case Stage::ShaderInput: return "shader_input";
    case Stage::EarlyDepth: return "early_depth";
    case Stage::PixelLock: return "pixel_lock";
    case Stage::Cache: return "cache";
    case Stage::BlendAlu: return "blend_alu";
    case Stage::Resolve: return "resolve";
  }
  return "?";
}

const char* stallKey(Stall s) {
  switch (s) {
    case Stall::LockWait: return "lock_wait";
    case Stall::ScoreboardFull: return "scoreboard_full";
    case Stall::CacheMissWait: return "cache_miss_wait";
    case Stall::DramBandwidth: return "dram_bandwidth";
    case Stall::AluBusy: return "alu_busy";
    case Stall::InputStarved: return "input_starved";
    case Stall::AtomicWait: return "atomic_wait";
    case Stall::ListWalk: return "list_walk";
    case Stall::Sort: return "sort";
  }
  return "?";
}

const char* surfaceKey(Surface s) {
  switch (s) {
    case Surface::BlendArrays: return "blend_arrays";
    case Surface::Depth: return "depth";
    case Surface::Colour: return "colour";
    case Surface::Resolve: return "resolve";
  }
  return "?";
}

uint64_t StageCycles::stalled() const {
  uint64_t s = 0;
  for (uint64_t v : stalls) s += v;
  return s;
}

StageCycles& StageCycles::operator+=(const StageCycles& o) {
  busy += o.busy;
  idle += o.idle;
  for (size_t i = 0; i < kStallCount; ++i) stalls[i] += o.stalls[i];
  return *this;
}

void StageAccounts::padTo(uint64_t total) {
  for (size_t i = 0; i < kStageCount; ++i) {
    const uint64_t t = stage[i].total();
    if (t > total)
      throw std::logic_error(fmt::format("stage {} accounted {} cycles, more than the frame's {}",
                                         stageKey(Stage(i)), t, total));
    stage[i].idle += total - t;
  }
}

void StageAccounts::checkBalanced(uint64_t total) const {
  for (size_t i = 0; i < kStageCount; ++i)
    if (stage[i].total() != total)
      throw std::logic_error(fmt::format("stage {}: busy + stalls + idle = {} != {} cycles",
                                         stageKey(Stage(i)), stage[i].total(), total));
}

}  // namespace oit::rop
