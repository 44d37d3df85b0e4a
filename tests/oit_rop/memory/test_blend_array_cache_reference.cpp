// Blending-array cache (the ROP cache) against a reference that writes the policies of
// oit_rop/memory/MEMORY.md out plainly, on random streams of accesses.
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "oit_rop/TestLcg.hpp"
#include "oit_rop/memory/BlendArrayCache.hpp"
#include "oit_rop/memory/BlendArrayCacheTestUtil.hpp"
#include "oit_rop/memory/DramSystem.hpp"

namespace oit::rop {
namespace blend_array_cache_reference_test {

using namespace cache_testutil;

// Reference: the policies of MEMORY.md written out plainly (tag search over the
// set, miss queue as a list of free-at cycles, first invalid way else the
// smallest LRU stamp), driving its own MemorySystem.
class ReferenceCache {
 public:
  ReferenceCache(const CacheConfig& cfg, uint32_t line_bytes, uint32_t tiles, uint64_t base, MemorySystem& mem,
                 bool fast_clear)
      : cfg_(cfg), line_bytes_(line_bytes), base_(base), mem_(mem), fast_clear_(fast_clear), touched_(tiles, false) {
    const uint64_t lines = cfg.size_bytes / line_bytes;
    ways_ = uint32_t(std::min<uint64_t>(cfg.ways, lines));
    sets_ = uint32_t(lines / ways_);
    lines_.assign(size_t(sets_) * ways_, Line{});
    queue_.assign(cfg.miss_queue, 0);
  }

  Cycle acquire(Cycle now, uint32_t tile, bool write) {
    Line* set = &lines_[size_t(tile % sets_) * ways_];
    for (uint32_t w = 0; w < ways_; ++w) {
      Line& l = set[w];
      if (!l.valid || l.tile != tile) continue;
      ++stats.accesses;
      ++stats.hits;
      l.used = ++clock_;
      if (write) l.dirty = touched_[tile] = true;
      if (l.ready > now + cfg_.hit_latency) {
        ++stats.hits_under_miss;
        return l.ready;
      }
      return now + cfg_.hit_latency;
    }
    int free_entry = -1;
    uint32_t busy = 0;
    for (size_t i = 0; i < queue_.size(); ++i) {
      if (queue_[i] > now)
        ++busy;
      else if (free_entry < 0)
        free_entry = int(i);
    }
    if (free_entry < 0) {
      ++stats.miss_queue_full;
      return kNever;
    }
    ++stats.accesses;
    ++stats.misses;
    Line* victim = nullptr;
    for (uint32_t w = 0; w < ways_ && !victim; ++w)
      if (!set[w].valid) victim = &set[w];
    if (!victim) {
      victim = &set[0];
      for (uint32_t w = 1; w < ways_; ++w)
        if (set[w].used < victim->used) victim = &set[w];
    }
    Cycle ready = now + cfg_.hit_latency;
    if (victim->valid) {
      ++stats.evictions;
      if (victim->dirty) {
        ++stats.writebacks;
        ready = std::max(ready, mem_.access(now, base_ + uint64_t(victim->tile) * line_bytes_, line_bytes_, true,
                                            Surface::BlendArrays));
      }
    }
    if (fast_clear_ && !touched_[tile])
      ++stats.clear_fills;
    else
      ready = std::max(ready, mem_.access(now, base_ + uint64_t(tile) * line_bytes_, line_bytes_, false,
                                          Surface::BlendArrays));
    *victim = Line{true, tile, write, ++clock_, ready};
    if (write) touched_[tile] = true;
    queue_[size_t(free_entry)] = ready;
    stats.peak_misses_in_flight = std::max(stats.peak_misses_in_flight, busy + (ready > now ? 1u : 0u));
    return ready;
  }
  bool resident(uint32_t tile) const {
    const Line* set = &lines_[size_t(tile % sets_) * ways_];
    for (uint32_t w = 0; w < ways_; ++w)
      if (set[w].valid && set[w].tile == tile) return true;
    return false;
  }
  uint32_t inFlight(Cycle now) const {
    return uint32_t(std::count_if(queue_.begin(), queue_.end(), [now](Cycle c) { return c > now; }));
  }

  CacheStats stats;

