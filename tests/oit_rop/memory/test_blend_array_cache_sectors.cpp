// Blending-array cache lines apart from tiles: several lines per tile,
// sectors of a line filled and written back on their own, accesses that take
// all their lines or none, miss classes (values by hand; MEMORY.md).
#include <gtest/gtest.h>

#include <span>
#include <vector>

#include "oit_rop/memory/BlendArrayCache.hpp"

namespace oit::rop {
namespace blend_array_cache_sectors_test {

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

}  // namespace blend_array_cache_sectors_test
}  // namespace oit::rop
