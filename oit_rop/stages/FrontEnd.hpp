// The ROP front end: reads the trace in batches, classifies and routes every
// fragment to the partition that owns its screen tile, and runs the
// functional model on the way ("functional decides what, timing decides
// when"): the early-depth cull decision (z >= final opaque depth) and, with
// lock.mode = ordered, the algorithm's insert() are made here, in global
// submission order, pass by pass, on the full-screen per-pixel state. The
// InsertOutcome travels with the fragment's record and decides its timing cost
// downstream. With lock.mode = unordered or none the order of the inserts is
// the timing model's: the front end routes the fragment itself beside its
// record (deferred(), only in those modes) and the partition inserts it when
// it enters its critical section (BlendArrayRmw). A partition pulls a batch
// when its input runs dry; a partition with a long backlog holds the others
// back (high watermark), so memory stays bounded.
#pragma once

#include <systemc>

#include <array>
#include <functional>
#include <span>
#include <string>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "model/FunctionalRenderer.hpp"
#include "model/OitAlgorithm.hpp"
#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

// Screen tiles (tile_w x tile_h pixels: the partition interleave, HiZ, tile
// locks, fast clear and the resolve) and their owners: tile (tx, ty) belongs
// to partition (tx + ty) % partitions, a checkerboard-like interleave that
// spreads neighbouring tiles.
struct FrameGeometry {
  uint32_t width = 0, height = 0, tile_w = 8, tile_h = 8, tiles_x = 0, tiles_y = 0, partitions = 1;
  uint32_t tile_shift = 6;          // log2(tile_w x tile_h) (tile sizes are powers of two)
  std::vector<uint32_t> tile_col;   // x -> tile column
  std::vector<uint32_t> tile_row;   // y -> tile row * tiles_x
  // A pixel's number in tile order: tile x tile pixels + its offset in the
  // tile (row-major inside the tile) = pix_row[y] + pix_col[x]; tile =
  // number >> tile_shift (the cache's line tables and the array layout use both).
  std::vector<uint32_t> pix_row, pix_col;
  std::vector<uint8_t> owner;       // tile -> partition
  // tile -> its number among its partition's tiles, ty * ceil(tiles_x / N) + tx / N:
  // what a partition's cache sets and depth-tile buffer are indexed by (the
  // global number would use only some of them: a partition's tiles all share
  // one residue mod N when tiles_x = 1 mod N).
  std::vector<uint32_t> local;
  // Lock addresses (lock.granularity: pixel, 2x2 quad or tile) numbered among
  // the partition's own: local[tile] * lock_per_tile + lock_row[y] + lock_col[x],
  // dense in [0, the partition's tiles x lock_per_tile). A partition's
  // PixelLock table then holds its share of the frame, not the whole frame.
  uint32_t lock_per_tile = 1;
  std::vector<uint32_t> lock_row, lock_col;  // y, x -> the address's offset inside its tile

  FrameGeometry() = default;
  FrameGeometry(uint32_t w, uint32_t h, const PartitionConfig& p, LockGranularity lock = LockGranularity::Pixel);
  uint32_t tiles() const { return tiles_x * tiles_y; }
  uint32_t tilePixels() const { return tile_w * tile_h; }
  uint32_t tileOf(uint32_t x, uint32_t y) const { return tile_row[y] + tile_col[x]; }
  uint32_t tiledPixel(uint32_t x, uint32_t y) const { return pix_row[y] + pix_col[x]; }
  uint32_t partitionOf(uint32_t tile) const { return owner[tile]; }
  uint32_t localOf(uint32_t tile) const { return local[tile]; }
  uint32_t lockAddress(uint32_t x, uint32_t y) const {
    return local[tileOf(x, y)] * lock_per_tile + lock_row[y] + lock_col[x];
  }
};

// One routed fragment (20 bytes; culled and inserted fragments alike).
struct InRec {
  // kDeferredInsert: not inserted yet (lock.mode unordered / none, not culled):
  // its outcome is decided when it enters the lock, its Fragment travels in the
  // partition's deferred() queue.
  enum Flags : uint8_t { kCulled = 1, kNeedsDepthRead = 2, kPassEnd = 4, kDeferredInsert = 8 };
  uint32_t lock;    // lock address in its partition (FrameGeometry::lockAddress)
  uint32_t pixel;   // in tile order (FrameGeometry::tiledPixel): tile = pixel >> tile_shift
  uint32_t seq;     // index in the trace (shader latency hash)
  uint8_t flags;
  // model::InsertOutcome (0 while kDeferredInsert); kCulledKind for a culled fragment (no insert), so
  // that `outcome` is the fragment's kind (culled x 4 + outcome), the index
  // of the approximate engine's per-kind tables.
  uint8_t outcome;
  static constexpr uint8_t kCulledKind = 4;
  // seq - first seq of its primitive's run (restarts every 65536 records; 0 when the lock does not group)
  uint16_t prim_offset;
  // What its insert did (rows compared and written: the BlendAlu's latency);
  // {0, 0} while kDeferredInsert and for a culled fragment.
  model::InsertWork work;
};

struct DrawCounts {
  uint64_t fragments = 0, culled = 0, inserted = 0;  // inserted: reached the blend (stored, merged or discarded)
};

