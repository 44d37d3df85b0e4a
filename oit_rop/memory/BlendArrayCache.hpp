// The ROP's tile cache of per-pixel blending arrays: one line holds one screen
// tile's arrays (tile pixels x the algorithm's bytes per pixel); set-associative,
// LRU, write-back, with a bounded miss queue. Misses and dirty evictions go to
// the MemorySystem (surface BlendArrays).
//
// Fast clear: a tile never written in this frame is "clear" by a per-tile bit;
// its first miss needs no DRAM read, and the resolve skips it.
#pragma once

#include <cstdint>
#include <vector>

#include "oit_rop/memory/MemorySystem.hpp"
#include "oit_rop/config/RopConfig.hpp"
#include "oit_rop/Types.hpp"

namespace oit::rop {

struct CacheStats {
  uint64_t accesses = 0, hits = 0, misses = 0;
  uint64_t clear_fills = 0;     // misses on never-written tiles served without DRAM (fast clear)
  uint64_t evictions = 0, writebacks = 0;
  uint64_t miss_queue_full = 0; // acquire() calls refused because the miss queue was full
  uint64_t set_in_use = 0;      // misses refused because every way of the set was in use (pinned)
  uint32_t peak_misses_in_flight = 0;
  // Added: hits on a line whose fill was still in flight (counted in `hits`
  // too: the tag matched and no new DRAM traffic was made; the caller waits
  // for the fill).
  uint64_t hits_under_miss = 0;
  double hitRate() const { return accesses ? double(hits) / double(accesses) : 0.0; }
  bool operator==(const CacheStats&) const = default;
};

// Cache geometry once the algorithm fixes the line size (tile pixels x bytes per
// pixel), as BlendArrayCache models it (MEMORY.md): ways = min(cache.ways,
// lines), sets = lines / ways, lines = sets x ways (the rest of size_bytes
// unused). Throws std::invalid_argument, naming cache.size_bytes, when not even
// one line fits.
struct CacheGeometry {
  uint32_t line_bytes = 0, ways = 0, sets = 0, lines = 0;
};
CacheGeometry cacheGeometry(const CacheConfig& cache, uint32_t line_bytes);

class BlendArrayCache {
 public:
  // base_address: where the full-screen arrays start in DRAM; line i (tile i)
  // lives at base_address + i * line_bytes.
  // set_index (optional, one per tile): the number the set is chosen by, set =
  // set_index[tile] % sets (a partition passes its local tile numbers,
  // FrameGeometry::local); without it, the tile number itself.
  BlendArrayCache(const CacheConfig& cfg, uint32_t line_bytes, uint32_t tiles, uint64_t base_address,
                  MemorySystem& memory, bool fast_clear, std::vector<uint32_t> set_index = {});

  // A fragment of `tile` needs its pixel's array at cycle `now`. Returns the
  // cycle the line is available (hit: now + hit_latency; miss: when the fill
  // arrives, after any dirty victim was written back), or kNever when the miss
  // queue is full or every way of the tile's set is in use (the caller stalls
  // and retries: refusedBySet() tells which). `write` marks the line dirty and
  // the tile touched. An accepted acquire pins the line: it is in use (no
  // victim) until the caller's release() of the tile, so a line is never
  // evicted while its fill is in flight or before its blend wrote it.
  Cycle acquire(Cycle now, uint32_t tile, bool write) {  // inline: the hit path, once per fragment
    const uint32_t index = tile < tiles_ ? line_of_[tile] : kInvalid;
    if (index == kInvalid) [[unlikely]]
      return miss(now, tile, write);  // also throws std::out_of_range for a bad tile
    ++lines_[index].pins;
    return hit(lines_[index], now, tile, write);
  }
  // A fragment a few visits ahead will touch `tile`: its line-index entry is
  // an L1 miss (one entry per tile of the frame), so fetch it now. (A hint:
  // any tile number will do, nothing is read.)
  void prefetch(uint32_t tile) const { __builtin_prefetch(line_of_.data() + tile); }
  // acquire() and release() at once: a use that pins nothing (the approximate
  // engine, whose fragments hold no line across their blend). kNever as for
  // acquire(); the line is then not pinned either.
  // `missed`: whether the tile was not resident (an accepted or refused miss).
  Cycle touch(Cycle now, uint32_t tile, bool write, bool& missed) {  // inline: once per fragment
    const uint32_t index = tile < tiles_ ? line_of_[tile] : kInvalid;
    missed = index == kInvalid;
    if (missed) [[unlikely]] {
      const Cycle ready = miss(now, tile, write);
      if (ready != kNever) release(tile);
      return ready;
    }
    return hit(lines_[index], now, tile, write);
  }
  // The use of one acquire() of `tile` ended (its blend or resolve is done).
  // Returns true when this made a line of the set of the last refusedBySet()
  // acquire free (the refused access may now be retried).
  bool release(uint32_t tile) {  // inline: once per fragment
    const uint32_t index = tile < tiles_ ? line_of_[tile] : kInvalid;
    if (index == kInvalid || lines_[index].pins == 0) [[unlikely]]
      releaseWithoutAcquire(tile);
    if (--lines_[index].pins != 0) return false;
    if (!refused_by_set_ || index / ways_ != refused_set_) return false;
    refused_by_set_ = false;
    return true;
  }

