// RopPartition: one ROP partition (sc_module). Its stages are plain C++
// objects (ShaderInput -> EarlyDepth -> PixelLock -> BlendArrayCache ->
// BlendAlu, then Resolve) driven by ONE SC_THREAD with a tlm_quantumkeeper.
// The partition owns the stages, its time (advance: quantum keeper) and its
// accounts; a timing engine moves the fragments through the stages during the
// transparent passes (engines/: CycleEngine evaluates cycle by cycle, the
// reference; ApproximateEngine visits each fragment once, sim.engine =
// approximate, DESIGN.md). The opaque phase and the resolve are shared.
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

#include "oit_rop/stages/BlendAlu.hpp"
#include "oit_rop/memory/ArrayLayout.hpp"
#include "oit_rop/stages/BlendArrayRmw.hpp"
#include "oit_rop/memory/BlendArrayCache.hpp"
#include "oit_rop/memory/DramSystem.hpp"
#include "oit_rop/stages/EarlyDepth.hpp"
#include "oit_rop/stages/NodeCounter.hpp"
#include "oit_rop/stages/NodePool.hpp"
#include "oit_rop/stages/FrontEnd.hpp"
#include "oit_rop/stages/PixelLock.hpp"
#include "oit_rop/stages/ShaderInput.hpp"
#include "oit_rop/RootCause.hpp"
#include "oit_rop/TimingStats.hpp"

namespace oit::rop {

class CycleEngine;
class ApproximateEngine;

// Address map of the frame's surfaces (tile-linear; MEMORY.md).
struct AddressMap {
  uint64_t blend_arrays = 0, depth = 0, colour = 0, node_pool = 0;
  uint32_t tile_stride = 0;  // one tile of blending arrays (A-buffer: heads), whole cache lines (ArrayLayout)
  uint32_t tile4_bytes = 0;  // one tile of a 4 B/pixel surface
};

struct PartitionSetup {
  const RopConfig* cfg = nullptr;
  const FrameGeometry* geo = nullptr;
  FrontEnd* front = nullptr;
  const model::OitAlgorithm* algo = nullptr;  // resolveBytes (what the resolve reads)
  const ArrayLayout* layout = nullptr;        // where the arrays' bytes are
  const FragmentLines* lines = nullptr;       // the lines each insert touches
  AddressMap map;
  unsigned array_rows = 0;   // layout rows (BlendAlu::chargedWork without lazy merging)
  double format_rate = 1.0;  // BlendAlu throughput factor
  bool bounded = true;       // false: A-buffer node pool traffic
  unsigned node_bytes = 12;  // A-buffer: one pool node (OitAlgorithm::poolNodeBytes)
  NodeCounter* counter = nullptr;  // A-buffer: the GPU's node counter (shared by all partitions)
  NodePool* pool = nullptr;        // A-buffer: where its nodes are (shared by all partitions)
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
  // A-buffer resolve: nodes read by the list walks, cycles tiles waited for
  // them (the dependent reads' latency), sort cycles summed over pixels.
  uint64_t list_nodes_walked = 0, list_walk_cycles = 0, sort_cycles = 0;
  uint64_t merges_skipped = 0;   // Stored inserts that did not pay the merge (lazy)
  RootCauseAccount::Cycles root_causes{};  // every cycle up to `end` by root cause (RootCause.hpp)
};

class RopPartition : public sc_core::sc_module, public MemoryPort {
 public:
  tlm_utils::simple_initiator_socket<RopPartition> dram;

  SC_HAS_PROCESS(RopPartition);
  // `shared`: the first shared memory level (l2, else DRAM), for the cache's fills and write-backs.
  // `shared`: the first level below the ROP cache (l2, else DRAM); `memory`:
  // the DRAM controller, whose write queues the partition drains at its end.
  RopPartition(sc_core::sc_module_name name, unsigned id, const PartitionSetup& setup, MemoryPort& shared,
               MemorySystem& memory);
  ~RopPartition() override;

  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) override;

  bool done() const { return done_; }
  sc_core::sc_event& doneEvent() { return done_event_; }
  const PartitionResult& result() const { return res_; }
  const PixelLock& lock() const { return lock_; }
  // The lock's figures, from the PixelLock or (sim.engine = approximate) the
  // approximate engine; scoreboard entries in use and fragments waiting for
  // the lock at the partition's current cycle (the sampler's values).
  const LockStats& lockStats() const;
  uint32_t occupancy() const;
  uint32_t lockWaiters() const;
  const BlendArrayCache& cache() const { return cache_; }
  const EarlyDepth& earlyDepth() const { return early_; }
  const BlendAlu& alu() const { return alu_; }
  // lock.mode unordered / none: the inserts this partition made (nullptr when ordered).
  const BlendArrayRmw* rmw() const { return rmw_.get(); }