class FrontEnd {
 public:
  FrontEnd(FragmentSource& src, model::OitAlgorithm& algo, const model::DrawClassifier& classes,
           const model::OpaqueLayer& opaque, std::vector<uint64_t> opaque_per_partition, const FrameGeometry& geo,
           const RopConfig& cfg);

  Fifo<InRec>& queue(unsigned partition) { return queues_[partition]; }
  // lock.mode unordered / none: the fragments of the partition's
  // kDeferredInsert records, in the same order (empty otherwise).
  Fifo<Fragment>& deferred(unsigned partition) { return deferred_[partition]; }
  bool defersInserts() const { return defer_; }
  // The per-pixel state the deferred inserts read and write (BlendArrayRmw).
  struct PixelState {
    model::OitAlgorithm* algo;
    uint32_t* words;          // width x height x words_per_pixel
    unsigned words_per_pixel;
    uint32_t width;
    const float* opaque_z;    // final opaque depth per pixel
    uint32_t* tile_nodes;     // A-buffer: nodes stored per tile (nullptr when bounded)
    uint32_t* updates;        // lock.mode = none: per pixel, the updates its array holds (else nullptr)
  };
  PixelState pixelState();
  // Outcomes of pass `pass` decided outside the route (deferred inserts):
  // added to counts() with their state traffic, as the route adds its own.
  void addOutcomes(unsigned pass, const std::array<uint64_t, model::kOutcomeCount>& outcomes);
  bool exhausted() const { return exhausted_; }
  // False while some partition's backlog is above the high watermark.
  bool canRefill() const;
  // Routes the next source batch (or, at the end of a pass, a pass-end marker
  // to every partition and a rewind).
  void refill();
  // A partition popped its queue below the low watermark.
  void popped(unsigned partition) {  // inline: once per fragment
    if (waiters_ != 0) wakeWaiters(partition);
  }
  sc_core::sc_event& drained() { return drained_; }
  void addWaiter() { ++waiters_; }
  bool hasWaiters() const { return waiters_ != 0; }  // popped() has something to do

  // Called about every 2^20 fragments routed: fraction of all passes done.
  void setProgress(std::function<void(double, const std::string&)> f) { progress_ = std::move(f); }
  unsigned passes() const { return passes_; }
  std::span<const uint32_t> state() const { return {state_.data(), state_.size()}; }
  const model::RenderCounts& counts() const { return counts_; }
  uint64_t sourceReads() const { return source_reads_; }
  // Per tile: min / max opaque depth (hierarchical Z), opaque pixels landed.
  const std::vector<float>& hizMin() const { return hiz_min_; }
  const std::vector<float>& hizMax() const { return hiz_max_; }
  const std::vector<uint16_t>& opaqueLanded() const { return landed_; }
  // Unbounded algorithms (A-buffer): nodes stored per tile.
  const std::vector<uint32_t>& tileNodes() const { return tile_nodes_; }
  const std::unordered_map<uint32_t, DrawCounts>& perDraw() const { return per_draw_; }
  // Opaque fragments per partition (counted by the opaque-phase scan).
  const std::vector<uint64_t>& opaquePerPartition() const { return opaque_per_part_; }

 private:
  void wakeWaiters(unsigned partition);
  template <bool First, bool Hierarchical, bool Defer>
  void route(std::span<const Fragment> batch);  // refill()'s per-record loop
  template <bool First>
  void routeBatch(std::span<const Fragment> batch);  // route<First, ...> for the settings
  FragmentSource& src_;
  std::span<const Fragment> pending_;  // the rest of the source's last batch, not yet routed
  model::OitAlgorithm& algo_;
  const model::DrawClassifier& classes_;
  const model::OpaqueLayer& opaque_;
  const FrameGeometry& geo_;
  bool hierarchical_;
  bool prim_runs_;  // the PixelLock groups owners (lock.per_primitive at quad/tile granularity)
  bool defer_;      // lock.mode unordered / none: the partitions insert
  unsigned words_, passes_, pass_ = 0;
  bool exhausted_ = false;
  uint64_t index_ = 0, source_reads_ = 0;
  // The current primitive run (consecutive transparent records of one draw and
  // primitive): InRec::prim_offset, PixelLock's owner with lock.per_primitive.
  uint32_t run_draw_ = ~0u, run_prim_ = ~0u, run_start_ = 0;
  model::StateBuffer state_;  // uninitialised until clearFrame, huge pages
  std::vector<Fifo<InRec>> queues_;
  std::vector<Fifo<Fragment>> deferred_;
  std::vector<float> hiz_min_, hiz_max_;
  std::vector<uint16_t> landed_;
  std::vector<uint32_t> tile_nodes_;
  std::vector<uint32_t> updates_;  // PixelState::updates
  std::vector<uint64_t> opaque_per_part_;
  std::unordered_map<uint32_t, DrawCounts> per_draw_;
  model::RenderCounts counts_;
  sc_core::sc_event drained_;
  unsigned waiters_ = 0;
  std::function<void(double, const std::string&)> progress_;
  // Progress every 2^14 records (the display redraws at most every 100 ms): at
  // 2^20 a trace of under a million records showed 0 % until its pass ended.
  static constexpr uint64_t kProgressRecords = uint64_t(1) << 14;
  uint64_t next_progress_ = kProgressRecords;
};

}  // namespace oit::rop
