// The shared cache level (l2 / l3): hit and miss latency, the slice ports'
// bandwidth, LRU and write-back, sectors, write-allocate, the victim-only
// mode, the miss classes and the dirty bytes left at the end. Expected values
// are derived by hand in the comments.
#include <gtest/gtest.h>

#include <vector>

#include "oit_rop/memory/CacheLevel.hpp"

using namespace oit::rop;

namespace {

// The level below: a fixed latency, every request recorded.
struct FakeBelow : MemoryPort {
  struct Req {
    Cycle now;
    uint64_t addr;
    uint32_t bytes;
    bool write;
  };
  Cycle latency = 100;
  std::vector<Req> reqs;
  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface) override {
    reqs.push_back({now, addr, bytes, write});
    return now + latency;
  }
  uint64_t bytes(bool write) const {
    uint64_t n = 0;
    for (const Req& r : reqs) n += r.write == write ? r.bytes : 0;
    return n;
  }
};

SharedCacheConfig small(uint64_t size, unsigned ways, unsigned line = 64, unsigned slices = 1) {
  SharedCacheConfig c;
  c.size_bytes = size;
  c.ways = ways;
  c.line_bytes = line;
  c.slices = slices;
  c.hit_latency = 20;
  c.bytes_per_clock = 16;
  return c;
}

}  // namespace

TEST(CacheLevel, MissThenHitLatency) {
  FakeBelow below;
  CacheLevel l2("l2", small(4096, 4), 1000, below);
  // Miss at 0: the port moves 64 B in 4 cycles (16 B/clock) from 0, the lookup
  // takes 20, then the fill 100: ready at 120.
  EXPECT_EQ(l2.access(0, 0, 64, false, Surface::BlendArrays), 120u);
  ASSERT_EQ(below.reqs.size(), 1u);
  EXPECT_EQ(below.reqs[0].now, 20u);
  EXPECT_EQ(below.reqs[0].bytes, 64u);
  // Hit at 200: 200 + 20.
  EXPECT_EQ(l2.access(200, 0, 64, false, Surface::BlendArrays), 220u);
  EXPECT_EQ(l2.stats().hits[0], 1u);
  EXPECT_EQ(l2.stats().misses[0], 1u);
  // A hit on a line whose fill is still in flight waits for that fill.
  EXPECT_EQ(l2.access(300, 64, 64, false, Surface::Depth), 420u);
  EXPECT_EQ(l2.access(301, 64, 64, false, Surface::Depth), 420u);
}

namespace {
// Lines 0..15 read at cycle 0 (warm), then all read again at t0: when the
// last of these 16 hits is there.
Cycle lastOfSixteenHits(CacheLevel& l2, Cycle t0) {
  for (uint64_t a = 0; a < 1024; a += 64) l2.access(0, a, 64, false, Surface::BlendArrays);
  Cycle last = 0;
  for (uint64_t a = 0; a < 1024; a += 64) last = std::max(last, l2.access(t0, a, 64, false, Surface::BlendArrays));
  return last;
}
}  // namespace

TEST(CacheLevel, OneSlicePortMovesBytesPerClock) {
  FakeBelow below;
  CacheLevel l2("l2", small(4096, 4), 1000, below);
  // 16 hits of 64 B requested at t0 on one 16 B/clock port: transfers start
  // at t0, t0 + 4, ..., t0 + 60; the last is there at t0 + 60 + 20 = t0 + 80,
  // i.e. 1024 B / 16 B per clock + the hit latency - one transfer (4).
  EXPECT_EQ(lastOfSixteenHits(l2, 10000), 10000u + 80);
}

TEST(CacheLevel, SlicesServeInParallel) {
  FakeBelow below;
  CacheLevel l2("l2", small(4 * 4096, 4, 64, 4), 1000, below);
  // Consecutive lines walk the 4 slices (lines 0..15: no bits from 12 up, so
  // slice = line mod 4): 4 lines per slice, the last transfer of each starts
  // at t0 + 12, data at t0 + 32.
  std::vector<unsigned> per_slice(4, 0);
  for (uint64_t a = 0; a < 1024; a += 64) ++per_slice[l2.sliceOf(a)];
  EXPECT_EQ(per_slice, (std::vector<unsigned>{4, 4, 4, 4}));
  EXPECT_EQ(lastOfSixteenHits(l2, 10000), 10000u + 32);
}