 private:
  // The engines move fragments through this partition's stages and time.
  friend class CycleEngine;
  friend class ApproximateEngine;
  // The pipeline's registers between stages (the cycle engine's; the
  // approximate engine computes a fragment's times without them): what a
  // fragment carries from issue to release, indexed by its scoreboard token,
  // and the queues after the lock.
  struct TokenInfo {
    uint32_t pixel;  // in tile order (InRec::pixel)
    uint8_t flags, outcome;  // outcome: InRec's kind (culled: kCulledKind)
    model::InsertWork work;  // as charged (BlendAlu::chargedWork)
  };
  struct CacheEntry {  // a fragment between lock entry and its blend slot
    uint32_t token;
    Cycle ready;  // its line is there
    bool miss;
    WaitSplit wait;  // a miss: its wait by root cause
  };
  struct ResolveEntry {
    uint32_t tile;
    Cycle ready;  // the tile's line, opaque colour and (A-buffer) node lists are all there (kNever: walking)
    Cycle sort;   // A-buffer: the tile's slowest per-pixel sort, cycles
    WaitSplit wait;  // what the tile's inputs waited for (root causes)
    // A-buffer: the list walk in progress (walk_nodes_[slot]: each pixel's
    // list), its next step and the cycle that step's reads issue.
    uint32_t slot = 0, step = 0, steps = 0;
    Cycle step_at = 0;
  };
  // The tile's lists into `lists` (one per pixel, in walk order); returns the
  // tile's slowest pixel sort, `longest` its longest list.
  Cycle prepareWalk(uint32_t tile, std::vector<std::vector<uint32_t>>& lists, uint32_t& longest);
  // Issues step `step` of a walk at `now` (the step-th node of every list
  // that long); returns when the last of those reads is back.
  Cycle walkStep(const std::vector<std::vector<uint32_t>>& lists, uint32_t step, Cycle now);

