// Blending-array tile cache: hit rates, victims, DRAM bytes and latencies
// computed by hand (policies in oit_rop/memory/MEMORY.md).
#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

#include "oit_rop/TestLcg.hpp"
#include "oit_rop/memory/BlendArrayCache.hpp"
#include "oit_rop/memory/DramSystem.hpp"

namespace oit::rop {
namespace {

constexpr uint32_t kLine = 256;  // bytes per tile line in these tests

// Whole-cycle DRAM: 1000 MHz core, tCK 1 ns, 16 B/cycle; controller 40,
// CL = tRCD = tRP = 11. A 256 B line is 16 bus cycles; an unloaded line read
// on a closed bank takes 40 + 11 + 11 + 16 = 78 cycles.
DramConfig roundDram(unsigned channels = 1) {
  DramConfig c;
  c.channels = channels;
  c.channel_gbps = 16.0;
  c.tck_ns = 1.0;
  c.cl = c.trcd = c.trp = 11;
  c.controller_ns = 40.0;
  return c;
}
constexpr double kMhz = 1000.0;

CacheConfig cacheOf(uint32_t lines, unsigned ways, unsigned miss_queue = 16, unsigned hit_latency = 10) {
  CacheConfig c;
  c.size_bytes = uint64_t(lines) * kLine;
  c.ways = ways;
  c.miss_queue = miss_queue;
  c.hit_latency = hit_latency;
  return c;
}

// Most tests use one line per tile (the old tile-sized lines): a tile's
// arrays are one line of `bytes`, read whole and, for a write, written whole.
TileLines oneLine(uint32_t bytes = kLine) { return {bytes, bytes, 1}; }
constexpr LineTouch kReadLine{0, 1, 0}, kWriteLine{0, 1, 1};
std::span<const LineTouch> whole(bool write) { return {write ? &kWriteLine : &kReadLine, 1}; }
Cycle acquire(BlendArrayCache& cache, Cycle now, uint32_t tile, bool write) {
  return cache.acquire(now, tile, whole(write));
}
bool release(BlendArrayCache& cache, uint32_t tile) { return cache.release(tile, whole(false)); }

// One access whose use ends at once (acquire, then release when accepted):
// for the tests of LRU, fills and the miss queue, where no line stays in use.
// (Lines in use are the subject of the LinesInUse tests below.)
Cycle use(BlendArrayCache& cache, Cycle now, uint32_t tile, bool write) {
  const Cycle t = acquire(cache, now, tile, write);
  if (t != kNever) release(cache, tile);
  return t;
}

// Acquire like a pipeline would: on kNever, retry one cycle later.
Cycle acquireRetrying(BlendArrayCache& cache, Cycle& now, uint32_t tile, bool write) {
  for (;;) {
    const Cycle t = use(cache, now, tile, write);
    if (t != kNever) return t;
    ++now;
  }
}

TEST(BlendArrayCache, Geometry) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache a(cacheOf(16, 4), oneLine(), 100, 0, port, false);
  EXPECT_EQ(a.lines(), 16u);
  EXPECT_EQ(a.sets(), 4u);
  EXPECT_EQ(a.ways(), 4u);
  EXPECT_EQ(a.lineBytes(), kLine);
  // Fewer lines than ways: one fully associative set.
  BlendArrayCache b(cacheOf(3, 8), oneLine(), 100, 0, port, false);
  EXPECT_EQ(b.lines(), 3u);
  EXPECT_EQ(b.sets(), 1u);
  // 10 lines, 4 ways: 2 full sets; the 2 lines left over are not modelled.
  BlendArrayCache c(cacheOf(10, 4), oneLine(), 100, 0, port, false);
  EXPECT_EQ(c.lines(), 8u);
  EXPECT_EQ(c.sets(), 2u);
  // Smaller than one line: refused (it was modelled as one line, larger than configured).
  CacheConfig tiny = cacheOf(1, 8);
  tiny.size_bytes = kLine / 2;
  EXPECT_THROW(BlendArrayCache(tiny, oneLine(), 100, 0, port, false), std::invalid_argument);
  tiny.size_bytes = kLine;
  BlendArrayCache d(tiny, oneLine(), 100, 0, port, false);
  EXPECT_EQ(d.lines(), 1u);
  EXPECT_EQ(d.lineAddress(3), 3u * kLine);
}

TEST(BlendArrayCache, HitLatencyAndMissLatency) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(16, 4), oneLine(), 64, 0, port, false);
  EXPECT_EQ(use(cache, 0, 0, false), 78u);         // fill from DRAM
  EXPECT_EQ(use(cache, 500, 0, false), 510u);      // hit: now + hit_latency
  EXPECT_TRUE(cache.resident(0));
  EXPECT_FALSE(cache.resident(1));
}

TEST(BlendArrayCache, DirtyVictimIsWrittenBackBeforeTheLineIsAvailable) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(1, 1), oneLine(), 64, 0, port, false);
  EXPECT_EQ(use(cache, 0, 0, true), 78u);
  // At 1000: the write-back of tile 0 is posted (the DRAM controller accepts
  // it at 1040 into its write queue, MEMORY.md) and the fill of tile 1 reads
  // first (row 0 open: 40 + CL 11 + 16 -> 1067).
  EXPECT_EQ(use(cache, 1000, 1, false), 1067u);
  EXPECT_EQ(mem.stats().write_bytes[unsigned(Surface::BlendArrays)], kLine);
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], 2 * kLine);
  EXPECT_EQ(cache.stats().evictions, 1u);
  EXPECT_EQ(cache.stats().writebacks, 1u);
}