TEST(CacheLevel, LeastRecentlyUsedDirtyVictimIsWrittenBack) {
  FakeBelow below;
  CacheLevel l2("l2", small(128, 2), 1000, below);  // one set of 2 ways
  l2.access(0, 0, 64, true, Surface::Colour);      // A dirty (write-allocate, whole sector: no fetch)
  l2.access(10, 64, 64, false, Surface::Depth);    // B clean (a fill)
  l2.access(20, 0, 64, false, Surface::Colour);    // A hit: B is now the LRU
  l2.access(30, 128, 64, false, Surface::Depth);   // C evicts B (clean: no write)
  EXPECT_EQ(below.bytes(true), 0u);
  l2.access(40, 192, 64, false, Surface::Depth);   // D evicts A (dirty: 64 B written back)
  EXPECT_EQ(below.bytes(true), 64u);
  EXPECT_EQ(l2.stats().writebacks[unsigned(Surface::Colour)], 1u);
  EXPECT_EQ(l2.stats().writeback_bytes[unsigned(Surface::Colour)], 64u);
  EXPECT_FALSE(l2.resident(0));
  EXPECT_TRUE(l2.resident(128));
}

TEST(CacheLevel, SectorsFillAndWriteBackOnlyWhatIsNeeded) {
  FakeBelow below;
  SharedCacheConfig c = small(1024, 2, 128);
  c.sector_bytes = 32;
  CacheLevel l2("l2", c, 1000, below);
  l2.access(0, 32, 32, false, Surface::BlendArrays);  // sector 1: a 32 B fill
  ASSERT_EQ(below.reqs.size(), 1u);
  EXPECT_EQ(below.reqs[0].addr, 32u);
  EXPECT_EQ(below.reqs[0].bytes, 32u);
  l2.access(200, 32, 32, false, Surface::BlendArrays);  // hit
  l2.access(300, 64, 64, false, Surface::BlendArrays);  // sectors 2 and 3: one 64 B fill (a sector miss)
  ASSERT_EQ(below.reqs.size(), 2u);
  EXPECT_EQ(below.reqs[1].addr, 64u);
  EXPECT_EQ(below.reqs[1].bytes, 64u);
  EXPECT_EQ(l2.stats().misses[0], 2u);
  // A whole-sector write needs no fetch; a partial one fetches its sector.
  l2.access(400, 1024, 32, true, Surface::BlendArrays);
  EXPECT_EQ(below.reqs.size(), 2u);
  l2.access(500, 1024 + 40, 8, true, Surface::BlendArrays);
  ASSERT_EQ(below.reqs.size(), 3u);
  EXPECT_EQ(below.reqs[2].addr, 1024u + 32);
  EXPECT_EQ(below.reqs[2].bytes, 32u);
  // The dirty bytes left: sectors 0 and 1 of the line at 1024, one run.
  std::vector<DirtyRange> dirty;
  l2.dirtyRanges(dirty);
  ASSERT_EQ(dirty.size(), 1u);
  EXPECT_EQ(dirty[0].addr, 1024u);
  EXPECT_EQ(dirty[0].bytes, 64u);
}

TEST(CacheLevel, VictimLevelTakesEveryEvictionAndDoesNotAllocateOnReadMisses) {
  FakeBelow dram;
  SharedCacheConfig c3 = small(4096, 4);
  c3.victim_only = true;
  CacheLevel l3("l3", c3, 1000, dram);
  CacheLevel l2("l2", small(128, 2), 1000, l3, &l3);  // one set of 2 ways
  l2.access(0, 0, 64, false, Surface::BlendArrays);   // A: misses both, from DRAM; l3 keeps nothing
  EXPECT_FALSE(l3.resident(0));
  EXPECT_EQ(dram.reqs.size(), 1u);
  l2.access(10, 64, 64, true, Surface::BlendArrays);   // B dirty
  l2.access(20, 128, 64, false, Surface::BlendArrays); // C evicts A (clean) into l3
  EXPECT_TRUE(l3.resident(0));
  EXPECT_EQ(l3.stats().victims_in, 1u);
  l2.access(30, 192, 64, false, Surface::BlendArrays); // D evicts B (dirty) into l3: nothing reaches DRAM yet
  EXPECT_EQ(dram.bytes(true), 0u);
  const size_t dram_reads = dram.reqs.size();
  // A again: an l3 hit, no DRAM access; 20 (l2 lookup) + 20 (l3 lookup) = 40 after the request.
  EXPECT_EQ(l2.access(1000, 0, 64, false, Surface::BlendArrays), 1040u);
  EXPECT_EQ(dram.reqs.size(), dram_reads);
  std::vector<DirtyRange> dirty;
  l3.dirtyRanges(dirty);
  ASSERT_EQ(dirty.size(), 1u);
  EXPECT_EQ(dirty[0].addr, 64u);
}

