// The ROP's cache of per-pixel blending arrays (one per partition): lines of
// cache.line_bytes with valid and dirty bits per sector, set-associative, LRU,
// write-back, with a bounded miss queue (one entry per missing line).
// A screen tile's arrays are lines_per_tile consecutive lines (ArrayLayout);
// an access names its tile and the lines of it it touches (LineTouch: the
// sectors it needs and those it writes), all of which it gets or none. Fills
// and write-backs go to the level below (the shared l2, or DRAM), surface
// BlendArrays.
//
// Fast clear: a sector never written in this frame is "clear" (per-sector
// bits); it needs no read from below, and the resolve skips untouched tiles.
#pragma once

#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "oit_rop/config/RopConfig.hpp"
#include "oit_rop/memory/ArrayLayout.hpp"
#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/Types.hpp"

namespace oit::rop {

struct CacheStats {
  // Per line an access touched (an access of three lines counts three).
  uint64_t accesses = 0, hits = 0, misses = 0;
  uint64_t sector_misses = 0;   // misses on a resident line lacking a sector (in misses too)
  uint64_t clear_fills = 0;     // misses served by the fast clear alone (no read below)
  uint64_t evictions = 0, writebacks = 0;
  uint64_t miss_queue_full = 0; // accesses refused because the miss queue lacked entries
  uint64_t set_in_use = 0;      // accesses refused because a set had no line out of use (pinned)
  uint32_t peak_misses_in_flight = 0;
  // Hits on a line whose fill was still in flight (counted in `hits` too: the
  // tag matched and no new traffic was made; the caller waits for the fill).
  uint64_t hits_under_miss = 0;
  uint64_t read_bytes = 0, write_bytes = 0;       // sectors the accesses needed / wrote, in bytes
  uint64_t fill_bytes = 0, writeback_bytes = 0;   // moved from / to the level below
  // The misses' causes (stats.miss_classes): a sector never held before
  // (compulsory), one a fully associative LRU cache of the same lines would
  // have held (conflict), or not (capacity).
  uint64_t compulsory_misses = 0, capacity_misses = 0, conflict_misses = 0;
  double hitRate() const { return accesses ? double(hits) / double(accesses) : 0.0; }
  bool operator==(const CacheStats&) const = default;
  // Adds another partition's counts (the peak: the larger).
  CacheStats& operator+=(const CacheStats& o) {
    accesses += o.accesses, hits += o.hits, misses += o.misses, sector_misses += o.sector_misses;
    clear_fills += o.clear_fills, evictions += o.evictions, writebacks += o.writebacks;
    miss_queue_full += o.miss_queue_full, set_in_use += o.set_in_use;
    peak_misses_in_flight = std::max(peak_misses_in_flight, o.peak_misses_in_flight);
    hits_under_miss += o.hits_under_miss, read_bytes += o.read_bytes, write_bytes += o.write_bytes;
    fill_bytes += o.fill_bytes, writeback_bytes += o.writeback_bytes;
    compulsory_misses += o.compulsory_misses, capacity_misses += o.capacity_misses;
    conflict_misses += o.conflict_misses;
    return *this;
  }
};

// Cache geometry for lines of `line_bytes` (cache.line_bytes): ways =
// min(cache.ways, lines), sets = lines / ways, lines = sets x ways (the rest
// of size_bytes unused). Throws std::invalid_argument, naming
// cache.size_bytes, when not even one line fits.
struct CacheGeometry {
  uint32_t line_bytes = 0, ways = 0, sets = 0, lines = 0;
};
CacheGeometry cacheGeometry(const CacheConfig& cache, uint32_t line_bytes);

// How a tile's arrays fall into lines: lines_per_tile lines of line_bytes,
// sectors of sector_bytes (= line_bytes: no sectors).
struct TileLines {
  uint32_t line_bytes = 0, sector_bytes = 0, lines_per_tile = 1;
};

class BlendArrayCache {
 public:
  // base_address: where the frame's arrays start below; tile t's line l lives
  // at base_address + (t x lines_per_tile + l) x line_bytes.
  // local (optional, one per tile): the partition's own number of each tile
  // (FrameGeometry::local); the cache's per-line tables and its set index
  // count lines among those tiles only (set = (local x lines_per_tile + l)
  // mod sets). Without it, the tile number itself. `classify`: count the
  // misses' causes (CacheStats; costs a list update per line access).
  BlendArrayCache(const CacheConfig& cfg, const TileLines& lines, uint32_t tiles, uint64_t base_address,
                  MemoryPort& lower, bool fast_clear, std::vector<uint32_t> local = {}, bool classify = false);
  ~BlendArrayCache();
  BlendArrayCache(const BlendArrayCache&) = delete;
  BlendArrayCache& operator=(const BlendArrayCache&) = delete;

