// Blending-array tile cache: hit rates, victims, DRAM bytes and latencies
// computed by hand (policies in oit_rop/MEMORY.md).
#include <gtest/gtest.h>

#include <stdexcept>
#include <vector>

#include "oit_rop/BlendArrayCache.hpp"

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

// Acquire like a pipeline would: on kNever, retry one cycle later.
Cycle acquireRetrying(BlendArrayCache& cache, Cycle& now, uint32_t tile, bool write) {
  for (;;) {
    const Cycle t = cache.acquire(now, tile, write);
    if (t != kNever) return t;
    ++now;
  }
}

TEST(BlendArrayCache, Geometry) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache a(cacheOf(16, 4), kLine, 100, 0, mem, false);
  EXPECT_EQ(a.lines(), 16u);
  EXPECT_EQ(a.sets(), 4u);
  EXPECT_EQ(a.ways(), 4u);
  EXPECT_EQ(a.lineBytes(), kLine);
  // Fewer lines than ways: one fully associative set.
  BlendArrayCache b(cacheOf(3, 8), kLine, 100, 0, mem, false);
  EXPECT_EQ(b.lines(), 3u);
  EXPECT_EQ(b.sets(), 1u);
  // 10 lines, 4 ways: 2 full sets; the 2 lines left over are not modelled.
  BlendArrayCache c(cacheOf(10, 4), kLine, 100, 0, mem, false);
  EXPECT_EQ(c.lines(), 8u);
  EXPECT_EQ(c.sets(), 2u);
  // Smaller than one line: still one line.
  CacheConfig tiny = cacheOf(1, 8);
  tiny.size_bytes = kLine / 2;
  BlendArrayCache d(tiny, kLine, 100, 0, mem, false);
  EXPECT_EQ(d.lines(), 1u);
  EXPECT_EQ(d.lineAddress(3), 3u * kLine);
}

TEST(BlendArrayCache, HitLatencyAndMissLatency) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(16, 4), kLine, 64, 0, mem, false);
  EXPECT_EQ(cache.acquire(0, 0, false), 78u);         // fill from DRAM
  EXPECT_EQ(cache.acquire(500, 0, false), 510u);      // hit: now + hit_latency
  EXPECT_TRUE(cache.resident(0));
  EXPECT_FALSE(cache.resident(1));
}

TEST(BlendArrayCache, DirtyVictimIsWrittenBackBeforeTheLineIsAvailable) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(1, 1), kLine, 64, 0, mem, false);
  EXPECT_EQ(cache.acquire(0, 0, true), 78u);
  // At 1000: write-back of tile 0 (row 0 open: 40 + CL 11 + 16 -> 1067), then
  // the fill of tile 1 (same row; its column read issues at 1040 but the bus
  // is booked until 1067) -> 1083.
  EXPECT_EQ(cache.acquire(1000, 1, false), 1083u);
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
    BlendArrayCache cache(cacheOf(8, 2), kLine, 64, 0, mem, false);
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
  BlendArrayCache cache(cacheOf(8, 2), kLine, 64, 0, mem, false);
  Cycle now = 0;
  for (int sweep = 0; sweep < 2; ++sweep)
    for (uint32_t t = 0; t < 16; ++t, ++now) acquireRetrying(cache, now, t, false);
  EXPECT_EQ(cache.stats().hits, 0u);
  EXPECT_EQ(cache.stats().misses, 32u);
}

TEST(BlendArrayCache, ArraysThatFitMissOnlyOnce) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(16, 4), kLine, 64, 0, mem, false);
  Cycle now = 0;
  for (uint32_t t = 0; t < 16; ++t, ++now) acquireRetrying(cache, now, t, false);
  EXPECT_EQ(cache.stats().misses, 16u);
  EXPECT_EQ(cache.stats().hits, 0u);
  now += 1000;
  for (uint32_t t = 0; t < 16; ++t, ++now) EXPECT_EQ(cache.acquire(now, t, false), now + 10) << t;
  EXPECT_EQ(cache.stats().misses, 16u);
  EXPECT_EQ(cache.stats().hits, 16u);
  EXPECT_EQ(cache.stats().evictions, 0u);
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], 16u * kLine);
}