TEST(CacheLevel, MissesAreClassifiedCompulsoryCapacityConflict) {
  FakeBelow below;
  // Two sets of one way (direct mapped), 2 lines: lines 0 and 2 share set 0.
  CacheLevel l2("l2", small(128, 1), 1000, below);
  Cycle t = 0;
  const auto read = [&](uint64_t line) { l2.access(t += 200, line * 64, 64, false, Surface::BlendArrays); };
  read(0);  // compulsory
  read(2);  // compulsory (evicts 0)
  read(0);  // conflict: a 2-line fully associative cache still holds 0
  EXPECT_EQ(l2.stats().compulsory_misses, 2u);
  EXPECT_EQ(l2.stats().conflict_misses, 1u);
  read(1);  // compulsory
  read(3);  // compulsory; the fully associative cache now holds 1 and 3
  read(2);  // capacity: neither cache holds 2
  EXPECT_EQ(l2.stats().compulsory_misses, 4u);
  EXPECT_EQ(l2.stats().capacity_misses, 1u);
  EXPECT_EQ(l2.stats().misses[0], 6u);
}

// stats.level_miss_classes off: the same accesses, hits, misses, bytes and
// cycles, and no split (all three causes 0, classifiesMisses false).
TEST(CacheLevel, WithoutClassificationOnlyTheSplitIsMissing) {
  FakeBelow below_on, below_off;
  CacheLevel on("l2", small(128, 1), 1000, below_on, nullptr, true);
  CacheLevel off("l2", small(128, 1), 1000, below_off, nullptr, false);
  EXPECT_TRUE(on.classifiesMisses());
  EXPECT_FALSE(off.classifiesMisses());
  Cycle t = 0;
  for (uint64_t line : {0, 2, 0, 1, 3, 2, 2}) {  // the sequence above, and a hit
    t += 200;
    const bool write = line == 1;
    EXPECT_EQ(on.access(t, line * 64, 64, write, Surface::BlendArrays),
              off.access(t, line * 64, 64, write, Surface::BlendArrays));
  }
  EXPECT_EQ(on.stats().misses[0], 6u);
  EXPECT_EQ(off.stats().misses[0], 6u);
  EXPECT_EQ(off.stats().hits[0], 1u);
  EXPECT_EQ(on.stats().fill_bytes, off.stats().fill_bytes);
  EXPECT_EQ(on.stats().writeback_bytes, off.stats().writeback_bytes);
  EXPECT_EQ(on.stats().compulsory_misses + on.stats().capacity_misses + on.stats().conflict_misses, 6u);
  EXPECT_EQ(off.stats().compulsory_misses + off.stats().capacity_misses + off.stats().conflict_misses, 0u);
  EXPECT_EQ(below_on.reqs.size(), below_off.reqs.size());
}

TEST(CacheLevel, ASectorMissIsAConflictOnlyWhenTheFullyAssociativeCacheHoldsTheSector) {
  FakeBelow below;
  // Two sets of one way, 64-byte lines of 16-byte sectors: lines 0 and 2 share set 0.
  SharedCacheConfig c = small(128, 1);
  c.sector_bytes = 16;
  CacheLevel l2("l2", c, 1000, below);
  Cycle t = 0;
  const auto read = [&](uint64_t line, uint32_t sector) {
    l2.access(t += 200, line * 64 + sector * 16, 16, false, Surface::BlendArrays);
  };
  read(0, 0);  // compulsory
  read(1, 0);  // compulsory
  read(2, 0);  // compulsory; evicts 0 in both caches (the fully associative one's LRU is 0)
  read(0, 1);  // compulsory (sector 1 never held); 0 is back with sector 1 in both
  read(0, 0);  // capacity: neither holds sector 0 of line 0
  EXPECT_EQ(l2.stats().compulsory_misses, 4u);
  EXPECT_EQ(l2.stats().capacity_misses, 1u);
  EXPECT_EQ(l2.stats().conflict_misses, 0u);
  read(2, 0);  // conflict: evicted from set 0, still in the fully associative cache
  EXPECT_EQ(l2.stats().conflict_misses, 1u);
}

