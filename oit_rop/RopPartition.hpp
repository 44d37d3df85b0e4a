// RopPartition: one ROP partition (sc_module). Its stages are plain C++
// objects (ShaderInput -> EarlyDepth -> PixelLock -> BlendArrayCache ->
// BlendAlu, then Resolve) advanced cycle by cycle by ONE SC_THREAD with a
// tlm_quantumkeeper; when no stage can move, the thread jumps to the next
// cycle at which one can (skip.idle_cycles), and the skipped span keeps every
// stage's status (busy / stall cause / idle) for the accounting. With
// sim.engine = approximate the transparent phase visits each fragment once
// instead (approximatePhase, DESIGN.md).
//
// Frame: opaque phase (depth + colour of the opaque pre-pass, charged as
// traffic and input time), then every algorithm pass (pass p+1 after this
// partition drained pass p), then resolve of the partition's tiles.
#pragma once

#include <systemc>
#include <tlm>
#include <tlm_utils/simple_initiator_socket.h>
#include <tlm_utils/tlm_quantumkeeper.h>

#include <memory>
#include <vector>

#include "oit_rop/engines/ApproximateTiming.hpp"
#include "oit_rop/stages/BlendAlu.hpp"
#include "oit_rop/memory/BlendArrayCache.hpp"
#include "oit_rop/memory/DramSystem.hpp"
#include "oit_rop/stages/EarlyDepth.hpp"
#include "oit_rop/stages/FrontEnd.hpp"
#include "oit_rop/stages/PixelLock.hpp"
#include "oit_rop/stages/ShaderInput.hpp"
#include "oit_rop/TimingStats.hpp"

namespace oit::rop {

// DRAM address map of the frame's surfaces (tile-linear).
struct AddressMap {
  uint64_t blend_arrays = 0, depth = 0, colour = 0, node_pool = 0;
  uint32_t line_bytes = 0;   // one tile of blending arrays (A-buffer: heads)
  uint32_t tile4_bytes = 0;  // one tile of a 4 B/pixel surface
};

struct PartitionSetup {
  const RopConfig* cfg = nullptr;
  const FrameGeometry* geo = nullptr;
  FrontEnd* front = nullptr;
  AddressMap map;
  unsigned array_rows = 0;   // layout rows (for rowsFor)
  double format_rate = 1.0;  // BlendAlu throughput factor
  bool bounded = true;       // false: A-buffer node pool traffic
};

struct PartitionResult {
  Cycle end = 0;                 // last cycle incl. draining posted writes
  Cycle opaque_end = 0;
  std::vector<Cycle> pass_end;   // cycle each pass drained
  StageAccounts accounts;
  uint64_t skipped_idle = 0;
  uint64_t fragments = 0, culled_early = 0, culled_late = 0, blended = 0;
  uint64_t tiles_resolved = 0, tiles_skipped_fast_clear = 0;
  uint64_t node_bytes_written = 0, node_bytes_read = 0;
  uint64_t merges_skipped = 0;   // Stored inserts that did not pay the merge (lazy)
};

class RopPartition : public sc_core::sc_module, public MemoryPort {
 public:
  tlm_utils::simple_initiator_socket<RopPartition> dram;

  SC_HAS_PROCESS(RopPartition);
  RopPartition(sc_core::sc_module_name name, unsigned id, const PartitionSetup& setup, MemorySystem& memory);

  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) override;

  bool done() const { return done_; }
  sc_core::sc_event& doneEvent() { return done_event_; }
  const PartitionResult& result() const { return res_; }
  const PixelLock& lock() const { return lock_; }
  // The lock's figures, from the PixelLock or (sim.engine = approximate) the
  // approximate engine; scoreboard entries in use and fragments waiting for
  // the lock at the partition's current cycle (the sampler's values).
  const LockStats& lockStats() const { return approximate_ ? approx_lock_ : lock_.stats(); }
  uint32_t occupancy() const { return approximate_ ? uint32_t(approx_sb_.size()) : lock_.occupancy(); }
  uint32_t lockWaiters() const { return approximate_ ? uint32_t(approx_waiting_.size()) : uint32_t(lock_.waiting()); }
  const BlendArrayCache& cache() const { return cache_; }
  const EarlyDepth& earlyDepth() const { return early_; }
  const BlendAlu& alu() const { return alu_; }