TEST(BlendArrayCache, LruVictimInATwoWaySet) {
  // 4 lines, 2 ways -> 2 sets; even tiles share set 0.
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(4, 2), kLine, 64, 0, mem, true);
  cache.acquire(0, 1, false);  // set 1, must stay untouched by set 0's traffic
  cache.acquire(1, 0, false);
  cache.acquire(2, 2, false);
  cache.acquire(3, 0, false);  // hit: 0 becomes most recent, 2 is LRU
  cache.acquire(4, 4, false);  // evicts 2
  EXPECT_TRUE(cache.resident(0));
  EXPECT_FALSE(cache.resident(2));
  EXPECT_TRUE(cache.resident(4));
  cache.acquire(5, 2, false);  // now 0 (used at 3) is older than 4 (used at 4)
  EXPECT_FALSE(cache.resident(0));
  EXPECT_TRUE(cache.resident(2));
  EXPECT_TRUE(cache.resident(4));
  EXPECT_TRUE(cache.resident(1));
  EXPECT_EQ(cache.stats().evictions, 2u);
  EXPECT_EQ(cache.stats().hits, 1u);
}

TEST(BlendArrayCache, LruInAFullyAssociativeCache) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(3, 8), kLine, 64, 0, mem, true);  // 3 lines, 1 set
  for (uint32_t t : {0u, 1u, 2u, 0u}) cache.acquire(t, t, false);
  cache.acquire(10, 3, false);  // LRU is 1
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
    BlendArrayCache cache(cacheOf(4, 2), kLine, 64, 0, mem, fast_clear);
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
    BlendArrayCache cache(cacheOf(1, 1), kLine, 64, base, mem, true);
    cache.acquire(0, 1, true);   // clear fill, dirty
    cache.acquire(10, 2, false); // clear fill; evicts dirty tile 1 -> write base + 256
    const unsigned ch = unsigned((base / kLine + 1) % 2);
    EXPECT_EQ(mem.stats().channel_busy[ch], 16u) << base;
    EXPECT_EQ(mem.stats().channel_busy[1 - ch], 0u) << base;
    EXPECT_EQ(mem.stats().readBytes(), 0u);
  }
}

TEST(BlendArrayCache, FastClearFirstTouchNeedsNoDramRead) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(4, 2), kLine, 64, 0, mem, true);
  for (uint32_t t = 0; t < 4; ++t) EXPECT_EQ(cache.acquire(100 + t, t, t % 2 == 0), 110u + t);
  EXPECT_EQ(mem.stats().readBytes(), 0u);
  EXPECT_EQ(cache.stats().clear_fills, 4u);
  EXPECT_EQ(cache.stats().misses, 4u);
  // Tile 0 was written: after eviction its next miss must read it back.
  // Set 0 holds 0 and 2; 4 evicts 0 (LRU, dirty), 6 evicts 2 (dirty).
  cache.acquire(200, 4, false);
  cache.acquire(201, 6, false);
  EXPECT_FALSE(cache.resident(0));
  EXPECT_EQ(mem.stats().write_bytes[unsigned(Surface::BlendArrays)], 2u * kLine);
  const Cycle t = cache.acquire(1000, 0, false);  // evicts clean 4
  EXPECT_GT(t, 1000u + 40u);  // a real DRAM fill, not a clear one
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], kLine);
  EXPECT_EQ(cache.stats().clear_fills, 6u);
}

TEST(BlendArrayCache, WithoutFastClearFirstTouchReadsALine) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(16, 4), kLine, 64, 0, mem, false);
  Cycle now = 0;
  for (uint32_t t = 0; t < 10; ++t, ++now) acquireRetrying(cache, now, t, true);
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], 10u * kLine);
  EXPECT_EQ(cache.stats().clear_fills, 0u);
}