TEST(CacheLevel, LruOrderSurvivesTheStampClocksWrap) {
  FakeBelow below;
  CacheLevel l2("l2", small(256, 4), 1000, below);  // one set of 4 ways
  l2.setLruClock(0xFFFFFFFEu);
  l2.access(0, 0, 64, false, Surface::Depth);    // A: stamp 0xFFFFFFFE
  l2.access(1, 64, 64, false, Surface::Depth);   // B: 0xFFFFFFFF
  l2.access(2, 128, 64, false, Surface::Depth);  // C: the clock wraps; A, B renumbered 1, 2; C 3
  l2.access(3, 192, 64, false, Surface::Depth);  // D: 4
  l2.access(4, 0, 64, false, Surface::Depth);    // A hit: 5, so B is the least recently used
  l2.access(5, 256, 64, false, Surface::Depth);  // E evicts B (a wrap to stamp 0 would have evicted C)
  EXPECT_FALSE(l2.resident(64));
  for (uint64_t a : {0u, 128u, 192u, 256u}) EXPECT_TRUE(l2.resident(a)) << a;
  EXPECT_EQ(l2.stats().misses[unsigned(Surface::Depth)], 5u);
}

TEST(CacheLevel, RefusesALineNumberItsTagsCannotHold) {
  FakeBelow below;
  CacheLevel l2("l2", small(4096, 4), 1000, below);
  // Tags are 32 bits (line number + 1): line 0xFFFFFFFE is the last one.
  const uint64_t last = 0xFFFFFFFEull * 64;
  EXPECT_EQ(l2.access(0, last, 64, false, Surface::Depth), 120u);  // a miss: 20 + 100
  EXPECT_TRUE(l2.resident(last));
  EXPECT_FALSE(l2.resident(last + 64));
  EXPECT_THROW(l2.access(200, last + 64, 64, false, Surface::Depth), std::runtime_error);
  EXPECT_THROW(l2.insertVictim(200, last + 64, 64, 64, 1, 1, Surface::Depth), std::runtime_error);
}

TEST(CacheLevel, RejectsBadGeometry) {
  FakeBelow below;
  EXPECT_THROW(CacheLevel("l2", small(1000, 4), 1000, below), std::invalid_argument);  // not whole sets
  SharedCacheConfig c = small(4096, 4);
  c.sector_bytes = 48;
  EXPECT_THROW(CacheLevel("l2", c, 1000, below), std::invalid_argument);
  c = small(4096, 4);
  c.bytes_per_clock = 0;
  EXPECT_THROW(CacheLevel("l2", c, 1000, below), std::invalid_argument);
}

namespace {
// A level below that accepts writes 5000 cycles late (its write queue full)
// and answers reads after 100; it keeps the cycle of its last write.
struct SlowWrites : MemoryPort {
  Cycle write_at = 0;
  unsigned writes = 0;
  Cycle access(Cycle now, uint64_t, uint32_t, bool write, Surface) override {
    if (write) {
      write_at = now;
      ++writes;
    }
    return now + (write ? 5000 : 100);
  }
};
}  // namespace

