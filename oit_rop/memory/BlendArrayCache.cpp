// Set-associative, true-LRU, write-back cache of blending-array lines with
// sectors and a bounded miss queue. Policies and what counts as a hit: MEMORY.md.
#include "oit_rop/memory/BlendArrayCache.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <stdexcept>
#include <utility>

namespace oit::rop {

CacheGeometry cacheGeometry(const CacheConfig& cache, uint32_t line_bytes) {
  if (line_bytes == 0) throw std::invalid_argument("cache line size is 0 bytes");
  if (cache.ways == 0) throw std::invalid_argument("cache.ways must be >= 1");
  const uint64_t lines = cache.size_bytes / line_bytes;
  if (lines == 0)
    throw std::invalid_argument(fmt::format(
        "cache.size_bytes ({}) is smaller than one line of {} bytes (cache.line_bytes); enlarge cache.size_bytes or "
        "use shorter lines",
        cache.size_bytes, line_bytes));
  if (lines > UINT32_MAX) throw std::invalid_argument("cache.size_bytes: too many lines");
  CacheGeometry g;
  g.line_bytes = line_bytes;
  g.ways = uint32_t(std::min<uint64_t>(cache.ways, lines));  // fewer lines than ways: fully associative
  g.sets = uint32_t(lines / g.ways);                            // lines that cannot fill a set are unused
  g.lines = g.sets * g.ways;
  return g;
}

BlendArrayCache::BlendArrayCache(const CacheConfig& cfg, const TileLines& lines, uint32_t tiles,
                                 uint64_t base_address, MemoryPort& lower, bool fast_clear,
                                 std::vector<uint32_t> local, bool classify)
    : cfg_(cfg), geo_(lines), tiles_(tiles), base_(base_address), lower_(lower), fast_clear_(fast_clear),
      classify_(classify) {
  if (geo_.sector_bytes == 0) geo_.sector_bytes = geo_.line_bytes;
  if (geo_.line_bytes == 0 || geo_.lines_per_tile == 0)
    throw std::invalid_argument("BlendArrayCache: line_bytes and lines_per_tile must be > 0");
  if (geo_.line_bytes % geo_.sector_bytes != 0 || geo_.line_bytes / geo_.sector_bytes > 32)
    throw std::invalid_argument("BlendArrayCache: the sector must divide the line into at most 32 sectors");
  if (!local.empty() && local.size() != tiles)
    throw std::invalid_argument("BlendArrayCache: local must have one entry per tile");
  // A zero-entry miss queue could never serve a miss: the caller would stall forever.
  if (cfg.miss_queue == 0) throw std::invalid_argument("BlendArrayCache: miss_queue must be >= 1");
  // Capacity in lines (one source of truth with the configuration check; a
  // cache smaller than one line is refused, not silently enlarged).
  const CacheGeometry g = cacheGeometry(cfg, geo_.line_bytes);
  ways_ = g.ways;
  sets_ = g.sets;
  if (uint64_t(sets_) * ways_ >= kInvalid) throw std::invalid_argument("BlendArrayCache: too many lines");
  const uint32_t sectors = geo_.line_bytes / geo_.sector_bytes;
  all_sectors_ = sectors == 32 ? ~0u : (1u << sectors) - 1;
  uint64_t numbered = tiles;  // tiles the per-line tables cover
  if (!local.empty()) numbered = uint64_t(*std::max_element(local.begin(), local.end())) + 1;
  if (numbered * geo_.lines_per_tile >= kInvalid) throw std::invalid_argument("BlendArrayCache: too many lines");
  base_of_.resize(tiles);
  for (uint32_t t = 0; t < tiles; ++t) base_of_[t] = (local.empty() ? t : local[t]) * geo_.lines_per_tile;
  lines_.assign(size_t(sets_) * ways_, Line{});
  line_of_.assign(numbered * geo_.lines_per_tile, kInvalid);
  written_.assign(line_of_.size(), 0);
  tile_touched_.assign(tiles, 0);
  miss_queue_.assign(cfg.miss_queue, 0);
  miss_sorted_.assign(2 * size_t(cfg.miss_queue), 0);
  if (classify_) {
    fa_prev_.assign(line_of_.size(), kInvalid);
    fa_next_.assign(line_of_.size(), kInvalid);
    seen_.assign(line_of_.size(), 0);
    fa_in_.assign(line_of_.size(), 0);
    fa_valid_.assign(line_of_.size(), 0);
  }
  // (A fragment asks for every line it touches at once: one per line at most.)
  scratch_index_.reserve(64);
}

BlendArrayCache::~BlendArrayCache() = default;

void BlendArrayCache::classifyAccess(uint32_t ll, uint32_t sectors, bool missed) {
  const bool fresh = (sectors & ~seen_[ll]) != 0;
  seen_[ll] |= sectors;
  // The fully associative cache holds ll's sectors fa_valid_[ll] while
  // fa_in_[ll]; it hits when it holds every sector the access needs.
  const bool fa_present = fa_in_[ll] != 0;
  const bool fa_hit = fa_present && (sectors & ~fa_valid_[ll]) == 0;
  fa_valid_[ll] = (fa_present ? fa_valid_[ll] : 0) | sectors;
  // Move (or put) ll at the front of the fully associative LRU list.
  if (fa_present) {
    if (fa_head_ != ll) {
      const uint32_t p = fa_prev_[ll], n = fa_next_[ll];
      fa_next_[p] = n;
      (n == kInvalid ? fa_tail_ : fa_prev_[n]) = p;
      fa_prev_[ll] = kInvalid;
      fa_next_[ll] = fa_head_;
      fa_prev_[fa_head_] = ll;
      fa_head_ = ll;
    }
  } else {
    fa_in_[ll] = 1;
    fa_prev_[ll] = kInvalid;
    fa_next_[ll] = fa_head_;
    (fa_head_ == kInvalid ? fa_tail_ : fa_prev_[fa_head_]) = ll;
    fa_head_ = ll;
    if (++fa_size_ > lines()) {  // the least recently used line leaves
      const uint32_t t = fa_tail_;
      fa_in_[t] = 0;
      fa_tail_ = fa_prev_[t];
      fa_next_[fa_tail_] = kInvalid;
      --fa_size_;
    }
  }
  if (!missed) return;
  if (fresh) ++stats_.compulsory_misses;
  else if (fa_hit) ++stats_.conflict_misses;
  else ++stats_.capacity_misses;
}

bool BlendArrayCache::missQueueRefuses(Cycle now, uint32_t misses, uint32_t& busy) {
  // A free miss-queue entry per missing line (one whose line is available by
  // now). The entries' cycles in ascending order (miss_sorted_) give the free
  // count and the cycle the last entry needed frees without a scan: the queue
  // is nearly always busy (bench trace: 96 % of the entries), so this test
  // runs on most misses and on every refused retry.
  busy = 0;  // entries in flight before this access
  const Cycle* const sorted = miss_sorted_.data() + sorted_head_;
  if (sorted[cfg_.miss_queue - 1] <= now) return false;  // the latest entry is free: all are
  uint32_t free = 0;
  while (free < cfg_.miss_queue && sorted[free] <= now) ++free;
  busy = cfg_.miss_queue - free;
  if (free >= misses) return false;
  // Exact: the (misses - free)-th smallest busy entry frees the last one
  // needed (one missing line, the usual case: the earliest), i.e. the
  // misses-th smallest entry.
  miss_queue_min_ = sorted[std::min(misses, cfg_.miss_queue) - 1];
  refused_by_set_ = false;
  ++stats_.miss_queue_full;  // refused: no state change, not counted as an access
  return true;
}

uint32_t BlendArrayCache::victimIn(uint32_t set) const {
  // The first invalid way, else the least recently used of the lines out of
  // use (stamps are 0 only while invalid); kInvalid when every way is pinned.
  const size_t first = size_t(set) * ways_;
  uint32_t victim = kInvalid;
  uint64_t victim_stamp = ~uint64_t(0);  // stamps never reach it
  for (size_t w = first; w < first + ways_; ++w)
    if (lines_[w].pins == 0 && lines_[w].stamp < victim_stamp) {
      victim = uint32_t(w);
      victim_stamp = lines_[w].stamp;
    }
  return victim;
}

Cycle BlendArrayCache::refuseBySet(uint32_t set) {
  // Refused like a full miss queue: no state change (the caller undid its pins).
  refused_by_set_ = true;
  refused_set_ = set;
  ++stats_.set_in_use;
  return kNever;
}

Cycle BlendArrayCache::commitMiss(Cycle now, uint32_t tile, const LineTouch& t, uint32_t index, bool absent,
                                  uint32_t& slot) {
  Line& line = lines_[index];
  const uint32_t ll = lineOf(tile, t.line);
  ++stats_.accesses;
  ++stats_.misses;
  stats_.read_bytes += uint64_t(sectorCount(t.fill)) * geo_.sector_bytes;
  if (classify_) classifyAccess(ll, t.fill | t.dirty, true);
  Cycle line_ready = now + cfg_.hit_latency;
  if (absent) {
    if (line.line != kInvalid) {
      ++stats_.evictions;
      line_of_[line.line] = kInvalid;
      if (line.dirty) {
        ++stats_.writebacks;
        const uint64_t addr = lineAddress(line.tile, line.in_tile);
        forEachRun(line.dirty, [&](uint32_t s, uint32_t e) {  // a write per run of dirty sectors
          const uint32_t bytes = (e - s) * geo_.sector_bytes;
          stats_.writeback_bytes += bytes;
          line_ready = std::max(line_ready, lower_.access(now, addr + uint64_t(s) * geo_.sector_bytes, bytes, true,
                                                          Surface::BlendArrays));
        });
      }
    }
    const uint32_t pins = line.pins;
    line = Line{};
    line.line = ll;
    line.tile = tile;
    line.in_tile = t.line;
    line.pins = pins;
    line_of_[ll] = index;
  } else {
    ++stats_.sector_misses;
  }
  // The sectors to fill: those needed and not held; with fast clear, the
  // ones never written this frame come from the clear value on chip.
  const uint32_t missing = t.fill & ~line.valid;
  const uint32_t from_below = fast_clear_ ? missing & written_[ll] : missing;
  if (from_below == 0) {
    ++stats_.clear_fills;
  } else {
    const uint64_t addr = lineAddress(tile, t.line);
    forEachRun(from_below, [&](uint32_t s, uint32_t e) {  // a read per run of sectors
      const uint32_t bytes = (e - s) * geo_.sector_bytes;
      stats_.fill_bytes += bytes;
      line_ready = std::max(line_ready, lower_.access(now, addr + uint64_t(s) * geo_.sector_bytes, bytes, false,
                                                      Surface::BlendArrays));
    });
  }
  line.valid |= missing | t.dirty;
  if (t.dirty) {
    line.dirty |= t.dirty;
    written_[ll] |= t.dirty;
    tile_touched_[tile] = 1;
    stats_.write_bytes += uint64_t(sectorCount(t.dirty)) * geo_.sector_bytes;
  }
  line.stamp = ++stamp_;
  line.ready = std::max(line.ready, line_ready);
  // Its miss-queue entry (the first free one from `slot` on): busy until the line is there.
  while (miss_queue_[slot] > now) ++slot;
  replaceSorted(miss_queue_[slot], line.ready);
  miss_queue_[slot] = line.ready;
  return line.ready;
}

// Out of line: several lines, or a line missing (or lacking a sector).
Cycle BlendArrayCache::acquireSlow(Cycle now, uint32_t tile, std::span<const LineTouch> lines, bool pin) {
  if (tile >= tiles_) throw std::out_of_range("BlendArrayCache::acquire: tile out of range");
  if (lines.size() == 1) [[likely]] {
    // One line, and acquire() / touch() found it missing: the same steps as
    // below for one line, without the lists.
    const LineTouch& t = lines[0];
    if (t.line >= geo_.lines_per_tile) throw std::out_of_range("BlendArrayCache::acquire: line out of range");
    uint32_t index = indexOf(tile, t.line);
    const bool absent = index == kInvalid;
    uint32_t busy;
    if (missQueueRefuses(now, 1, busy)) return kNever;
    if (absent) {
      const uint32_t set = (base_of_[tile] + t.line) % sets_;
      index = victimIn(set);
      if (index == kInvalid) return refuseBySet(set);
    }
    refused_by_set_ = false;
    // Pinned while its fill is booked (below the victim keeps the pins of its way).
    ++lines_[index].pins;
    uint32_t slot = 0;
    const Cycle line_ready = commitMiss(now, tile, t, index, absent, slot);
    stats_.peak_misses_in_flight =
        std::max(stats_.peak_misses_in_flight, std::min(busy + (line_ready > now ? 1u : 0u), cfg_.miss_queue));
    if (!pin) --lines_[index].pins;
    return std::max(now + cfg_.hit_latency, line_ready);
  }
  // Which lines are resident with their sectors (hits), resident without some
  // (sector misses) or absent (tag misses).
  scratch_index_.clear();
  uint32_t misses = 0;
  for (const LineTouch& t : lines) {
    if (t.line >= geo_.lines_per_tile) throw std::out_of_range("BlendArrayCache::acquire: line out of range");
    const uint32_t index = indexOf(tile, t.line);
    scratch_index_.push_back(index);
    misses += index == kInvalid || (t.fill & ~lines_[index].valid) != 0;
  }
  uint32_t busy = 0;  // entries in flight before this access
  if (misses != 0 && missQueueRefuses(now, misses, busy)) return kNever;
  // Victims for the absent lines: the first invalid way, else the least
  // recently used of the lines out of use (a pinned line is filling or waits
  // for its blend; evicting it would let more fills be in flight than the
  // cache has lines). The access's own lines are pinned first, so none of
  // them becomes another's victim; when a set has no line left the pins are
  // undone and the access is refused.
  for (uint32_t index : scratch_index_)
    if (index != kInvalid) ++lines_[index].pins;
  for (size_t i = 0; i < lines.size(); ++i) {
    if (scratch_index_[i] != kInvalid) continue;
    const uint32_t set = (base_of_[tile] + lines[i].line) % sets_;
    const uint32_t victim = victimIn(set);
    if (victim == kInvalid) {
      for (uint32_t index : scratch_index_)  // the access's lines and the victims chosen so far
        if (index != kInvalid) --lines_[index & 0x7FFFFFFFu].pins;
      return refuseBySet(set);
    }
    ++lines_[victim].pins;
    scratch_index_[i] = victim | 0x80000000u;  // marked: a victim for an absent line
  }
  refused_by_set_ = false;

  // Commit.
  const Cycle hit_ready = now + cfg_.hit_latency;
  Cycle ready = hit_ready;
  uint32_t slot = 0;  // miss-queue search position
  uint32_t mine = 0;  // this access's misses still in flight at `now`
  for (size_t i = 0; i < lines.size(); ++i) {
    const LineTouch& t = lines[i];
    const bool absent = (scratch_index_[i] & 0x80000000u) != 0;
    const uint32_t index = scratch_index_[i] & 0x7FFFFFFFu;
    Line& line = lines_[index];
    if (!absent && (t.fill & ~line.valid) == 0) {
      ready = std::max(ready, hit(line, now, lineOf(tile, t.line), t));
      continue;
    }
    const Cycle line_ready = commitMiss(now, tile, t, index, absent, slot);
    ready = std::max(ready, line_ready);
    mine += line_ready > now;
  }
  if (misses != 0) {
    // The entries busy before plus this access's misses whose line is not there yet.
    stats_.peak_misses_in_flight = std::max(stats_.peak_misses_in_flight, std::min(busy + mine, cfg_.miss_queue));
  }
  if (!pin)
    for (uint32_t index : scratch_index_) --lines_[index & 0x7FFFFFFFu].pins;
  return ready;
}

void BlendArrayCache::replaceSorted(Cycle old, Cycle now_ready) {
  // `old` is in the list, near its front (it is free: not later than the
  // access's cycle); the new value is not smaller (an entry only grows) and
  // usually the largest. The list is a window of a buffer twice its size:
  // `old` leaves by shifting the few values before it one place on and
  // moving the window's start; the new value enters at the window's end and
  // moves back past the larger values (usually none).
  const size_t n = cfg_.miss_queue;
  Cycle* const b = miss_sorted_.data();
  size_t i = sorted_head_;
  while (b[i] != old) ++i;
  for (; i > sorted_head_; --i) b[i] = b[i - 1];
  if (++sorted_head_ == n) {  // the window reached the buffer's end: back to its start
    std::copy(b + n, b + 2 * n - 1, b);
    sorted_head_ = 0;
  }
  size_t j = sorted_head_ + n - 1;
  for (; j > sorted_head_ && b[j - 1] > now_ready; --j) b[j] = b[j - 1];
  b[j] = now_ready;
}

void BlendArrayCache::releaseWithoutAcquire(uint32_t tile, uint32_t line) {
  throw std::logic_error(fmt::format("BlendArrayCache::release: line {} of tile {} has no acquire in use", line, tile));
}

bool BlendArrayCache::touched(uint32_t tile) const { return tile < tiles_ && tile_touched_[tile]; }
uint64_t BlendArrayCache::writtenBytes() const {
  uint64_t sectors = 0;
  for (uint32_t m : written_) sectors += uint64_t(std::popcount(m));
  return sectors * geo_.sector_bytes;
}
uint32_t BlendArrayCache::writtenSectors(uint32_t tile, uint32_t line) const {
  return tile < tiles_ && line < geo_.lines_per_tile ? written_[lineOf(tile, line)] : 0;
}
bool BlendArrayCache::resident(uint32_t tile, uint32_t line) const {
  return tile < tiles_ && line < geo_.lines_per_tile && indexOf(tile, line) != kInvalid;
}
uint32_t BlendArrayCache::lines() const { return static_cast<uint32_t>(lines_.size()); }
uint32_t BlendArrayCache::ways() const { return ways_; }
uint32_t BlendArrayCache::sets() const { return sets_; }
uint32_t BlendArrayCache::tiles() const { return tiles_; }
uint64_t BlendArrayCache::lineAddress(uint32_t tile, uint32_t line) const {
  return base_ + (uint64_t(tile) * geo_.lines_per_tile + line) * geo_.line_bytes;
}

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

void BlendArrayCache::dirtyRanges(std::vector<DirtyRange>& out) const {
  for (const Line& l : lines_) {
    if (l.line == kInvalid || l.dirty == 0) continue;
    const uint64_t addr = lineAddress(l.tile, l.in_tile);
    forEachRun(l.dirty, [&](uint32_t s, uint32_t e) {
      out.push_back({addr + uint64_t(s) * geo_.sector_bytes, (e - s) * geo_.sector_bytes, Surface::BlendArrays});
    });
  }
}

}  // namespace oit::rop