TEST(BlendArrayCache, MissQueueFullRefusesAndCounts) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(16, 4, /*miss_queue=*/2), kLine, 64, 0, mem, false);
  EXPECT_EQ(cache.acquire(0, 0, false), 78u);
  EXPECT_EQ(cache.acquire(0, 1, false), 94u);  // same row, queued 16 cycles behind on the bus
  EXPECT_EQ(cache.missesInFlight(0), 2u);
  EXPECT_EQ(cache.acquire(0, 2, false), kNever);
  EXPECT_EQ(cache.acquire(77, 2, false), kNever);
  EXPECT_EQ(cache.stats().miss_queue_full, 2u);
  EXPECT_EQ(cache.stats().accesses, 2u);  // refusals are not accesses
  EXPECT_FALSE(cache.resident(2));
  // A hit still goes through while the queue is full (it waits for its fill).
  EXPECT_EQ(cache.acquire(1, 0, false), 78u);
  // At 78 tile 0's fill has arrived: its entry is free again.
  EXPECT_EQ(cache.acquire(78, 2, false), 145u);  // column at 118 + CL = 129, + 16
  EXPECT_EQ(cache.stats().misses, 3u);
  EXPECT_EQ(cache.stats().peak_misses_in_flight, 2u);
  EXPECT_EQ(mem.stats().read_bytes[unsigned(Surface::BlendArrays)], 3u * kLine);
}

TEST(BlendArrayCache, HitUnderMissWaitsForTheFillAndCountsAsHit) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(16, 4), kLine, 16, 0, mem, false);
  EXPECT_EQ(cache.acquire(0, 5, false), 78u);
  EXPECT_EQ(cache.acquire(1, 5, true), 78u);
  EXPECT_EQ(cache.acquire(70, 5, false), 80u);  // fill done by then + hit latency
  EXPECT_EQ(cache.stats().hits, 2u);
  EXPECT_EQ(cache.stats().hits_under_miss, 1u);
  EXPECT_EQ(cache.stats().misses, 1u);
  EXPECT_TRUE(cache.touched(5));  // the write under the miss marks it
  EXPECT_EQ(mem.stats().readBytes(), kLine);  // no second fill
}

TEST(BlendArrayCache, RejectsBadInput) {
  MemorySystem mem(roundDram(), kMhz);
  BlendArrayCache cache(cacheOf(4, 2), kLine, 8, 0, mem, true);
  EXPECT_THROW(cache.acquire(0, 8, false), std::out_of_range);
  EXPECT_THROW(BlendArrayCache(cacheOf(4, 2, 0), kLine, 8, 0, mem, true), std::invalid_argument);
  EXPECT_THROW(BlendArrayCache(cacheOf(4, 2), 0, 8, 0, mem, true), std::invalid_argument);
}

TEST(BlendArrayCache, Deterministic) {
  struct Result {
    uint64_t sum, hits, misses, writebacks, full, dram_read, dram_write;
    bool operator==(const Result&) const = default;
  };
  auto run = [] {
    MemorySystem mem(DramConfig{}, 1150.0);
    CacheConfig c;  // igpu defaults: 128 KiB, 8 ways, 16-entry miss queue
    BlendArrayCache cache(c, 2048, 14400, 1 << 24, mem, true);
    uint64_t x = 99, sum = 0;
    Cycle now = 0;
    for (int i = 0; i < 50000; ++i) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      const uint32_t tile = uint32_t((x >> 33) % 512);  // 512 tiles vs 64 lines
      const Cycle t = cache.acquire(now, tile, (x >> 3) & 1);
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
  CacheConfig cfg = cacheOf(1, 8);
  cfg.size_bytes = 128 * 1024;
  BlendArrayCache cache(cfg, 2048, 64, 0, mem, false);
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

}  // namespace
}  // namespace oit::rop