// A posted write returns when the level below accepted it (MEMORY.md, "DRAM:
// writes": a full write queue makes the writer wait, it pushes back on its
// requesters), and a way is not free before its old line left it: a miss that
// evicts a dirty line is ready no earlier than the write-back's acceptance, as
// in the ROP cache (BlendArrayCache::commitMiss). (Until the fix CacheLevel
// dropped that acceptance, so behind an l2 nothing ever waited for room in the
// DRAM's write queue: why dram.write_queue 64 -> 60 made test_monotonicity's
// particles frame 1.28 % faster with input.seed = 8, DESIGN.md, "Monotonicity
// of the DRAM steps".) One set of two ways, A and B written (dirty, whole
// sectors: no fetch), then C read at 300 evicts A: its write-back goes below
// at 300 (the allocation's tick, the port's start), accepted at 5300; the
// fill, read below after the 20-cycle lookup at 320, is there at 420, but the
// line's way is free only at 5300: C is ready at max(420, 5300) = 5300 (420
// before the fix). A hit on C afterwards waits for the same way: 5300.
TEST(CacheLevel, AMissWaitsForItsDirtyVictimsAcceptanceBelow) {
  SlowWrites below;
  CacheLevel l2("l2", small(128, 2), 1000, below);  // one set of 2 ways
  l2.access(0, 0, 64, true, Surface::BlendArrays);     // A dirty
  l2.access(10, 64, 64, true, Surface::BlendArrays);   // B dirty
  const Cycle c = l2.access(300, 128, 64, false, Surface::BlendArrays);  // C evicts A
  ASSERT_EQ(below.write_at, 300u);
  EXPECT_EQ(c, 5300u);
  EXPECT_EQ(l2.access(400, 128, 64, false, Surface::BlendArrays), 5300u);  // hit under the way's wait
}

// The same for a write that allocates (a write-back of the level above): it
// is accepted once its bytes crossed the port and the way it takes is free.
// A and B written dirty at 0 and 10; D written at 300 evicts A (written below
// at 300, accepted at 5300): D's bytes cross the port 300..304 (64 B at 16 B
// a clock), accepted at max(304, 5300) = 5300 (304 before the fix). A write
// that hits (B again at 400) is accepted at 404: nothing waits for room.
TEST(CacheLevel, AWriteThatAllocatesWaitsForItsDirtyVictimsAcceptanceBelow) {
  SlowWrites below;
  CacheLevel l2("l2", small(128, 2), 1000, below);
  l2.access(0, 0, 64, true, Surface::BlendArrays);
  l2.access(10, 64, 64, true, Surface::BlendArrays);
  EXPECT_EQ(l2.access(300, 128, 64, true, Surface::BlendArrays), 5300u);
  EXPECT_EQ(below.writes, 1u);
  EXPECT_EQ(l2.access(400, 64, 64, true, Surface::BlendArrays), 404u);
}

// A victim level's port is the write-back's acceptance: the l2 hands its
// evicted line to the victim l3 through the l3 slice's port, and its way is
// free once the l3 took the bytes. The l3 has two slices of 1 B a clock
// (slice = line mod 2 for these lines), 20-cycle lookups; the l2 one set of
// two ways at 16 B a clock, 20-cycle lookups; DRAM (FakeBelow) 100 cycles.
// A (line 0, l3 slice 0) and B (line 1) written into the l2 (dirty). At 1000
// five reads of other even lines keep the l3's slice 0 busy 1000..1320 (64
// cycles each: another requester, as the l2's other sets' misses would). C
// (line 3, slice 1) read from the l2 at 1000: the l2's port 1000..1004, its
// lookup to 1020, the fill from the l3 at 1020 on slice 1 (idle): its port
// 1020..1084, lookup to 1040, a miss (not allocated: victim-only), DRAM at
// 1040 -> 1140, so the fill is there at max(1084, 1040, 1140) = 1140. A is the
// l2's victim, handed to the l3 at 1000 (the l2's port start): slice 0 is free
// from 1320, A's 64 B move 1320..1384, and the l3 installs it in an empty way
// (no eviction of its own). C is ready at max(1140, 1384) = 1384 (1140 before
// the fix); A is in the l3, dirty, nothing written to DRAM.
TEST(CacheLevel, AMissWaitsForTheVictimLevelsPortToTakeItsVictim) {
  FakeBelow dram;
  SharedCacheConfig c3 = small(4096, 4, 64, 2);
  c3.victim_only = true;
  c3.bytes_per_clock = 1;
  CacheLevel l3("l3", c3, 1000, dram);
  CacheLevel l2("l2", small(128, 2), 1000, l3, &l3);
  ASSERT_EQ(l3.sliceOf(0), 0u);
  ASSERT_EQ(l3.sliceOf(3 * 64), 1u);
  l2.access(0, 0, 64, true, Surface::BlendArrays);    // A dirty
  l2.access(10, 64, 64, true, Surface::BlendArrays);  // B dirty
  Cycle busy = 0;
  for (uint64_t line = 16; line < 26; line += 2) {
    ASSERT_EQ(l3.sliceOf(line * 64), 0u);
    busy = std::max(busy, l3.access(1000, line * 64, 64, false, Surface::Depth));
  }
  // The fifth read's bytes move 1256..1320, lookup to 1276, DRAM 1276 -> 1376.
  ASSERT_EQ(busy, 1376u);
  EXPECT_EQ(l2.access(1000, 3 * 64, 64, false, Surface::BlendArrays), 1384u);
  EXPECT_TRUE(l3.resident(0));
  EXPECT_EQ(dram.bytes(true), 0u);
}

