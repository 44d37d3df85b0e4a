// Blending-array cache (the ROP cache): hit rates, victims, DRAM bytes and latencies
// computed by hand (policies in oit_rop/memory/MEMORY.md). Against a plain
// reference on random streams: test_blend_array_cache_reference.cpp; lines
// apart from tiles and sectors: test_blend_array_cache_sectors.cpp.
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
namespace {

using namespace cache_testutil;

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

}  // namespace
}  // namespace oit::rop