TEST(BlendArrayCache, StreamingHitRateIsRMinusOneOverR) {
  // 64 tiles through 8 lines: each tile accessed r times in a row -> one
  // compulsory miss then r - 1 hits (hits under the fill count as hits).
  for (unsigned r : {1u, 2u, 3u, 4u, 8u}) {
    MemorySystem mem(roundDram(), kMhz);
    DramPort port(mem);
    BlendArrayCache cache(cacheOf(8, 2), oneLine(), 64, 0, port, false);
    Cycle now = 0;
    for (uint32_t t = 0; t < 64; ++t)
      for (unsigned i = 0; i < r; ++i, ++now) acquireRetrying(cache, now, t, false);
    const CacheStats& s = cache.stats();
    EXPECT_EQ(s.accesses, 64u * r) << "r=" << r;
    EXPECT_EQ(s.misses, 64u) << "r=" << r;
    EXPECT_EQ(s.hits, 64u * (r - 1)) << "r=" << r;
    EXPECT_DOUBLE_EQ(s.hitRate(), double(r - 1) / double(r)) << "r=" << r;
    EXPECT_EQ(s.evictions, 64u - 8u);
    EXPECT_EQ(s.writebacks, 0u);  // read only
    // Without fast clear every first touch reads one line.
    EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], 64u * kLine);
    EXPECT_EQ(mem.stats().writeBytes(), 0u);
  }
}

TEST(BlendArrayCache, CyclicSweepLargerThanCacheNeverHitsUnderLru) {
  // LRU's worst case: 2 sweeps over 2x capacity, every access misses.
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(8, 2), oneLine(), 64, 0, port, false);
  Cycle now = 0;
  for (int sweep = 0; sweep < 2; ++sweep)
    for (uint32_t t = 0; t < 16; ++t, ++now) acquireRetrying(cache, now, t, false);
  EXPECT_EQ(cache.stats().hits, 0u);
  EXPECT_EQ(cache.stats().misses, 32u);
}

TEST(BlendArrayCache, ArraysThatFitMissOnlyOnce) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(16, 4), oneLine(), 64, 0, port, false);
  Cycle now = 0;
  for (uint32_t t = 0; t < 16; ++t, ++now) acquireRetrying(cache, now, t, false);
  EXPECT_EQ(cache.stats().misses, 16u);
  EXPECT_EQ(cache.stats().hits, 0u);
  now += 1000;
  for (uint32_t t = 0; t < 16; ++t, ++now) EXPECT_EQ(use(cache, now, t, false), now + 10) << t;
  EXPECT_EQ(cache.stats().misses, 16u);
  EXPECT_EQ(cache.stats().hits, 16u);
  EXPECT_EQ(cache.stats().evictions, 0u);
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], 16u * kLine);
}

TEST(BlendArrayCache, LruVictimInATwoWaySet) {
  // 4 lines, 2 ways -> 2 sets; even tiles share set 0.
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(4, 2), oneLine(), 64, 0, port, true);
  use(cache, 0, 1, false);  // set 1, must stay untouched by set 0's traffic
  use(cache, 1, 0, false);
  use(cache, 2, 2, false);
  use(cache, 3, 0, false);  // hit: 0 becomes most recent, 2 is LRU
  use(cache, 4, 4, false);  // evicts 2
  EXPECT_TRUE(cache.resident(0));
  EXPECT_FALSE(cache.resident(2));
  EXPECT_TRUE(cache.resident(4));
  use(cache, 5, 2, false);  // now 0 (used at 3) is older than 4 (used at 4)
  EXPECT_FALSE(cache.resident(0));
  EXPECT_TRUE(cache.resident(2));
  EXPECT_TRUE(cache.resident(4));
  EXPECT_TRUE(cache.resident(1));
  EXPECT_EQ(cache.stats().evictions, 2u);
  EXPECT_EQ(cache.stats().hits, 1u);
}

TEST(BlendArrayCache, LruInAFullyAssociativeCache) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(3, 8), oneLine(), 64, 0, port, true);  // 3 lines, 1 set
  for (uint32_t t : {0u, 1u, 2u, 0u}) use(cache, t, t, false);
  use(cache, 10, 3, false);  // LRU is 1
  EXPECT_FALSE(cache.resident(1));
  EXPECT_TRUE(cache.resident(0));
  EXPECT_TRUE(cache.resident(2));
  EXPECT_TRUE(cache.resident(3));
}

TEST(BlendArrayCache, DirtyEvictionsWriteExactlyTheirLines) {
  // 4 lines, 2 ways. Writing tiles 0..7 evicts dirty 0..3; reading 8..15 then
  // evicts dirty 4..7 and clean 8..11: 12 evictions, 8 write-backs.
  for (bool fast_clear : {false, true}) {
    MemorySystem mem(roundDram(), kMhz);
    DramPort port(mem);
    BlendArrayCache cache(cacheOf(4, 2), oneLine(), 64, 0, port, fast_clear);
    Cycle now = 0;
    for (uint32_t t = 0; t < 8; ++t, ++now) acquireRetrying(cache, now, t, true);
    for (uint32_t t = 8; t < 16; ++t, ++now) acquireRetrying(cache, now, t, false);
    EXPECT_EQ(cache.stats().evictions, 12u);
    EXPECT_EQ(cache.stats().writebacks, 8u);
    EXPECT_EQ(mem.stats().write_bytes[unsigned(Surface::BlendArrays)], 8u * kLine);
    // Every tile was first touched once: fills read 16 lines, or none with fast clear.
    EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], fast_clear ? 0u : 16u * kLine);
    EXPECT_EQ(cache.stats().clear_fills, fast_clear ? 16u : 0u);
    for (uint32_t t = 0; t < 16; ++t) EXPECT_EQ(cache.touched(t), t < 8) << t;
  }
}