// The victim level's own eviction: the line the l3 drops to take the l2's
// victim is written to DRAM, and the l2's way is free once DRAM accepted it.
// The l3 holds one line (one set, one way), victim-only; DRAM (SlowWrites)
// accepts writes 5000 cycles late, reads in 100. The l2 one set of two ways.
// A and B written into the l2 (dirty) at 0 and 10. C read at 300: an l2 miss,
// the fill from the l3 at 320 (the l3's port 320..324, lookup to 340, a miss:
// DRAM at 340 -> 440); A handed to the l3 at 300 (its port 300..304, an empty
// way): C ready at max(440, 304) = 440. D read at 1000: the fill the same way,
// 1040 -> 1140; B (the l2's LRU) handed to the l3 at 1000 (port 1000..1004),
// whose one way holds A, dirty: A is written to DRAM at 1000 (the l3's port
// start), accepted at 6000. D is ready at max(1140, 1004, 6000) = 6000 (1140
// before the fix).
TEST(CacheLevel, AMissWaitsForTheVictimLevelsOwnEvictionBelow) {
  SlowWrites dram;
  SharedCacheConfig c3 = small(64, 1);
  c3.victim_only = true;
  CacheLevel l3("l3", c3, 1000, dram);
  CacheLevel l2("l2", small(128, 2), 1000, l3, &l3);
  l2.access(0, 0, 64, true, Surface::BlendArrays);    // A dirty
  l2.access(10, 64, 64, true, Surface::BlendArrays);  // B dirty
  EXPECT_EQ(l2.access(300, 128, 64, false, Surface::BlendArrays), 440u);
  EXPECT_EQ(dram.writes, 0u);
  EXPECT_EQ(l2.access(1000, 192, 64, false, Surface::BlendArrays), 6000u);
  EXPECT_EQ(dram.writes, 1u);
  EXPECT_EQ(dram.write_at, 1000u);
  EXPECT_TRUE(l3.resident(64));
  EXPECT_FALSE(l3.resident(0));
}

// A write a victim-only level does not hold goes on below and is accepted
// when the level below accepted it. The level's port moves the 64 B 100..104
// (16 B a clock); not held, so it is written below at 100 (the port's start),
// accepted at 5100: the write is accepted at max(104, 5100) = 5100 (104 before
// the fix). Nothing is allocated.
TEST(CacheLevel, AWritePassedThroughAVictimLevelIsAcceptedWhenBelowAcceptedIt) {
  SlowWrites dram;
  SharedCacheConfig c = small(4096, 4);
  c.victim_only = true;
  CacheLevel l3("l3", c, 1000, dram);
  EXPECT_EQ(l3.access(100, 512, 64, true, Surface::Colour), 5100u);
  EXPECT_EQ(dram.write_at, 100u);
  EXPECT_FALSE(l3.resident(512));
}