  // A fragment (or the resolve) of `tile` needs the lines `lines` at cycle
  // `now`. Returns the cycle they are all available (a hit: now + hit_latency,
  // or its fill's cycle while that is in flight; a miss: when its fill
  // arrives, after any dirty victim was written back), or kNever when the miss
  // queue lacks an entry for each missing line or a set has no line out of use
  // for it (nothing changes then; refusedBySet() says which; the caller
  // retries). Lines written get their sectors dirty and touched. An accepted
  // acquire pins every line it names until release() of the same lines.
  Cycle acquire(Cycle now, uint32_t tile, std::span<const LineTouch> lines) {
    if (lines.size() == 1) [[likely]] {  // inline: the usual case, once per fragment
      const LineTouch& t = lines[0];
      const uint32_t index = indexOf(tile, t.line);
      if (index != kInvalid && (t.fill & ~lines_[index].valid) == 0) [[likely]] {
        ++lines_[index].pins;
        return hit(lines_[index], now, lineOf(tile, t.line), t);
      }
    }
    return acquireSlow(now, tile, lines, true);
  }
  // acquire() then release() at once: a use that pins nothing (the
  // approximate engine; the resolve). kNever as for acquire(). `missed`:
  // whether some line was not resident with its sectors (an accepted or
  // refused miss).
  Cycle touch(Cycle now, uint32_t tile, std::span<const LineTouch> lines, bool& missed) {
    if (lines.size() == 1) [[likely]] {
      const LineTouch& t = lines[0];
      const uint32_t index = indexOf(tile, t.line);
      if (index != kInvalid && (t.fill & ~lines_[index].valid) == 0) [[likely]] {
        missed = false;
        return hit(lines_[index], now, lineOf(tile, t.line), t);
      }
    }
    missed = true;
    return acquireSlow(now, tile, lines, false);
  }
  // The use of one acquire() of these lines ended (its blend is done).
  // Returns true when this made a line of the set of the last refusedBySet()
  // acquire free (the refused access may now be retried).
  bool release(uint32_t tile, std::span<const LineTouch> lines) {
    bool freed = false;
    for (const LineTouch& t : lines) {
      const uint32_t index = indexOf(tile, t.line);
      if (index == kInvalid || lines_[index].pins == 0) [[unlikely]]
        releaseWithoutAcquire(tile, t.line);
      if (--lines_[index].pins == 0 && refused_by_set_ && index / ways_ == refused_set_) {
        refused_by_set_ = false;
        freed = true;
      }
    }
    return freed;
  }
  // A fragment a few visits ahead will touch `tile`: its line-index entries
  // are likely L1 misses, so fetch them now (a hint: nothing is read).
  void prefetch(uint32_t tile) const { __builtin_prefetch(line_of_.data() + base_of_[tile]); }

  bool touched(uint32_t tile) const;  // a sector of the tile was written this frame
  uint64_t writtenBytes() const;      // the sectors written this frame, in bytes
  // The sectors of line l of `tile` written this frame (fast clear: the others are clear).
  uint32_t writtenSectors(uint32_t tile, uint32_t line) const;
  bool resident(uint32_t tile, uint32_t line = 0) const;
  uint32_t lineBytes() const { return geo_.line_bytes; }
  uint32_t sectorBytes() const { return geo_.sector_bytes; }
  uint32_t linesPerTile() const { return geo_.lines_per_tile; }
  uint32_t lines() const;  // capacity in lines
  uint32_t ways() const;   // effective associativity (<= cfg.ways)
  uint32_t sets() const;
  uint32_t tiles() const;
  uint64_t lineAddress(uint32_t tile, uint32_t line = 0) const;
  const CacheStats& stats() const { return stats_; }
  uint32_t missesInFlight(Cycle now) const;  // miss-queue entries whose line is not yet available
  // After acquire() returned kNever: the cycle enough miss-queue entries are
  // free (an acquire before it would be refused again). Unspecified otherwise.
  Cycle missQueueFreesAt() const { return miss_queue_min_; }
  // After acquire() returned kNever: true when a set had no line out of use
  // (a retry can succeed only after a release()), false when the miss queue
  // lacked entries (a retry can succeed at missQueueFreesAt()).
  bool refusedBySet() const { return refused_by_set_; }
  uint32_t linesInUse() const;  // lines pinned by acquires not yet released (a scan: for tests)
  // Every dirty sector still held (frame end), merged into runs per line.
  void dirtyRanges(std::vector<DirtyRange>& out) const;