  bool touched(uint32_t tile) const;
  bool resident(uint32_t tile) const;
  uint32_t lineBytes() const;
  uint32_t lines() const;  // capacity in lines
  const CacheStats& stats() const { return stats_; }

  // Added accessors.
  uint32_t ways() const;  // effective associativity (<= cfg.ways)
  uint32_t sets() const;
  uint32_t tiles() const;
  uint64_t lineAddress(uint32_t tile) const;  // base_address + tile * line_bytes
  uint32_t missesInFlight(Cycle now) const;   // miss-queue entries whose line is not yet available
  // After acquire() returned kNever: the cycle the first miss-queue entry frees
  // (an acquire before it would be refused again). Unspecified otherwise.
  Cycle missQueueFreesAt() const { return miss_queue_min_; }
  // After acquire() returned kNever: true when the set had no line out of use
  // (a retry can succeed only after a release()), false when the miss queue
  // was full (a retry can succeed at missQueueFreesAt()).
  bool refusedBySet() const { return refused_by_set_; }
  uint32_t linesInUse() const;  // lines pinned by acquires not yet released (a scan: for tests)

 private:
  static constexpr uint32_t kInvalid = ~uint32_t(0);
  struct Line {
    uint32_t tile = kInvalid;
    bool dirty = false;
    uint64_t stamp = 0;  // LRU: larger = more recently used; 0 only while invalid
    Cycle ready = 0;     // cycle the line's data is available
    uint32_t pins = 0;   // acquires of this line whose use has not ended (no victim while > 0)
  };
  Cycle miss(Cycle now, uint32_t tile, bool write);  // acquire() of a tile not resident (or out of range)
  Cycle hit(Line& line, Cycle now, uint32_t tile, bool write) {  // acquire() of a resident tile, but the pin
    ++stats_.accesses;
    ++stats_.hits;
    line.stamp = ++stamp_;
    if (write) {
      line.dirty = true;
      touched_[tile] = 1;
    }
    const Cycle hit_ready = now + cfg_.hit_latency;
    if (line.ready > hit_ready) {
      ++stats_.hits_under_miss;  // the fill is still in flight: wait for it
      return line.ready;
    }
    return hit_ready;
  }
  [[noreturn]] static void releaseWithoutAcquire(uint32_t tile);  // release()'s caller bug

  CacheConfig cfg_;
  uint32_t line_bytes_;
  uint32_t tiles_;
  uint64_t base_;
  MemorySystem& memory_;
  bool fast_clear_;
  uint32_t ways_ = 1, sets_ = 1;
  std::vector<Line> lines_;      // set-major: set * ways + way
  std::vector<uint8_t> touched_; // per tile: written this frame
  // Per tile: index in lines_ of the line holding it, kInvalid if none. The
  // same answer as searching the tile's set for its tag, without the search.
  std::vector<uint32_t> line_of_;
  std::vector<uint32_t> set_index_;  // per tile: set = set_index_[tile] % sets_ (empty: the tile)
  std::vector<Cycle> miss_queue_;  // per entry: cycle it frees (<= now: free)
  // The largest miss_queue_ entry, exact: an entry is only ever overwritten by a
  // later cycle (it is free, <= now, and the new one is >= now).
  Cycle miss_queue_max_ = 0;
  // The smallest miss_queue_ entry as of the last refused acquire (missQueueFreesAt).
  Cycle miss_queue_min_ = 0;
  uint64_t stamp_ = 0;
  bool refused_by_set_ = false;
  uint32_t refused_set_ = 0;  // set of the last acquire refused by its set
  CacheStats stats_;
};

}  // namespace oit::rop