// Partitions a quantum apart (DESIGN.md, "Structure (SystemC)"): a line
// another partition's eviction wrote into a level below at its own, later
// time is read back by a partition behind at its earlier time, and must not
// wait for the other's time (a write-allocate's line is there once its way is
// free for a reader after the write; one whose lookup came before it waits as
// long as the way took, from its own lookup; a victim's copy in a victim-only
// level does not wait for its way, insertVictim). An l2 of one set of two ways (16 B a clock, 20-cycle
// lookups) above a non-victim l3 (16 sets of 4 ways, same port and lookup)
// above DRAM (FakeBelow, 100 cycles); the ports keep 24,096 cycles (a quantum
// of 10,000: 2 x 10,000 + 4,096). Partition B writes Y (line 0) at 0, dirty;
// partition A, a quantum ahead, writes X1 (line 1) at 10 and reads X2 (line 2)
// at 10,000: an l2 miss whose fill comes from the l3 (its port 10,020..10,024,
// lookup to 10,040, a miss: DRAM 10,040 -> 10,140), and whose way is Y's (the
// LRU): Y is written into the l3 at 10,000 (its port 10,000..10,004, an
// empty way: free at once, Y's data there at 10,000 for a lookup after the
// write). B, behind, reads Y at 100: an l2 miss (its port 100..104,
// lookup to 120), X1 the l2's victim (written into the l3 at 100: port
// 100..104, accepted at 104), Y's fill from the l3 at 120 (port 120..124,
// lookup to 140, before the write at 10,000: a hit that waits as long as Y's
// way took, 0, from 140): ready at max(120, 104, 140, 104) = 140. Before the
// fix the l3's copy of Y was ready when its way was free at A's time, 10,000,
// and B waited until then. (In lockstep Y would still be in the l2 at 100:
// a hit at 120; the 20 cycles are the interleave's, the LRU state seen a
// quantum on.)
TEST(CacheLevel, ALineAnotherPartitionWroteBelowAQuantumAheadIsNotReadyOnlyAtItsTime) {
  FakeBelow dram;
  constexpr Cycle kLookback = 2 * 10000 + 4096;
  CacheLevel l3("l3", small(4096, 4), kLookback, dram);
  CacheLevel l2("l2", small(128, 2), kLookback, l3);
  l2.access(0, 0, 64, true, Surface::BlendArrays);                               // B: Y dirty
  l2.access(10, 64, 64, true, Surface::BlendArrays);                             // A: X1 dirty
  ASSERT_EQ(l2.access(10000, 128, 64, false, Surface::BlendArrays), 10140u);     // A: X2 evicts Y
  ASSERT_TRUE(l3.resident(0));
  ASSERT_FALSE(l2.resident(0));
  EXPECT_EQ(l2.access(100, 0, 64, false, Surface::BlendArrays), 140u);           // B reads Y back
  EXPECT_EQ(dram.bytes(true), 0u);
  // The writer itself still waits for its way: covered by
  // AWriteThatAllocatesWaitsForItsDirtyVictimsAcceptanceBelow.
}

// A hit under a fill another partition asked for after the hit's lookup (it
// runs up to a quantum ahead): in lockstep that fill was not asked yet, and
// the reader would have missed itself. An l2 (4 KiB, 4 ways, 16 B a clock,
// 20-cycle lookups) above DRAM (FakeBelow, 100 cycles); the ports keep 24,096
// cycles (a quantum of 10,000). Partition A reads X at 10,000: a miss, its
// port 10,000..10,004, the fill asked at 10,020, there at 10,120. Partition
// B, behind, reads X at 100: its port 100..104, lookup done at 120, before
// A's fill was asked (10,020): its data is there as long after its lookup as
// A's was after its request, 120 + 100 = 220 (what its own miss would have
// taken); before the fix it waited for A's fill, 10,120. A later reader whose
// lookup comes after the request (A again at 10,050: lookup done at 10,070)
// waits for the fill in flight, 10,120, as always (MissThenHitLatency).
TEST(CacheLevel, AHitUnderAFillAskedAfterItsLookupWaitsAsLongFromItsLookup) {
  FakeBelow dram;
  CacheLevel l2("l2", small(4096, 4), 2 * 10000 + 4096, dram);
  EXPECT_EQ(l2.access(10000, 0, 64, false, Surface::BlendArrays), 10120u);  // A
  EXPECT_EQ(l2.access(100, 0, 64, false, Surface::BlendArrays), 220u);      // B, a quantum behind
  EXPECT_EQ(l2.access(10050, 0, 64, false, Surface::BlendArrays), 10120u);  // A, under its own fill
  EXPECT_EQ(l2.stats().hits[0], 2u);
  EXPECT_EQ(dram.reqs.size(), 1u);  // no second fill is booked: the reader's wait is shifted, not re-asked
}