  void run();
  // now_ = next, skip count, quantum keeper. Inline (with the helpers below):
  // the engines call them per cycle or per fragment from another file.
  void advance(Cycle next, bool count_skip) {
    // Stage accounting is lazy (setStatus adds a status's span when it changes).
    const Cycle span = next - now_;
    if (count_skip && span > 1) res_.skipped_idle += span - 1;
    now_ = next;
    if (now_ >= next_sync_) syncQuantum();
  }
  void syncQuantum();  // yields to the other partitions at the quantum boundary reached
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
  void setStatuses(uint64_t codes, unsigned stages) {
    for (unsigned i = 0; i < stages; ++i) {
      const uint8_t c = uint8_t(codes >> (8 * i));
      if (c != uint8_t(codes_ >> (8 * i))) setStatus(Stage(i), decode(c));
    }
  }
  void setAll(StageStatus v);
  void flushAccounts();  // accounts every stage's current status up to now_
  void opaquePhase();
  void waitForFrontEnd();
  void resolvePhase();
  // The lines (and sectors) the resolve of tile t reads.
  void resolveLines(uint32_t t, std::vector<LineTouch>& out);
  uint32_t tileOf(uint32_t pixel) const { return pixel >> geo_.tile_shift; }
  // The lines a fragment of this pass touches (FragmentLines): kind = InRec's.
  std::span<const LineTouch> linesOf(uint32_t pixel, uint8_t kind) const {
    const FragmentLines::Span l = s_.lines->lines(pass_, kind & (FragmentLines::kKinds - 1), pixel & tile_mask_);
    return {l.begin, l.count};
  }
  // BlendArrayCache::release, re-enabling a set-refused retry.
  void releaseLines(uint32_t pixel, uint8_t kind) {
    if (cache_.release(tileOf(pixel), linesOf(pixel, kind))) retry_at_ = 0;  // the refused access's set has a line out of use now
  }
  void nodeWrite();
  void refillInput() {
    auto& q = front_.queue(id_);
    while (q.empty() && front_.canRefill()) front_.refill();
    starving_ = q.empty() && !front_.exhausted();
  }
  // BlendArrayCache::acquire of a fragment's lines, not called before
  // retry_at_ (false: refused; ready: when the lines are there).
  bool acquireGated(Cycle now, uint32_t pixel, uint8_t kind, Cycle& ready) {
    // While every miss-queue entry is busy a retry would be refused again: no call
    // until the first entry frees, so the refusals counted (cache.miss_queue_full:
    // one per access that had to wait) and the cycle the access goes through do
    // not depend on how often the partition is evaluated (skip.idle_cycles).
    // A set with every way in use is retried after the release that frees one
    // of its lines (releaseLine), also independent of how often we ask.
    if (now < retry_at_) return false;
    memory_.resetProbe();
    const uint64_t misses = cache_.stats().misses;
    ready = cache_.acquire(now, tileOf(pixel), linesOf(pixel, kind));
    if (ready != kNever) {
      // A miss waits for memory (a fast-clear fill for the cache alone); a
      // hit under a fill in flight for that fill, which the partition's
      // latest miss stands for.
      if (cache_.stats().misses != misses) {
        last_miss_ = splitWait(now, ready, memory_.probe(), miss_rest_);
        miss_waits_.add(now, ready, last_miss_);
      }
      return true;
    }
    retry_at_ = cache_.refusedBySet() ? kNever : cache_.missQueueFreesAt();
    refused_wait_ = retry_at_ == kNever ? last_miss_ : miss_waits_.freeing(retry_at_, last_miss_);
    return false;
  }

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
  std::unique_ptr<BlendArrayRmw> rmw_;  // lock.mode unordered / none: inserts at lock entry
  std::vector<TokenInfo> tok_;
  Fifo<CacheEntry> cache_q_;
  Fifo<std::pair<Cycle, uint32_t>> tail_q_;  // EndOfShader releases
  Cycle retry_at_ = 0;  // after a refused acquire: the cycle the cache's first miss-queue entry frees (kNever: until a line of the set is released)
  uint32_t tile_mask_;  // tile pixels - 1
  unsigned cache_ports_;              // cache accesses per cycle (ceil(alu.blends_per_clock))
  bool early_cull_;
  bool merge_skip_;                   // a Stored insert skips the merge (lazy, > 1 row)
  // The work a fragment's blend is charged: its insert's (BlendAlu::chargedWork).
  model::InsertWork charged(model::InsertWork w, uint8_t outcome) const {
    return BlendAlu::chargedWork(w, model::InsertOutcome(outcome & 3), s_.array_rows, cfg_.skip.lazy_merge);
  }
  // When a blend's work can start: at `now`, or (A-buffer, a stored node) when
  // the node counter's atomic returns.
  Cycle blendStart(Cycle now, bool appends) { return appends ? s_.counter->grant(now) : now; }
  unsigned pass_ = 0;
  Cycle now_ = 0, next_sync_ = 0;
  std::vector<uint32_t> owned_;  // tiles of this partition
  std::array<StageStatus, kStageCount> status_{};
  std::array<Cycle, kStageCount> since_{};  // cycle the current status_[i] began
  uint64_t codes_ = 0;                      // status_ packed, byte i = code(status_[i])
  bool starving_ = false;
  RootCauseAccount root_;     // this partition's cycles by root cause
  WaitSplit last_miss_;       // the latest blend-array miss's wait (root causes)
  MissWaits miss_waits_;      // the latest misses' waits (as many as the miss queue holds)
  // A refused access's wait: a full miss queue's, the miss that frees its
  // first entry; a full set's, the latest miss (DESIGN.md "Root causes").
  WaitSplit refused_wait_;
  WaitSplit last_depth_;      // the latest depth-tile read's wait
  RootCause miss_rest_;       // a miss's wait beyond DRAM: the shared levels' (l2) or the ROP cache's
  std::vector<uint32_t> resolve_fill_;  // resolveLines' sectors per line of the tile
  // The list walks in progress: per prefetch slot, each pixel's list (pool indices) in walk order.
  std::vector<std::vector<std::vector<uint32_t>>> walk_nodes_;
  Cycle last_write_done_ = 0;  // the latest posted write's completion (the resolve's window)
  WaitSplit last_write_wait_;  // what that write waited for (root causes of the window and the frame's tail)
  MemorySystem& memory_;  // the shared DRAM: its write queues drain at the partition's end
  bool done_ = false;
  // The transparent passes' engine: one of the two (sim.engine).
  std::unique_ptr<CycleEngine> cycle_;
  std::unique_ptr<ApproximateEngine> approximate_;
  sc_core::sc_event done_event_;
  PartitionResult res_;
};

}  // namespace oit::rop