TEST(BlendArrayCache, WriteBackGoesToTheVictimsAddress) {
  // 2 channels interleaved by one line: tile t's line sits on channel
  // (base / 256 + t) % 2, so the busy channel reveals the written address.
  for (uint64_t base : {uint64_t(0), uint64_t(kLine)}) {
    DramConfig d = roundDram(2);
    d.interleave_bytes = kLine;
    MemorySystem mem(d, kMhz);
    DramPort port(mem);
    BlendArrayCache cache(cacheOf(1, 1), oneLine(), 64, base, port, true);
    use(cache, 0, 1, true);   // clear fill, dirty
    use(cache, 10, 2, false); // clear fill; evicts dirty tile 1 -> write base + 256
    mem.drainWrites(100);     // the posted write-back reaches the bus
    const unsigned ch = unsigned((base / kLine + 1) % 2);
    EXPECT_EQ(mem.stats().channel_busy[ch], 16u) << base;
    EXPECT_EQ(mem.stats().channel_busy[1 - ch], 0u) << base;
    EXPECT_EQ(mem.stats().readBytes(), 0u);
  }
}

TEST(BlendArrayCache, FastClearFirstTouchNeedsNoDramRead) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(4, 2), oneLine(), 64, 0, port, true);
  for (uint32_t t = 0; t < 4; ++t) EXPECT_EQ(use(cache, 100 + t, t, t % 2 == 0), 110u + t);
  EXPECT_EQ(mem.stats().readBytes(), 0u);
  EXPECT_EQ(cache.stats().clear_fills, 4u);
  EXPECT_EQ(cache.stats().misses, 4u);
  // Tile 0 was written: after eviction its next miss must read it back.
  // Set 0 holds 0 and 2; 4 evicts 0 (LRU, dirty), 6 evicts 2 (dirty).
  use(cache, 200, 4, false);
  use(cache, 201, 6, false);
  EXPECT_FALSE(cache.resident(0));
  EXPECT_EQ(mem.stats().write_bytes[unsigned(Surface::BlendArrays)], 2u * kLine);
  const Cycle t = use(cache, 1000, 0, false);  // evicts clean 4
  EXPECT_GT(t, 1000u + 40u);  // a real DRAM fill, not a clear one
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], kLine);
  EXPECT_EQ(cache.stats().clear_fills, 6u);
}

TEST(BlendArrayCache, WithoutFastClearFirstTouchReadsALine) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(16, 4), oneLine(), 64, 0, port, false);
  Cycle now = 0;
  for (uint32_t t = 0; t < 10; ++t, ++now) acquireRetrying(cache, now, t, true);
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], 10u * kLine);
  EXPECT_EQ(cache.stats().clear_fills, 0u);
}

TEST(BlendArrayCache, MissQueueFullRefusesAndCounts) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(16, 4, /*miss_queue=*/2), oneLine(), 64, 0, port, false);
  EXPECT_EQ(use(cache, 0, 0, false), 78u);
  EXPECT_EQ(use(cache, 0, 1, false), 94u);  // same row, queued 16 cycles behind on the bus
  EXPECT_EQ(cache.missesInFlight(0), 2u);
  EXPECT_EQ(use(cache, 0, 2, false), kNever);
  EXPECT_EQ(use(cache, 77, 2, false), kNever);
  EXPECT_EQ(cache.stats().miss_queue_full, 2u);
  EXPECT_EQ(cache.stats().accesses, 2u);  // refusals are not accesses
  EXPECT_FALSE(cache.resident(2));
  // A hit still goes through while the queue is full (it waits for its fill).
  EXPECT_EQ(use(cache, 1, 0, false), 78u);
  // At 78 tile 0's fill has arrived: its entry is free again.
  EXPECT_EQ(use(cache, 78, 2, false), 145u);  // column at 118 + CL = 129, + 16
  EXPECT_EQ(cache.stats().misses, 3u);
  EXPECT_EQ(cache.stats().peak_misses_in_flight, 2u);
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], 3u * kLine);
}

TEST(BlendArrayCache, HitUnderMissWaitsForTheFillAndCountsAsHit) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(16, 4), oneLine(), 16, 0, port, false);
  EXPECT_EQ(use(cache, 0, 5, false), 78u);
  EXPECT_EQ(use(cache, 1, 5, true), 78u);
  EXPECT_EQ(use(cache, 70, 5, false), 80u);  // fill done by then + hit latency
  EXPECT_EQ(cache.stats().hits, 2u);
  EXPECT_EQ(cache.stats().hits_under_miss, 1u);
  EXPECT_EQ(cache.stats().misses, 1u);
  EXPECT_TRUE(cache.touched(5));  // the write under the miss marks it
  EXPECT_EQ(mem.stats().readBytes(), kLine);  // no second fill
}

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