 private:
  struct TokenInfo {
    uint32_t tile;
    uint8_t flags, outcome, rows;
  };
  struct CacheEntry {
    uint32_t token;
    Cycle ready;
    bool miss;
  };
  struct ResolveEntry {
    uint32_t tile;
    Cycle ready;  // the tile's line, opaque colour and (A-buffer) node lists are all there
  };

  void run();
  void advance(Cycle next, bool count_skip);  // now_ = next, skip count, quantum keeper
  // The status of stage st from now_ on (holds until changed). Spans are
  // accounted when a status changes, not every evaluated cycle.
  void setStatus(Stage st, StageStatus v) {
    const size_t i = size_t(st);
    if (v.kind == status_[i].kind && v.cause == status_[i].cause) return;
    res_.accounts.stage[i].add(status_[i], now_ - since_[i]);
    status_[i] = v;
    since_[i] = now_;
    codes_ = (codes_ & ~(uint64_t(0xFF) << (8 * i))) | uint64_t(code(v)) << (8 * i);
  }
  // A status as one byte (kind | cause << 2) and back; codes_ holds status_ packed.
  static constexpr uint8_t code(StageStatus v) { return uint8_t(uint8_t(v.kind) | uint8_t(v.cause) << 2); }
  static constexpr StageStatus decode(uint8_t c) {
    return StageStatus{StageStatus::Kind(c & 3), Stall(c >> 2)};
  }
  // setStatus for stages 0 .. stages-1 from packed codes (byte i = stage i).
  void setStatuses(uint64_t codes, unsigned stages);
  void setAll(StageStatus v);
  void flushAccounts();  // accounts every stage's current status up to now_
  void opaquePhase();
  bool transparentStep();  // one cycle; false when every pass drained
  void approximatePhase();  // every pass, one visit per fragment (sim.engine = approximate)
  Cycle nextEvent(bool refused, bool sb_full, bool draining);
  void waitForFrontEnd();
  void resolvePhase();
  void release(uint32_t token);
  void releaseLine(uint32_t tile);  // BlendArrayCache::release, re-enabling a set-refused retry
  void nodeWrite();
  void refillInput();
  // BlendArrayCache::acquire, not called before retry_at_ (false: refused; ready: when the line is there).
  bool acquireGated(Cycle now, uint32_t tile, bool write, Cycle& ready);

  unsigned id_;
  PartitionSetup s_;
  const RopConfig& cfg_;
  const FrameGeometry& geo_;
  FrontEnd& front_;
  CoreClock clock_;
  tlm_utils::tlm_quantumkeeper qk_;
  Cycle quantum_;
  tlm::tlm_generic_payload payload_;
  DramExtension ext_;

  ShaderInput shader_;
  EarlyDepth early_;
  PixelLock lock_;
  BlendArrayCache cache_;
  BlendAlu alu_;
  std::vector<TokenInfo> tok_;
  Fifo<CacheEntry> cache_q_;
  Fifo<std::pair<Cycle, uint32_t>> tail_q_;  // EndOfShader releases
  Cycle retry_at_ = 0;  // after a refused acquire: the cycle the cache's first miss-queue entry frees (kNever: until a line of the set is released)
  unsigned cache_ports_;
  bool early_cull_;
  bool merge_skip_;                   // a Stored insert skips the merge (lazy, > 1 row)
  std::array<uint8_t, 4> rows_of_{};  // BlendAlu::rowsFor by outcome (index 3: invalid, 0 rows)
  unsigned pass_ = 0;
  Cycle now_ = 0, next_sync_ = 0;
  std::vector<uint32_t> owned_;  // tiles of this partition
  std::array<StageStatus, kStageCount> status_{};
  std::array<Cycle, kStageCount> since_{};  // cycle the current status_[i] began
  uint64_t codes_ = 0;                      // status_ packed, byte i = code(status_[i])
  bool starving_ = false;
  // A-buffer node pool (write-combined 12 B nodes, burst-sized writes).
  uint64_t node_pending_ = 0, node_addr_ = 0;
  Cycle last_write_done_ = 0;
  bool done_ = false;
  // Approximate engine: releases of the fragments in flight and lock-entry
  // cycles of those waiting for the lock (ReleaseCalendars), and its lock figures.
  bool approximate_ = false;
  ReleaseCalendar approx_sb_, approx_waiting_;
  void retireCalendars() {  // both calendars up to now_ (they retire lazily)
    approx_sb_.retire(now_);
    approx_waiting_.retire(now_);
  }
  LockStats approx_lock_;
  sc_core::sc_event done_event_;
  PartitionResult res_;
};

}  // namespace oit::rop
