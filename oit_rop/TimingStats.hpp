// Per-stage cycle accounting of one ROP partition: every cycle of the frame is
// busy, a stall by cause, or idle, for every stage (busy + stalls + idle =
// total, checked by checkBalanced()). A status recorded at cycle `now` holds
// until the next evaluated cycle: the simulator only skips cycles where no
// stage can change state, so the skipped span keeps the status.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "oit_rop/Types.hpp"

namespace oit::rop {

enum class Stage : uint8_t { ShaderInput, EarlyDepth, PixelLock, Cache, BlendAlu, Resolve };
inline constexpr unsigned kStageCount = 6;
const char* stageKey(Stage s);  // "shader_input", ... (report keys)

// AtomicWait: the BlendAlu's blends all wait for the A-buffer's node counter
// (NodeCounter); ListWalk: the resolve waits for a tile's dependent node
// reads; Sort: the resolve sorts a tile's lists (A-buffer).
enum class Stall : uint8_t {
  LockWait, ScoreboardFull, CacheMissWait, DramBandwidth, AluBusy, InputStarved, AtomicWait, ListWalk, Sort
};
inline constexpr unsigned kStallCount = 9;
const char* stallKey(Stall s);  // "lock_wait", ...

// What one stage did in one cycle.
struct StageStatus {
  enum Kind : uint8_t { Idle, Busy, Stalled } kind = Idle;
  Stall cause = Stall::InputStarved;
  static constexpr StageStatus idle() { return {}; }
  static constexpr StageStatus busy() { return {Busy, Stall::InputStarved}; }
  static constexpr StageStatus stall(Stall c) { return {Stalled, c}; }
};

struct StageCycles {
  uint64_t busy = 0, idle = 0;
  std::array<uint64_t, kStallCount> stalls{};
  uint64_t stalled() const;
  uint64_t total() const { return busy + idle + stalled(); }
  void add(StageStatus s, uint64_t cycles) {  // hot: once per stage per evaluated cycle
    if (s.kind == StageStatus::Busy) busy += cycles;
    else if (s.kind == StageStatus::Idle) idle += cycles;
    else stalls[size_t(s.cause)] += cycles;
  }
  StageCycles& operator+=(const StageCycles& o);
};

struct StageAccounts {
  std::array<StageCycles, kStageCount> stage{};
  StageCycles& operator[](Stage s) { return stage[size_t(s)]; }
  const StageCycles& operator[](Stage s) const { return stage[size_t(s)]; }
  // Pads every stage with idle cycles up to `total` (a partition that finished
  // early idles until the frame ends). Throws std::logic_error if a stage has
  // already accounted more than `total` cycles.
  void padTo(uint64_t total);
  // Throws std::logic_error unless busy + stalls + idle == total for every stage.
  void checkBalanced(uint64_t total) const;
};

const char* surfaceKey(Surface s);  // "blend_arrays", "depth", "colour", "resolve"

}  // namespace oit::rop