// Victim choice pinned by hand: the first invalid way even when a valid way is
// older, then the least recently used; hits refresh the LRU order.
TEST(BlendArrayCache, FirstInvalidWayThenLeastRecentlyUsed) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(4, 4), oneLine(), 16, 0, port, true);  // one set of 4 ways
  use(cache, 0, 0, false);
  use(cache, 1, 1, false);
  use(cache, 2, 0, false);  // hit
  use(cache, 3, 2, false);
  use(cache, 4, 3, false);  // fills the last invalid way: no eviction yet
  EXPECT_EQ(cache.stats().evictions, 0u);
  use(cache, 5, 4, false);  // LRU is 1 (used at 1; 0 was used again at 2)
  EXPECT_FALSE(cache.resident(1));
  use(cache, 6, 2, false);  // hit: now 0 is LRU
  use(cache, 7, 5, false);
  EXPECT_FALSE(cache.resident(0));
  for (uint32_t t : {2u, 3u, 4u, 5u}) EXPECT_TRUE(cache.resident(t)) << t;
  EXPECT_EQ(cache.stats().evictions, 2u);
  EXPECT_EQ(cache.stats().hits, 2u);
}

// The miss queue frees entries by time, not by order, and the peak counts the
// entries busy right after an accepted miss, including when `now` goes back.
TEST(BlendArrayCache, MissQueueEntriesFreeByTimeAndPeakCountsBusyOnes) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(16, 4, /*miss_queue=*/3), oneLine(), 64, 0, port, true);
  // Fast clear: fills are ready at now + 10.
  EXPECT_EQ(use(cache, 100, 0, false), 110u);
  EXPECT_EQ(use(cache, 100, 1, false), 110u);
  EXPECT_EQ(use(cache, 105, 2, false), 115u);
  EXPECT_EQ(cache.stats().peak_misses_in_flight, 3u);
  EXPECT_EQ(use(cache, 109, 3, false), kNever);
  EXPECT_EQ(cache.missesInFlight(109), 3u);
  EXPECT_EQ(cache.missesInFlight(110), 1u);
  // At 110 entries 0 and 1 are free: entry 0 takes the new miss (ready 120).
  EXPECT_EQ(use(cache, 110, 3, false), 120u);
  EXPECT_EQ(cache.missesInFlight(110), 2u);
  // Back in time to 108: entry 1 (110) and entry 2 (115) are busy, entry 0 (120)
  // too: refused.
  EXPECT_EQ(use(cache, 108, 4, false), kNever);
  EXPECT_EQ(use(cache, 116, 4, false), 126u);  // entries 1 and 2 free: entry 1
  EXPECT_EQ(cache.missesInFlight(116), 2u);        // 120 and 126
  EXPECT_EQ(cache.missesInFlight(111), 3u);        // 115 (entry 2) as well
  EXPECT_EQ(cache.stats().miss_queue_full, 2u);
  EXPECT_EQ(cache.stats().peak_misses_in_flight, 3u);
}

TEST(BlendArrayCache, RejectsBadInput) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(4, 2), oneLine(), 8, 0, port, true);
  EXPECT_THROW(use(cache, 0, 8, false), std::out_of_range);
  EXPECT_THROW(BlendArrayCache(cacheOf(4, 2, 0), oneLine(), 8, 0, port, true), std::invalid_argument);
  EXPECT_THROW(BlendArrayCache(cacheOf(4, 2), oneLine(0), 8, 0, port, true), std::invalid_argument);
}

TEST(BlendArrayCache, Deterministic) {
  struct Result {
    uint64_t sum, hits, misses, writebacks, full, dram_read, dram_write;
    bool operator==(const Result&) const = default;
  };
  auto run = [] {
    MemorySystem mem(DramConfig{}, 1150.0);
    DramPort port(mem);
    CacheConfig c;  // igpu defaults: 128 KiB, 8 ways, 16-entry miss queue
    BlendArrayCache cache(c, oneLine(2048), 14400, 1 << 24, port, true);
    uint64_t x = 99, sum = 0;
    Cycle now = 0;
    for (int i = 0; i < 50000; ++i) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      const uint32_t tile = uint32_t((x >> 33) % 512);  // 512 tiles vs 64 lines
      const Cycle t = use(cache, now, tile, (x >> 3) & 1);
      sum = sum * 1315423911u + t;
      now += (t == kNever) ? 7 : 1;
    }
    const CacheStats& s = cache.stats();
    return Result{sum, s.hits, s.misses, s.writebacks, s.miss_queue_full, mem.stats().readBytes(),
                  mem.stats().writeBytes()};
  };
  const Result a = run(), b = run();
  EXPECT_EQ(a, b);
  EXPECT_GT(a.full, 0u);  // the pattern does exercise the miss queue
  EXPECT_GT(a.writebacks, 0u);
}


// An exactly fitting cache (128 KiB of 2 KiB lines: 64 lines, 8 ways, 8 sets)
// over a 64x64 frame of 8x8 tiles (64 tiles) in raster order, two layers: every
// tile misses once (set = tile % 8 = tile column; 8 tiles per set), the
// second layer hits everywhere.
TEST(BlendArrayCache, ExactlyFittingCacheMissesEachTileOnceInRasterOrder) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  CacheConfig cfg = cacheOf(1, 8);
  cfg.size_bytes = 128 * 1024;
  BlendArrayCache cache(cfg, oneLine(2048), 64, 0, port, false);
  ASSERT_EQ(cache.lines(), 64u);
  ASSERT_EQ(cache.sets(), 8u);
  Cycle now = 0;
  for (int layer = 0; layer < 2; ++layer)
    for (uint32_t y = 0; y < 64; ++y)
      for (uint32_t x = 0; x < 64; ++x, ++now) acquireRetrying(cache, now, (y / 8) * 8 + x / 8, true);
  EXPECT_EQ(cache.stats().misses, 64u);
  EXPECT_EQ(cache.stats().hits, 2u * 64 * 64 - 64);
  EXPECT_EQ(cache.stats().evictions, 0u);
}


