// EarlyDepth: the depth test of transparent fragments against the opaque
// depth, before the PixelLock. Whether a fragment is culled is decided by the
// functional model (z >= final opaque depth); this stage only charges time and
// traffic. A per-tile hierarchical Z (min and max opaque depth of the tile)
// decides most fragments without reading depth: z < tile min -> in front of
// every opaque pixel, z >= tile max -> behind all of them. Otherwise the
// stage reads the tile's depth (Surface::Depth, tile pixels x 4 B) into a
// small direct-mapped depth-tile buffer (`depth_tiles` entries, tags only).
// In order: a fragment waiting for its depth tile blocks the ones behind it
// ("cache-miss wait"). Throughput: `per_clock` fragments per cycle.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

struct EarlyDepthStats {
  uint64_t tested = 0, depth_reads = 0, depth_buffer_hits = 0, hiz_decided = 0;
};

class EarlyDepth {
 public:
  static constexpr unsigned kDepthTiles = 16;  // entries of the ROP's depth-tile buffer (DESIGN.md)
  EarlyDepth(const EarlyDepthConfig& cfg, double per_clock, uint32_t tile_bytes, uint64_t depth_base,
             MemoryPort& mem, unsigned depth_tiles = kDepthTiles, std::vector<uint32_t> slot_index = {});
  // slot_index (optional, one per tile): the depth-tile buffer is direct mapped
  // by slot_index[tile] % depth_tiles (a partition passes its local tile
  // numbers, FrameGeometry::local); without it, by the tile number.

  // A shaded fragment arrives; `needs_read` = the HiZ could not decide it.
  void push(Cycle now, uint32_t token, uint32_t tile, bool needs_read) {  // inline: once per fragment
    ++stats_.tested;
    const Cycle passed = now + cfg_.latency;
    Cycle ready = passed;
    if (needs_read)
      ready = std::max(ready, depthTile(now, tile));
    else
      ++stats_.hiz_decided;
    ready = std::max(ready, last_ready_);
    last_ready_ = ready;
    q_.push({token, ready, passed});
  }
  // The approximate engine's visit (no queue, no order) in two parts: it
  // leaves at max(now + latency, depthTileReady()) when the HiZ could not
  // decide it (a read when the buffer lacks the tile), and the engine tallies
  // its tests and adds them after the phase, counted like push().
  Cycle depthTileReady(Cycle now, uint32_t tile) { return depthTile(now, tile); }
  void countTests(uint64_t tested, uint64_t hiz_decided) {
    stats_.tested += tested;
    stats_.hiz_decided += hiz_decided;
  }
  // Calls f(token) for each fragment leaving the stage at `now` (in order).
  template <class F>
  unsigned leave(Cycle now, F&& f) {
    if (q_.empty() || q_.front().ready > now) return 0;  // the common cycle: nobody due
    unsigned n = 0, slots = rate_.available(now);
    while (n < slots && !q_.empty() && q_.front().ready <= now) {
      const uint32_t t = q_.front().token;
      q_.pop();
      rate_.take();
      ++n;
      f(t);
    }
    return n;
  }
  // Earliest cycle > now at which leave() can move something (kNever if empty).
  // (Inline: the partition asks on every cycle it may skip.)
  Cycle nextEvent(Cycle now) const {
    if (q_.empty()) return kNever;
    const Entry& h = q_.front();
    // The head's status turns from busy (latency) to waiting (depth) at `passed`,
    // and back to busy at `ready` even when the rate lets it leave only later.
    if (h.passed > now && h.passed < h.ready) return h.passed;
    if (h.ready > now) return h.ready;
    return rate_.nextAvailable(now);
  }
  // The stage's status at `now` after leave() moved `moved` fragments.
  bool headWaitsForDepth(Cycle now) const {
    return !q_.empty() && q_.front().ready > now && q_.front().passed <= now;
  }
  size_t size() const { return q_.size(); }
  const EarlyDepthStats& stats() const { return stats_; }

 private:
  Cycle depthTile(Cycle now, uint32_t tile);  // cycle the tile's depth is in the buffer
  struct Entry {
    uint32_t token;
    Cycle ready;   // when it may leave (latency, depth data)
    Cycle passed;  // when the latency alone would let it leave
  };
  EarlyDepthConfig cfg_;
  RateLimiter rate_;
  uint32_t tile_bytes_;
  uint64_t depth_base_;
  MemoryPort& mem_;
  std::vector<uint32_t> tag_;    // tile + 1 (0 = empty)
  std::vector<uint32_t> slot_index_;  // per tile (empty: the tile)
  std::vector<Cycle> tag_ready_;
  Fifo<Entry> q_;
  Cycle last_ready_ = 0;  // in order: nobody leaves before the one ahead
  EarlyDepthStats stats_;
};

}  // namespace oit::rop