 private:
  static constexpr uint32_t kInvalid = ~uint32_t(0);
  struct Line {
    uint32_t line = kInvalid;  // the partition's line number (local tile x lines per tile + l)
    uint32_t tile = 0, in_tile = 0;  // for its address
    uint32_t valid = 0, dirty = 0;
    uint64_t stamp = 0;  // LRU: larger = more recently used; 0 only while invalid
    Cycle ready = 0;     // cycle the line's last fill is available
    uint32_t pins = 0;   // acquires of this line whose use has not ended (no victim while > 0)
  };
  uint32_t lineOf(uint32_t tile, uint32_t l) const { return base_of_[tile] + l; }
  uint32_t indexOf(uint32_t tile, uint32_t l) const {
    return tile < tiles_ ? line_of_[base_of_[tile] + l] : kInvalid;
  }
  Cycle acquireSlow(Cycle now, uint32_t tile, std::span<const LineTouch> lines, bool pin);
  // acquireSlow's steps. Refuses (true; the stats and missQueueFreesAt() set)
  // when the miss queue lacks an entry for each of `misses`; `busy`: the
  // entries in flight.
  bool missQueueRefuses(Cycle now, uint32_t misses, uint32_t& busy);
  uint32_t victimIn(uint32_t set) const;  // a way out of use for a new line, or kInvalid
  Cycle refuseBySet(uint32_t set);        // no way of `set` out of use: kNever, counted (set_in_use)
  // A missing line (absent: into way `index`, evicting its line) filled, its
  // miss-queue entry taken (the first free from `slot` on); returns when it is there.
  Cycle commitMiss(Cycle now, uint32_t tile, const LineTouch& t, uint32_t index, bool absent, uint32_t& slot);
  Cycle hit(Line& line, Cycle now, uint32_t ll, const LineTouch& t) {  // a resident line with its sectors, but the pin
    ++stats_.accesses;
    ++stats_.hits;
    stats_.read_bytes += uint64_t(sectorCount(t.fill)) * geo_.sector_bytes;
    if (classify_) classifyAccess(ll, t.fill | t.dirty, false);
    line.stamp = ++stamp_;
    if (t.dirty) {
      line.dirty |= t.dirty;
      line.valid |= t.dirty;
      written_[ll] |= t.dirty;
      tile_touched_[line.tile] = 1;
      stats_.write_bytes += uint64_t(sectorCount(t.dirty)) * geo_.sector_bytes;
    }
    const Cycle hit_ready = now + cfg_.hit_latency;
    if (line.ready > hit_ready) {
      ++stats_.hits_under_miss;  // the fill is still in flight: wait for it
      return line.ready;
    }
    return hit_ready;
  }
  void classifyAccess(uint32_t ll, uint32_t sectors, bool missed);
  void replaceSorted(Cycle old, Cycle now_ready);  // miss_sorted_: one entry old -> now_ready (>= old)
  [[noreturn]] static void releaseWithoutAcquire(uint32_t tile, uint32_t line);

  CacheConfig cfg_;
  TileLines geo_;
  uint32_t tiles_;
  uint64_t base_;
  MemoryPort& lower_;
  bool fast_clear_;
  bool classify_;
  uint32_t ways_ = 1, sets_ = 1, all_sectors_ = 1;
  std::vector<Line> lines_;          // set-major: set * ways + way
  std::vector<uint32_t> base_of_;    // per tile: its first line's number (local x lines per tile)
  std::vector<uint32_t> line_of_;    // per line number: index in lines_ of the line holding it, kInvalid if none
  std::vector<uint32_t> written_;    // per line number: sectors written this frame
  std::vector<uint8_t> tile_touched_;  // per tile: a sector written this frame
  std::vector<Cycle> miss_queue_;    // per entry: cycle it frees (<= now: free)
  std::vector<Cycle> miss_sorted_;   // the same cycles, ascending: [sorted_head_, + miss_queue) of twice that
  size_t sorted_head_ = 0;
  Cycle miss_queue_min_ = 0;         // after a refusal: when enough entries are free
  uint64_t stamp_ = 0;
  bool refused_by_set_ = false;
  uint32_t refused_set_ = 0;  // set of the last acquire refused by its set
  // Miss classes: a fully associative LRU list over the line numbers, the
  // sectors it holds of each line in it (fa_valid_) and the sectors each line
  // ever held (seen_) (only with classify_).
  std::vector<uint32_t> fa_prev_, fa_next_, fa_valid_, seen_;
  std::vector<uint8_t> fa_in_;
  uint32_t fa_head_ = kInvalid, fa_tail_ = kInvalid, fa_size_ = 0;
  // Scratch of acquireSlow (no allocation per call).
  std::vector<uint32_t> scratch_index_;
  CacheStats stats_;
};

}  // namespace oit::rop