// A line in use (acquired, release() not yet called: its fill is in flight or
// its blend has not written it) is never a victim. Audit: the victim used to be
// the plain LRU line, so a 2-line cache had 16 fills in flight and fragments
// blended into lines already written back.
TEST(BlendArrayCache, LinesInUseAreNeverVictims) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(2, 2), oneLine(), 8, 0, port, false);  // one set of 2 ways
  const Cycle r0 = acquire(cache, 0, 0, true);
  const Cycle r1 = acquire(cache, 1, 1, true);
  ASSERT_NE(r0, kNever);
  ASSERT_NE(r1, kNever);
  EXPECT_EQ(cache.linesInUse(), 2u);
  // Both ways in use: tile 2 is refused (not counted as an access) and the
  // refusal says the set, not the miss queue, is why.
  EXPECT_EQ(acquire(cache, 2, 2, true), kNever);
  EXPECT_TRUE(cache.refusedBySet());
  EXPECT_EQ(cache.stats().set_in_use, 1u);
  EXPECT_EQ(cache.stats().accesses, 2u);
  EXPECT_TRUE(cache.resident(0));
  EXPECT_TRUE(cache.resident(1));
  // A hit on a line in use is fine (no victim needed) and pins it once more.
  EXPECT_NE(acquire(cache, 3, 1, false), kNever);
  // Releasing tile 1 once leaves it in use (two acquires); the second release
  // frees it, which the refused set is told about.
  EXPECT_FALSE(release(cache, 1));
  EXPECT_TRUE(release(cache, 1));
  EXPECT_EQ(cache.linesInUse(), 1u);
  const Cycle r2 = acquire(cache, r1 + 1, 2, true);
  ASSERT_NE(r2, kNever);
  EXPECT_FALSE(cache.resident(1));  // the line out of use went, though 0 is older
  EXPECT_TRUE(cache.resident(0));
  EXPECT_EQ(cache.stats().evictions, 1u);
  EXPECT_EQ(cache.stats().writebacks, 1u);
  // Releasing a tile with no acquire in use is a caller bug.
  EXPECT_THROW(release(cache, 1), std::logic_error);
  EXPECT_THROW(release(cache, 5), std::logic_error);
}

// touch() is acquire() and release() in one call (the approximate engine):
// on a random stream with a small miss queue it returns the same cycles and
// counts the same as the pair, and leaves no line in use.
TEST(BlendArrayCache, TouchIsAcquireThenRelease) {
  MemorySystem mem_a(roundDram(), kMhz), mem_b(roundDram(), kMhz);
  DramPort port_a(mem_a), port_b(mem_b);
  BlendArrayCache a(cacheOf(8, 2, 2), oneLine(), 64, 0, port_a, false), b(cacheOf(8, 2, 2), oneLine(), 64, 0, port_b, false);
  testutil::TestLcg rng{99, 33};
  Cycle now = 0;
  uint64_t refused = 0;
  for (int i = 0; i < 5000; ++i) {
    now += rng(4);
    const uint32_t tile = uint32_t(rng(24));
    const bool write = rng(2) != 0;
    bool missed;
    const Cycle ta = use(a, now, tile, write), tb = b.touch(now, tile, whole(write), missed);
    ASSERT_EQ(ta, tb) << "access " << i;
    refused += ta == kNever;
    ASSERT_EQ(b.linesInUse(), 0u);
  }
  EXPECT_GT(refused, 0u);  // the two-entry miss queue did refuse (the stream is not too easy)
  EXPECT_TRUE(a.stats() == b.stats());  // every count and peak
  EXPECT_GT(a.stats().hits, 0u);
  EXPECT_GT(a.stats().misses, 0u);
  EXPECT_GT(a.stats().hits_under_miss, 0u);
  EXPECT_EQ(b.stats().set_in_use, 0u);  // nothing pinned: a set is never all in use
}

// Fills in flight never exceed the cache's lines, however long the miss queue.
TEST(BlendArrayCache, MissesInFlightNeverExceedTheLines) {
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  BlendArrayCache cache(cacheOf(2, 2, 64), oneLine(), 64, 0, port, false);
  std::vector<std::pair<Cycle, uint32_t>> pending;  // (ready, tile) of accepted acquires
  Cycle now = 0;
  for (uint32_t i = 0; i < 60; ++now) {
    // Uses end 5 cycles after the line arrived (the blend), oldest first.
    while (!pending.empty() && pending.front().first + 5 <= now) {
      release(cache, pending.front().second);
      pending.erase(pending.begin());
    }
    const uint32_t tile = i % 6;
    const Cycle r = acquire(cache, now, tile, true);
    if (r == kNever) continue;
    pending.push_back({r, tile});
    ++i;
    EXPECT_LE(cache.missesInFlight(now), 2u) << now;
  }
  EXPECT_LE(cache.stats().peak_misses_in_flight, 2u);
  EXPECT_GT(cache.stats().set_in_use, 0u);
  EXPECT_EQ(cache.stats().accesses, 60u);
}
// The set comes from set_index when given (a partition's own tile numbers):
// tiles 1, 3, 5, 7 in a 2-set, 2-way cache all map to set 1 by the tile number
// (4 tiles in 2 ways: a cyclic sweep always misses) and to sets 0, 1, 0, 1 by
// the index tile / 2 (they fit: 4 compulsory misses).
TEST(BlendArrayCache, SetIndexChoosesTheSet) {
  for (bool local : {false, true}) {
    MemorySystem mem(roundDram(), kMhz);
    DramPort port(mem);
    std::vector<uint32_t> index;
    if (local)
      for (uint32_t t = 0; t < 8; ++t) index.push_back(t / 2);
    BlendArrayCache cache(cacheOf(4, 2), oneLine(), 8, 0, port, false, index);
    ASSERT_EQ(cache.sets(), 2u);
    Cycle now = 0;
    for (int sweep = 0; sweep < 3; ++sweep)
      for (uint32_t t : {1u, 3u, 5u, 7u}) now = acquireRetrying(cache, now, t, true) + 1;
    EXPECT_EQ(cache.stats().misses, local ? 4u : 12u) << local;
  }
  MemorySystem mem(roundDram(), kMhz);
  DramPort port(mem);
  EXPECT_THROW(BlendArrayCache(cacheOf(4, 2), oneLine(), 8, 0, port, false, {0, 1}), std::invalid_argument);
}

