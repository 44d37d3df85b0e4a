// Set-associative, true-LRU, write-back tile cache with a bounded miss queue.
// Policies and what counts as a hit: MEMORY.md.
#include "oit_rop/memory/BlendArrayCache.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <utility>
#include <stdexcept>

namespace oit::rop {

CacheGeometry cacheGeometry(const CacheConfig& cache, uint32_t line_bytes) {
  if (line_bytes == 0) throw std::invalid_argument("cache line size is 0 bytes");
  if (cache.ways == 0) throw std::invalid_argument("cache.ways must be >= 1");
  const uint64_t lines = cache.size_bytes / line_bytes;
  if (lines == 0)
    throw std::invalid_argument(fmt::format(
        "cache.size_bytes ({}) is smaller than one line of {} bytes (one tile's blending arrays); "
        "enlarge cache.size_bytes, or shrink the tile (partitions.tile_width / tile_height) or the arrays",
        cache.size_bytes, line_bytes));
  if (lines > UINT32_MAX) throw std::invalid_argument("cache.size_bytes: too many lines");
  CacheGeometry g;
  g.line_bytes = line_bytes;
  g.ways = uint32_t(std::min<uint64_t>(cache.ways, lines));  // fewer lines than ways: fully associative
  g.sets = uint32_t(lines / g.ways);                            // lines that cannot fill a set are unused
  g.lines = g.sets * g.ways;
  return g;
}

BlendArrayCache::BlendArrayCache(const CacheConfig& cfg, uint32_t line_bytes, uint32_t tiles, uint64_t base_address,
                                 MemorySystem& memory, bool fast_clear, std::vector<uint32_t> set_index)
    : cfg_(cfg), line_bytes_(line_bytes), tiles_(tiles), base_(base_address), memory_(memory), fast_clear_(fast_clear),
      set_index_(std::move(set_index)) {
  if (!set_index_.empty() && set_index_.size() != tiles)
    throw std::invalid_argument("BlendArrayCache: set_index must have one entry per tile");
  if (line_bytes == 0) throw std::invalid_argument("BlendArrayCache: line_bytes must be > 0");
  // A zero-entry miss queue could never serve a miss: the caller would stall forever.
  if (cfg.miss_queue == 0) throw std::invalid_argument("BlendArrayCache: miss_queue must be >= 1");
  // Capacity in lines (one source of truth with the configuration check; a
  // cache smaller than one line is refused, not silently enlarged).
  const CacheGeometry g = cacheGeometry(cfg, line_bytes);
  ways_ = g.ways;
  sets_ = g.sets;
  if (uint64_t(sets_) * ways_ >= kInvalid) throw std::invalid_argument("BlendArrayCache: too many lines");
  lines_.assign(size_t(sets_) * ways_, Line{});
  line_of_.assign(tiles, kInvalid);
  touched_.assign(tiles, 0);
  miss_queue_.assign(cfg.miss_queue, 0);
}

// Out of line: keeps the frequent hit path of acquire() small.
Cycle BlendArrayCache::miss(Cycle now, uint32_t tile, bool write) {
  if (tile >= tiles_) throw std::out_of_range("BlendArrayCache::acquire: tile out of range");
  // A free miss-queue entry is needed (one whose line is available by now): the
  // first free one. When every entry is free (no miss in flight) that is entry 0.
  const uint32_t entries = cfg_.miss_queue;
  uint32_t slot = 0;
  uint32_t in_flight = 0;
  if (miss_queue_max_ > now) {
    slot = entries;
    for (uint32_t i = entries; i-- > 0;) {  // backwards: the last free one seen is the first
      const bool busy = miss_queue_[i] > now;
      in_flight += busy;
      if (!busy) slot = i;
    }
    if (slot == entries) {
      // Exact: every entry is busy until then. (A scan of its own: refusals are rare.)
      miss_queue_min_ = *std::min_element(miss_queue_.begin(), miss_queue_.end());
      refused_by_set_ = false;
      ++stats_.miss_queue_full;  // refused: no state change, not counted as an access
      return kNever;
    }
  }

  // Victim: the first invalid way, else the least recently used of the lines
  // out of use (a pinned line is filling or waits for its blend; evicting it
  // would let more fills be in flight than the cache has lines). Invalid lines
  // have stamp 0 and valid ones distinct stamps >= 1, so this is the first
  // unpinned way with the smallest stamp.
  const uint32_t set = (set_index_.empty() ? tile : set_index_[tile]) % sets_;
  const size_t first = size_t(set) * ways_;
  size_t victim_index = kInvalid;
  uint64_t victim_stamp = ~uint64_t(0);  // stamps never reach it
  for (size_t i = first; i < first + ways_; ++i)
    if (lines_[i].pins == 0 && lines_[i].stamp < victim_stamp) {
      victim_index = i;
      victim_stamp = lines_[i].stamp;
    }
  if (victim_index == kInvalid) {
    refused_by_set_ = true;
    refused_set_ = set;
    ++stats_.set_in_use;  // refused like a full miss queue: no state change
    return kNever;
  }
  refused_by_set_ = false;
  ++stats_.accesses;
  ++stats_.misses;
  Line& victim = lines_[victim_index];

  const Cycle hit_ready = now + cfg_.hit_latency;
  Cycle ready = hit_ready;
  if (victim.tile != kInvalid) {
    ++stats_.evictions;
    line_of_[victim.tile] = kInvalid;
    if (victim.dirty) {
      ++stats_.writebacks;
      ready = std::max(ready, memory_.access(now, lineAddress(victim.tile), line_bytes_, true, Surface::BlendArrays));
    }
  }
  if (fast_clear_ && !touched_[tile]) {
    ++stats_.clear_fills;  // the clear value is produced on chip
  } else {
    ready = std::max(ready, memory_.access(now, lineAddress(tile), line_bytes_, false, Surface::BlendArrays));
  }

  victim.tile = tile;
  victim.dirty = write;
  victim.stamp = ++stamp_;
  victim.ready = ready;
  victim.pins = 1;
  line_of_[tile] = static_cast<uint32_t>(victim_index);
  if (write) touched_[tile] = 1;

  miss_queue_[slot] = ready;
  miss_queue_max_ = std::max(miss_queue_max_, ready);
  stats_.peak_misses_in_flight = std::max(stats_.peak_misses_in_flight, in_flight + (ready > now ? 1u : 0u));
  return ready;
}

void BlendArrayCache::releaseWithoutAcquire(uint32_t tile) {
  throw std::logic_error(fmt::format("BlendArrayCache::release: tile {} has no acquire in use", tile));
}

bool BlendArrayCache::touched(uint32_t tile) const { return tile < tiles_ && touched_[tile]; }
bool BlendArrayCache::resident(uint32_t tile) const { return tile < tiles_ && line_of_[tile] != kInvalid; }
uint32_t BlendArrayCache::lineBytes() const { return line_bytes_; }
uint32_t BlendArrayCache::lines() const { return static_cast<uint32_t>(lines_.size()); }
uint32_t BlendArrayCache::ways() const { return ways_; }
uint32_t BlendArrayCache::sets() const { return sets_; }
uint32_t BlendArrayCache::tiles() const { return tiles_; }
uint64_t BlendArrayCache::lineAddress(uint32_t tile) const { return base_ + uint64_t(tile) * line_bytes_; }

uint32_t BlendArrayCache::linesInUse() const {
  uint32_t n = 0;
  for (const Line& l : lines_) n += l.pins != 0 ? 1u : 0u;
  return n;
}

uint32_t BlendArrayCache::missesInFlight(Cycle now) const {
  uint32_t n = 0;
  for (Cycle c : miss_queue_) n += c > now ? 1u : 0u;
  return n;
}

}  // namespace oit::rop