 private:
  struct Line {
    bool valid = false;
    uint32_t tile = 0;
    bool dirty = false;
    uint64_t used = 0;
    Cycle ready = 0;
  };
  CacheConfig cfg_;
  uint32_t line_bytes_, ways_, sets_;
  uint64_t base_;
  MemorySystem& mem_;
  bool fast_clear_;
  std::vector<bool> touched_;
  std::vector<Line> lines_;
  std::vector<Cycle> queue_;
  uint64_t clock_ = 0;
};

// Seeded random acquire streams (repeated tiles, a working set larger than the
// cache, reads and writes, time mostly forward but sometimes back, retries
// after refusals) over power-of-two and odd geometries: every returned cycle,
// every stats field, the DRAM traffic, residency and the miss queue equal the
// reference's.
TEST(BlendArrayCache, MatchesReferenceOnRandomStreams) {
  struct Shape {
    uint32_t lines;
    unsigned ways, miss_queue, hit_latency;
    uint32_t tiles;
  };
  const Shape shapes[] = {
      {64, 8, 16, 10, 512},  // igpu-like: 8 sets of 8
      {24, 8, 5, 3, 200},    // 3 sets
      {10, 4, 2, 10, 64},    // 2 sets, 2 lines dropped
      {3, 8, 1, 1, 16},      // one fully associative set of 3, one miss entry
      {1, 1, 3, 0, 8},       // one line, zero hit latency
      {7, 1, 4, 80, 100},    // direct mapped, 7 sets
      {32, 16, 32, 80, 4000} // dgpu-like
  };
  testutil::TestLcg rnd{12345, 21};
  int cases = 0;
  for (const Shape& sh : shapes) {
    for (bool fast_clear : {false, true}) {
      DramConfig d = roundDram(1 + cases % 3);
      MemorySystem mem(d, kMhz), ref_mem(d, kMhz);
      DramPort port(mem);
      const CacheConfig cfg = cacheOf(sh.lines, sh.ways, sh.miss_queue, sh.hit_latency);
      const uint64_t base = uint64_t(cases) << 20;
      BlendArrayCache cache(cfg, oneLine(), sh.tiles, base, port, fast_clear);
      ReferenceCache ref(cfg, kLine, sh.tiles, base, ref_mem, fast_clear);
      const std::string what = std::to_string(sh.lines) + " lines " + std::to_string(sh.ways) + " ways mq " +
                               std::to_string(sh.miss_queue) + (fast_clear ? " fast clear" : "");
      Cycle now = 0;
      uint32_t tile = 0;
      uint64_t refused = 0;
      for (int i = 0; i < 20000; ++i) {
        const uint64_t r = rnd(16);
        if (r < 8) {
          // same tile again
        } else if (r < 12) {
          tile = uint32_t(rnd(std::min<uint32_t>(sh.tiles, sh.lines * 2)));  // a hot working set
        } else {
          tile = uint32_t(rnd(sh.tiles));
        }
        const bool write = rnd(3) != 0;
        const Cycle at = rnd(50) == 0 ? now - std::min<Cycle>(now, rnd(300)) : now;
        const Cycle want = ref.acquire(at, tile, write);
        ASSERT_EQ(use(cache, at, tile, write), want) << what << ", acquire " << i;
        refused += want == kNever;
        now += rnd(3);
        if (rnd(64) == 0) now += rnd(500);
      }
      const CacheStats& a = cache.stats();
      const CacheStats& b = ref.stats;
      EXPECT_EQ(a.accesses, b.accesses) << what;
      EXPECT_EQ(a.hits, b.hits) << what;
      EXPECT_EQ(a.misses, b.misses) << what;
      EXPECT_EQ(a.clear_fills, b.clear_fills) << what;
      EXPECT_EQ(a.evictions, b.evictions) << what;
      EXPECT_EQ(a.writebacks, b.writebacks) << what;
      EXPECT_EQ(a.miss_queue_full, b.miss_queue_full) << what;
      EXPECT_EQ(a.peak_misses_in_flight, b.peak_misses_in_flight) << what;
      EXPECT_EQ(a.hits_under_miss, b.hits_under_miss) << what;
      EXPECT_EQ(mem.stats().readBytes(), ref_mem.stats().readBytes()) << what;
      EXPECT_EQ(mem.stats().writeBytes(), ref_mem.stats().writeBytes()) << what;
      EXPECT_EQ(mem.stats().last_completion, ref_mem.stats().last_completion) << what;
      for (uint32_t t = 0; t < sh.tiles; ++t) ASSERT_EQ(cache.resident(t), ref.resident(t)) << what << " tile " << t;
      for (Cycle c : {Cycle(0), now / 2, now, now + 100, now + 1000})
        EXPECT_EQ(cache.missesInFlight(c), ref.inFlight(c)) << what;
      // The streams do reach the cases that matter.
      EXPECT_EQ(refused, a.miss_queue_full) << what;
      EXPECT_GT(a.hits, 0u) << what;
      EXPECT_GT(a.evictions, 0u) << what;
      EXPECT_GT(a.hits_under_miss, 0u) << what;
      if (sh.miss_queue <= 5) {
        EXPECT_GT(a.miss_queue_full, 0u) << what;
      }
      ++cases;
    }
  }
  EXPECT_EQ(cases, 14);
}

}  // namespace blend_array_cache_reference_test
}  // namespace oit::rop