// ---- Lines apart from tiles: several lines per tile, sectors ----------------

// Tiles of 4 lines of 128 B, sectors of 32 B (4 per line): a DRAM that
// records every request.
struct Recorder : MemoryPort {
  struct Req {
    uint64_t addr;
    uint32_t bytes;
    bool write;
  };
  std::vector<Req> reqs;
  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface) override {
    reqs.push_back({addr, bytes, write});
    return now + 50;
  }
};
constexpr TileLines kSectored{128, 32, 4};

CacheConfig sectoredCache(uint32_t lines, unsigned ways, unsigned miss_queue = 16) {
  CacheConfig c;
  c.size_bytes = uint64_t(lines) * 128;
  c.ways = ways;
  c.miss_queue = miss_queue;
  c.hit_latency = 10;
  return c;
}

TEST(BlendArrayCacheLines, AMissFillsOnlyTheSectorsItReadsAndWritesBackOnlyDirtyOnes) {
  Recorder below;
  BlendArrayCache cache(sectoredCache(8, 2), kSectored, 16, 0, below, false);
  // Tile 1, line 2 (address (1 x 4 + 2) x 128 = 768): read sector 1, write sectors 1 and 2 (2 wholly).
  const LineTouch t{2, 0b0010, 0b0110};
  EXPECT_EQ(cache.acquire(0, 1, std::span(&t, 1)), 50u);  // one 32 B fill at 768 + 32
  ASSERT_EQ(below.reqs.size(), 1u);
  EXPECT_EQ(below.reqs[0].addr, 800u);
  EXPECT_EQ(below.reqs[0].bytes, 32u);
  cache.release(1, std::span(&t, 1));
  EXPECT_EQ(cache.writtenSectors(1, 2), 0b0110u);
  EXPECT_EQ(cache.writtenBytes(), 64u);
  // Sector 3 is not held: a sector miss, another 32 B fill.
  const LineTouch u{2, 0b1000, 0};
  EXPECT_EQ(cache.acquire(100, 1, std::span(&u, 1)), 150u);
  cache.release(1, std::span(&u, 1));
  EXPECT_EQ(cache.stats().sector_misses, 1u);
  EXPECT_EQ(cache.stats().misses, 2u);
  // The dirty sectors 1 and 2 leave as one 64 B write when the line is evicted:
  // it is line 6 (tile 1 x 4 + 2), set 6 mod 4 = 2, which tiles 2 and 3's
  // line 2 (lines 10 and 14) share; the second of them evicts it (LRU).
  const LineTouch r{2, 0b0001, 0};
  for (uint32_t tile : {2u, 3u}) {
    ASSERT_NE(cache.acquire(200 + tile, tile, std::span(&r, 1)), kNever);
    cache.release(tile, std::span(&r, 1));
  }
  std::vector<Recorder::Req> writes;
  for (const auto& q : below.reqs)
    if (q.write) writes.push_back(q);
  ASSERT_EQ(writes.size(), 1u);
  EXPECT_EQ(writes[0].addr, 800u);
  EXPECT_EQ(writes[0].bytes, 64u);
  EXPECT_EQ(cache.stats().writeback_bytes, 64u);
}

TEST(BlendArrayCacheLines, FastClearIsPerSector) {
  Recorder below;
  BlendArrayCache cache(sectoredCache(4, 1), kSectored, 16, 0, below, true);  // direct mapped, 4 sets
  const LineTouch w{0, 0b0001, 0b0001};  // tile 0 line 0: read-modify-write sector 0
  EXPECT_EQ(cache.acquire(0, 0, std::span(&w, 1)), 10u);  // never written: a clear fill
  cache.release(0, std::span(&w, 1));
  const LineTouch e{0, 0b0001, 0};
  EXPECT_NE(cache.acquire(20, 1, std::span(&e, 1)), kNever);  // tile 1's line 0 shares set 0: evicts it
  cache.release(1, std::span(&e, 1));
  ASSERT_EQ(below.reqs.size(), 1u);  // the write-back of sector 0
  // Back to tile 0: sector 1 was never written (clear, no read); sector 0 comes from below.
  const LineTouch s1{0, 0b0010, 0};
  EXPECT_EQ(cache.acquire(40, 0, std::span(&s1, 1)), 50u);
  cache.release(0, std::span(&s1, 1));
  EXPECT_EQ(below.reqs.size(), 1u);
  const LineTouch s0{0, 0b0001, 0};
  EXPECT_EQ(cache.acquire(60, 0, std::span(&s0, 1)), 110u);
  cache.release(0, std::span(&s0, 1));
  ASSERT_EQ(below.reqs.size(), 2u);
  EXPECT_FALSE(below.reqs[1].write);
  EXPECT_EQ(below.reqs[1].addr, 0u);
  EXPECT_EQ(below.reqs[1].bytes, 32u);
  EXPECT_EQ(cache.stats().clear_fills, 3u);  // the first fill, tile 1's, and sector 1's
}

TEST(BlendArrayCacheLines, ARefusedAccessWaitsForTheEntryThatFreesItsLastNeededOne) {
  // Three entries busy until 50, 55 and 70 (fills of 50 cycles from 0, 5 and
  // 20): an access of k missing lines is refused until the k-th earliest
  // frees, whatever order the entries were taken in, also for an access at an
  // earlier cycle than the last one (the approximate engine retries later).
  Recorder below;
  BlendArrayCache cache(sectoredCache(16, 4, /*miss_queue=*/3), kSectored, 16, 0, below, false);
  const LineTouch one{0, 0b1111, 0};
  const LineTouch line1{1, 0b1111, 0};
  const LineTouch two[2] = {{0, 0b1111, 0}, {1, 0b1111, 0}};
  const LineTouch three[3] = {{0, 0b1111, 0}, {1, 0b1111, 0}, {2, 0b1111, 0}};
  EXPECT_EQ(cache.acquire(20, 2, std::span(&one, 1)), 70u);
  EXPECT_EQ(cache.acquire(0, 0, std::span(&one, 1)), 50u);
  EXPECT_EQ(cache.acquire(5, 1, std::span(&one, 1)), 55u);
  EXPECT_EQ(cache.acquire(30, 3, two), kNever);  // no entry free: the second earliest
  EXPECT_EQ(cache.missQueueFreesAt(), 55u);
  EXPECT_EQ(cache.acquire(30, 3, std::span(&line1, 1)), kNever);  // the earliest
  EXPECT_EQ(cache.missQueueFreesAt(), 50u);
  EXPECT_EQ(cache.acquire(52, 3, two), kNever);  // one free (50), two needed
  EXPECT_EQ(cache.missQueueFreesAt(), 55u);
  EXPECT_EQ(cache.acquire(52, 3, std::span(&line1, 1)), 102u);  // takes the entry freed at 50: busy to 102
  EXPECT_EQ(cache.acquire(40, 4, std::span(&one, 1)), kNever);  // at 40 all busy (55, 70, 102)
  EXPECT_EQ(cache.missQueueFreesAt(), 55u);
  EXPECT_EQ(cache.acquire(60, 4, three), kNever);  // one free (55), three needed: the third earliest
  EXPECT_EQ(cache.missQueueFreesAt(), 102u);
  EXPECT_EQ(cache.stats().miss_queue_full, 5u);  // one per refused access
  EXPECT_EQ(cache.stats().misses, 4u);
  EXPECT_EQ(cache.missesInFlight(60), 2u);  // 70 and 102
}

TEST(BlendArrayCacheLines, AnAccessGetsAllItsLinesOrNone) {
  Recorder below;
  BlendArrayCache cache(sectoredCache(16, 4, /*miss_queue=*/3), kSectored, 16, 0, below, false);
  const LineTouch two[2] = {{0, 0b1111, 0}, {1, 0b1111, 0}};
  const LineTouch three[3] = {{0, 0b1111, 0}, {1, 0b1111, 0}, {2, 0b1111, 0}};
  // Two misses at 0 (entries busy until 50); a three-line access of another
  // tile needs three entries: refused until the second busy one frees, at 50.
  EXPECT_EQ(cache.acquire(0, 0, two), 50u);
  EXPECT_EQ(cache.acquire(1, 1, three), kNever);
  EXPECT_FALSE(cache.refusedBySet());
  EXPECT_EQ(cache.missQueueFreesAt(), 50u);
  EXPECT_EQ(cache.stats().accesses, 2u);  // nothing of the refused access counted
  EXPECT_FALSE(cache.resident(1, 0));
  EXPECT_EQ(cache.acquire(50, 1, three), 100u);
  EXPECT_EQ(cache.stats().misses, 5u);
  EXPECT_EQ(cache.linesInUse(), 5u);  // every line of both accesses is pinned
  // Tile 0's lines are resident: hitting both costs no entry.
  EXPECT_EQ(cache.acquire(60, 0, two), 70u);
  EXPECT_FALSE(cache.release(0, two));
  EXPECT_FALSE(cache.release(0, two));
  EXPECT_EQ(cache.linesInUse(), 3u);
}

TEST(BlendArrayCacheLines, AnAccessNeverEvictsItsOwnLines) {
  Recorder below;
  // One set of 2 ways, 1 line per tile of 128 B.
  BlendArrayCache cache(sectoredCache(2, 2), TileLines{128, 32, 2}, 8, 0, below, false);
  const LineTouch a{0, 0b0001, 0};
  ASSERT_NE(cache.acquire(0, 0, std::span(&a, 1)), kNever);  // tile 0 line 0 in way 0
  cache.release(0, std::span(&a, 1));
  // Tile 0, lines 0 (resident) and 1 (absent): the victim for line 1 must not
  // be line 0 of this very access: it takes the free way.
  const LineTouch both[2] = {{0, 0b0001, 0}, {1, 0b0001, 0}};
  ASSERT_NE(cache.acquire(10, 0, both), kNever);
  EXPECT_TRUE(cache.resident(0, 0));
  EXPECT_TRUE(cache.resident(0, 1));
  // Both pinned: tile 1's line 0 finds no way out of use.
  EXPECT_EQ(cache.acquire(20, 1, std::span(&a, 1)), kNever);
  EXPECT_TRUE(cache.refusedBySet());
  EXPECT_EQ(cache.stats().set_in_use, 1u);
  EXPECT_TRUE(cache.release(0, both));  // frees the refused set
}

TEST(BlendArrayCacheLines, MissesAreClassified) {
  Recorder below;
  // 2 lines direct mapped (2 sets of 1 way), one line per tile: tiles 0 and 2 share set 0.
  BlendArrayCache cache(sectoredCache(2, 1), TileLines{128, 128, 1}, 8, 0, below, false, {}, /*classify=*/true);
  Cycle now = 0;
  for (uint32_t t : {0u, 2u, 0u, 1u, 3u, 2u}) {
    const LineTouch r{0, 1, 0};
    ASSERT_NE(cache.acquire(now += 100, t, std::span(&r, 1)), kNever);
    cache.release(t, std::span(&r, 1));
  }
  // 0, 2: compulsory; 0: conflict (a 2-line fully associative cache still has
  // it); 1, 3: compulsory; 2: capacity (neither holds it).
  EXPECT_EQ(cache.stats().compulsory_misses, 4u);
  EXPECT_EQ(cache.stats().conflict_misses, 1u);
  EXPECT_EQ(cache.stats().capacity_misses, 1u);
  EXPECT_EQ(cache.stats().misses, 6u);
}

TEST(BlendArrayCacheLines, ASectorMissIsAConflictOnlyWhenTheFullyAssociativeCacheHoldsTheSector) {
  Recorder below;
  // 2 lines direct mapped (2 sets of 1 way), lines of 4 sectors, one line per tile.
  BlendArrayCache cache(sectoredCache(2, 1), TileLines{128, 32, 1}, 8, 0, below, false, {}, /*classify=*/true);
  Cycle now = 0;
  const auto touch = [&](uint32_t tile, uint32_t sectors) {
    const LineTouch r{0, sectors, 0};
    ASSERT_NE(cache.acquire(now += 100, tile, std::span(&r, 1)), kNever);
    cache.release(tile, std::span(&r, 1));
  };
  touch(0, 0b01);  // compulsory
  touch(1, 0b01);  // compulsory (set 1)
  touch(2, 0b01);  // compulsory: evicts tile 0 from set 0, and from the 2-line fully associative cache
  touch(0, 0b10);  // compulsory (sector 1 never held)
  // Tile 0 is back with sector 1 only, in both caches: sector 0 misses in
  // both (capacity), though the fully associative cache holds the line.
  touch(0, 0b01);
  EXPECT_EQ(cache.stats().compulsory_misses, 4u);
  EXPECT_EQ(cache.stats().capacity_misses, 1u);
  EXPECT_EQ(cache.stats().conflict_misses, 0u);
  // Tile 2 (sector 0) was evicted from set 0 but the fully associative cache
  // still holds it: a conflict.
  touch(2, 0b01);
  EXPECT_EQ(cache.stats().conflict_misses, 1u);
  EXPECT_EQ(cache.stats().misses, 6u);
}

TEST(BlendArrayCacheLines, StatsOfPartitionsAddUpAndThePeakIsTheLarger) {
  CacheStats a, b;
  a.accesses = 3, a.hits = 1, a.misses = 2, a.conflict_misses = 1, a.fill_bytes = 64, a.peak_misses_in_flight = 5;
  b.accesses = 4, b.hits = 4, b.hits_under_miss = 2, b.write_bytes = 32, b.peak_misses_in_flight = 2;
  a += b;
  EXPECT_EQ(a.accesses, 7u);
  EXPECT_EQ(a.hits, 5u);
  EXPECT_EQ(a.misses, 2u);
  EXPECT_EQ(a.conflict_misses, 1u);
  EXPECT_EQ(a.hits_under_miss, 2u);
  EXPECT_EQ(a.fill_bytes, 64u);
  EXPECT_EQ(a.write_bytes, 32u);
  EXPECT_EQ(a.peak_misses_in_flight, 5u);
}

TEST(BlendArrayCacheLines, DirtyRangesAtTheEndAreTheDirtySectors) {
  Recorder below;
  BlendArrayCache cache(sectoredCache(8, 2), kSectored, 16, 1 << 20, below, true);
  const LineTouch w{3, 0b1001, 0b1001};  // sectors 0 and 3: two runs
  ASSERT_NE(cache.acquire(0, 5, std::span(&w, 1)), kNever);
  std::vector<DirtyRange> d;
  cache.dirtyRanges(d);
  ASSERT_EQ(d.size(), 2u);
  const uint64_t line = (1 << 20) + (5 * 4 + 3) * 128;
  EXPECT_EQ(d[0].addr, line);
  EXPECT_EQ(d[0].bytes, 32u);
  EXPECT_EQ(d[1].addr, line + 96);
  EXPECT_TRUE(cache.touched(5));
  EXPECT_FALSE(cache.touched(4));
}

}  // namespace
}  // namespace oit::rop
