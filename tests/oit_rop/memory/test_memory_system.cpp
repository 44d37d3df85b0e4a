// DRAM model: expectations are derived by hand from the formulas in
// oit_rop/memory/MEMORY.md, mostly on a "round" configuration where every timing is a
// whole number of core cycles (1000 MHz core, tCK 1 ns, 16 B per cycle).
// Against a burst-by-burst reference: test_memory_system_reference.cpp;
// refresh: test_dram_refresh.cpp.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "oit_rop/TestLcg.hpp"
#include "oit_rop/memory/DramTestConfig.hpp"
#include "oit_rop/memory/MemorySystem.hpp"

namespace oit::rop {
namespace {

using namespace testutil;  // the round configuration's timings (DramTestConfig.hpp)
DramConfig roundConfig(unsigned channels) { return roundDramConfig(channels); }

// The accessors give the converted timings (DramTimings has the conversions' tests).
TEST(MemorySystem, DerivedTimingsOfRoundConfig) {
  MemorySystem m(roundConfig(2), kRoundMhz);
  EXPECT_DOUBLE_EQ(m.bytesPerCyclePerChannel(), 16.0);
  EXPECT_DOUBLE_EQ(m.peakBytesPerCycle(), 32.0);
  EXPECT_DOUBLE_EQ(m.controllerCycles(), 40.0);
  EXPECT_DOUBLE_EQ(m.clCycles(), 11.0);
  EXPECT_DOUBLE_EQ(m.burstCycles(), 4.0);
  EXPECT_EQ(m.channelOf(256), 1u);
  EXPECT_EQ(m.bankOf(8192 * 2), 1u);  // local 8192: bank 1
  EXPECT_EQ(m.rowOf(65536 * 2), 1u);
}

TEST(MemorySystem, IgpuPresetClosedBankLatency) {
  // ceil(46 + 2 * 15.8125 + 5.75) = ceil(83.375) = 84 (DramTimings.IgpuPresetConversions).
  MemorySystem m(DramConfig{}, 1150.0);
  EXPECT_EQ(m.access(0, 0, 64, false, Surface::BlendArrays), 84u);
}

TEST(MemorySystem, NonPowerOfTwoGeometryBooksEveryBank) {
  DramConfig c = roundConfig(3);
  c.banks = 6;
  MemorySystem m(c, kRoundMhz);
  // 3 x 48 KiB: one row index across 6 banks on each of 3 channels.
  m.access(0, 0, 3 * 48 * 1024, false, Surface::Depth);
  EXPECT_EQ(m.stats().row_misses, 3u * 6u);
  for (unsigned ch = 0; ch < 3; ++ch) EXPECT_EQ(m.stats().channel_busy[ch], 48u * 1024u / 16u);
}

TEST(MemorySystem, SingleReadLatencyClosedBankRowHitAndRowMiss) {
  MemorySystem m(roundConfig(1), kRoundMhz);
  // Nothing open yet: controller + tRCD + CL + one burst.
  EXPECT_EQ(m.access(0, 0, 64, false, Surface::Depth), kCtrl + kTrcd + kCl + kBurst);
  // Same row (bank 0, row 0), long after: controller + CL + burst.
  EXPECT_EQ(m.access(1000, 64, 64, false, Surface::Depth), 1000 + kCtrl + kCl + kBurst);
  // Bank 0, row 1 (1 channel: 8 banks x 8 KiB per row index): precharge too.
  ASSERT_EQ(m.bankOf(65536), 0u);
  ASSERT_EQ(m.rowOf(65536), 1u);
  EXPECT_EQ(m.access(2000, 65536, 64, false, Surface::Depth), 2000 + kCtrl + kTrp + kTrcd + kCl + kBurst);
  EXPECT_EQ(m.stats().row_hits, 1u);
  EXPECT_EQ(m.stats().row_misses, 2u);
  EXPECT_EQ(m.stats().requests, 3u);
  EXPECT_EQ(m.stats().last_completion, 2000 + kCtrl + kTrp + kTrcd + kCl + kBurst);
}

// Writes are posted: accepted into the channel's write queue after the
// controller latency, written later (here: at the frame-end drain).
TEST(MemorySystem, WritesArePostedAndWrittenAtTheDrain) {
  MemorySystem m(roundConfig(1), kRoundMhz);
  EXPECT_EQ(m.access(0, 0, 64, true, Surface::Colour), kCtrl);
  EXPECT_EQ(m.stats().write_bytes[unsigned(Surface::Colour)], 64u);
  EXPECT_EQ(m.stats().readBytes(), 0u);
  EXPECT_EQ(m.pendingWriteBursts(0), 1u);
  EXPECT_EQ(m.stats().channel_busy[0], 0u);
  // The drain at 100 writes it like a read of a closed bank: 100 + tRCD + CL + burst.
  EXPECT_EQ(m.drainWrites(100), 100 + kTrcd + kCl + kBurst);
  EXPECT_EQ(m.pendingWriteBursts(0), 0u);
  EXPECT_EQ(m.stats().channel_busy[0], kBurst);
  EXPECT_EQ(m.stats().row_misses, 1u);
  EXPECT_EQ(m.stats().last_completion, 100 + kTrcd + kCl + kBurst);
  // Nothing waits: the drain returns its cycle (or the last write's end).
  EXPECT_EQ(m.drainWrites(90), 126u);
  EXPECT_EQ(m.drainWrites(200), 200u);
}

TEST(MemorySystem, PartialBurstCostsAFullBurstButCountsExactBytes) {
  // DRAM moves whole bursts: 32 B take a 64 B burst's bus time.
  MemorySystem m(roundConfig(1), kRoundMhz);
  EXPECT_EQ(m.access(0, 0, 32, false, Surface::Resolve), kCtrl + kTrcd + kCl + kBurst);
  EXPECT_EQ(m.stats().channel_busy[0], kBurst);
  EXPECT_EQ(m.stats().read_bytes[unsigned(Surface::Resolve)], 32u);
  // 64 B straddling a burst boundary are two bursts.
  m.access(1000, 96, 64, false, Surface::Resolve);
  EXPECT_EQ(m.stats().channel_busy[0], 3 * kBurst);
}

TEST(MemorySystem, MovingBytesTakesAtLeastBytesOverBandwidth) {
  for (unsigned channels : {1u, 2u, 4u}) {
    for (uint32_t bytes : {64u * 1024u, 256u * 1024u, 1024u * 1024u, 4096u * 1024u}) {
      MemorySystem m(roundConfig(channels), kRoundMhz);
      const Cycle done = m.access(0, 0, bytes, false, Surface::BlendArrays);
      const double lower = bytes / m.peakBytesPerCycle();
      EXPECT_GE(double(done), lower) << channels << " ch, " << bytes << " B";
      // Open rows, row-major mapping: every row change of a bank is hidden behind
      // the other banks' transfers, so the bus never idles after the first
      // activate: done = controller + tRCD + CL + bytes / peak, exactly.
      EXPECT_EQ(done, kCtrl + kTrcd + kCl + Cycle(lower)) << channels << " ch, " << bytes << " B";
      for (unsigned c = 0; c < channels; ++c) EXPECT_EQ(m.stats().channel_busy[c], Cycle(lower));
    }
  }
}

TEST(MemorySystem, BandwidthBoundHoldsForManySmallRequestsOnIgpuPreset) {
  // 4096 back-to-back 64 B reads issued in the same cycle: the two channels at
  // 11.13 B/cycle each cannot finish before bytes / peak cycles.
  for (unsigned channels : {1u, 2u}) {
    DramConfig c;
    c.channels = channels;
    c.trefi_ns = 0;  // (refresh's share has its own tests)
    MemorySystem m(c, 1150.0);
    Cycle done = 0;
    for (uint64_t i = 0; i < 4096; ++i) done = std::max(done, m.access(0, i * 64, 64, false, Surface::BlendArrays));
    const double lower = 4096.0 * 64 / m.peakBytesPerCycle();
    EXPECT_GE(double(done), lower);
    EXPECT_LE(double(done), lower + 100.0);  // plus one unloaded latency (~84), not more
    EXPECT_EQ(m.stats().last_completion, done);
  }
}

// Closed page (dram.open_row = false): one activate per access run (the
// bursts of one request in one row), auto-precharge after its last burst.
TEST(MemorySystem, ClosedPageActivatesOncePerRequestRun) {
  DramConfig open_cfg = roundConfig(1);
  DramConfig closed_cfg = open_cfg;
  closed_cfg.open_row = false;
  // One request of 8 KiB, 1 channel: one row of bank 0, 128 bursts. Both
  // policies: one activate, then the bus streams 128 bursts.
  MemorySystem open(open_cfg, kRoundMhz), closed(closed_cfg, kRoundMhz);
  EXPECT_EQ(open.access(0, 0, 8192, false, Surface::Depth), kCtrl + kTrcd + kCl + 128 * kBurst);  // 582
  EXPECT_EQ(closed.access(0, 0, 8192, false, Surface::Depth), kCtrl + kTrcd + kCl + 128 * kBurst);
  EXPECT_EQ(closed.stats().row_hits, 127u);  // the run's later bursts hit the row it opened
  EXPECT_EQ(closed.stats().row_misses, 1u);
  // Closed page, a later access to the row just used: precharged after the
  // run, so tRCD + CL again, never a row hit.
  EXPECT_EQ(closed.access(100000, 0, 64, false, Surface::Depth), 100000 + kCtrl + kTrcd + kCl + kBurst);
  EXPECT_EQ(closed.stats().row_misses, 2u);
}

TEST(MemorySystem, OpenRowBeatsClosedPageOnSeparateRequestsToOneRow) {
  // 128 requests of 64 B to one row of bank 0, all at cycle 0.
  DramConfig open_cfg = roundConfig(1);
  DramConfig closed_cfg = open_cfg;
  closed_cfg.open_row = false;
  MemorySystem open(open_cfg, kRoundMhz), closed(closed_cfg, kRoundMhz);
  Cycle open_end = 0, closed_end = 0;
  for (uint64_t i = 0; i < 128; ++i) {
    open_end = std::max(open_end, open.access(0, i * 64, 64, false, Surface::Depth));
    closed_end = std::max(closed_end, closed.access(0, i * 64, 64, false, Surface::Depth));
  }
  // Open: one activate, then 128 row hits back to back on the bus.
  EXPECT_EQ(open_end, kCtrl + kTrcd + kCl + 128 * kBurst);
  EXPECT_EQ(open.stats().row_hits, 127u);
  // Closed: each request activates bank 0 again after the previous one's data
  // and auto-precharge: the first ends at tRCD + CL + burst, each further one
  // tRP + tRCD + CL + burst later.
  EXPECT_EQ(closed_end, kCtrl + (kTrcd + kCl + kBurst) + 127 * (kTrp + kTrcd + kCl + kBurst));
  EXPECT_EQ(closed.stats().row_hits, 0u);
  EXPECT_EQ(closed.stats().row_misses, 128u);
}

TEST(MemorySystem, RowHitsOfASequentialStreamCountedByHand) {
  // 2 channels, 64 KiB as 1024 requests of 64 B: each channel gets 32 KiB of
  // its local space = 4 rows (banks 0..3, row 0): 8 misses, 1016 hits.
  MemorySystem m(roundConfig(2), kRoundMhz);
  for (uint64_t i = 0; i < 1024; ++i) m.access(i, i * 64, 64, false, Surface::BlendArrays);
  EXPECT_EQ(m.stats().row_misses, 8u);
  EXPECT_EQ(m.stats().row_hits, 1016u);
  EXPECT_EQ(m.stats().requests, 1024u);

  // 1 channel, 128 KiB: row 0 of all 8 banks, then row 1 of all 8 banks.
  MemorySystem one(roundConfig(1), kRoundMhz);
  one.access(0, 0, 128 * 1024, false, Surface::BlendArrays);
  EXPECT_EQ(one.stats().row_misses, 16u);
  EXPECT_EQ(one.stats().row_hits, 2048u - 16u);
}

// tRAS: a row stays open at least tRAS after its activate. Round config with
// tRAS = 28: row 0 of bank 0 opens at 40 (controller), its data ends at 66; a
// conflicting row may start its precharge only at 40 + 28 = 68, not 66.
TEST(MemorySystem, TrasDelaysThePrechargeOfAConflictingRow) {
  for (unsigned tras : {0u, 28u}) {
    DramConfig c = roundConfig(1);
    c.tras = tras;
    MemorySystem m(c, kRoundMhz);
    EXPECT_EQ(m.access(0, 0, 64, false, Surface::Depth), kCtrl + kTrcd + kCl + kBurst);  // 66
    const Cycle pre = tras ? kCtrl + tras : kCtrl + kTrcd + kCl + kBurst;               // 68 or 66
    EXPECT_EQ(m.access(0, 65536, 64, false, Surface::Depth), pre + kTrp + kTrcd + kCl + kBurst) << tras;
  }
}

// Closed page: each request's run re-activates once the previous run's data
// ended and its row was open tRAS, plus tRP. Three requests of one burst to
// one row, tRAS 40: activates at 40, max(66, 80) + 11 = 91 and
// max(117, 131) + 11 = 142; data of the last at 142 + 22 = 164 .. 168. (Without
// tRAS: every step is tRP + tRCD + CL + burst.) As one request of three bursts
// the run activates once: 40 + 22 + 12 = 74.
TEST(MemorySystem, TrasSpacesTheActivatesOfClosedPageRuns) {
  DramConfig c = roundConfig(1);
  c.open_row = false;
  c.tras = 40;
  MemorySystem m(c, kRoundMhz);
  Cycle end = 0;
  for (uint64_t i = 0; i < 3; ++i) end = std::max(end, m.access(0, i * 64, 64, false, Surface::BlendArrays));
  EXPECT_EQ(end, 168u);
  MemorySystem one(c, kRoundMhz);
  EXPECT_EQ(one.access(0, 0, 192, false, Surface::BlendArrays), kCtrl + kTrcd + kCl + 3 * kBurst);
  c.tras = 0;
  MemorySystem none(c, kRoundMhz);
  end = 0;
  for (uint64_t i = 0; i < 3; ++i) end = std::max(end, none.access(0, i * 64, 64, false, Surface::BlendArrays));
  EXPECT_EQ(end, kCtrl + 3 * (kTrcd + kCl + kBurst) + 2 * kTrp);
}

// Two sequential streams a partition region apart (2^36 B) read alternately:
// with the plain map both sit in bank 0 on different rows and every access
// reopens a row; hashed, the second stream is in bank 4 and only the two
// first accesses open one.
TEST(MemorySystem, BankHashKeepsInterleavedStreamsOnTheirOwnRows) {
  for (bool hash : {false, true}) {
    DramConfig c = roundConfig(1);
    c.bank_hash = hash;
    MemorySystem m(c, kRoundMhz);
    const uint64_t other = uint64_t(1) << 36;
    for (uint64_t i = 0; i < 128; ++i) {  // 128 x 64 B = one 8 KiB row per stream
      m.access(i * 100, i * 64, 64, false, Surface::BlendArrays);
      m.access(i * 100 + 50, other + i * 64, 64, false, Surface::BlendArrays);
    }
    EXPECT_EQ(m.bankOf(other), hash ? 4u : 0u);
    EXPECT_EQ(m.stats().row_misses, hash ? 2u : 256u) << (hash ? "hashed" : "plain");
    EXPECT_EQ(m.stats().row_hits, hash ? 254u : 0u) << (hash ? "hashed" : "plain");
  }
}

TEST(MemorySystem, InterleaveSpreadsAStreamEvenly) {
  MemorySystem m(roundConfig(4), kRoundMhz);
  for (uint64_t i = 0; i < 256; ++i) m.access(i, i * 256, 256, false, Surface::BlendArrays);
  // 64 KiB over 4 channels: 16 KiB each = 1024 cycles of bus at 16 B/cycle.
  for (unsigned c = 0; c < 4; ++c) EXPECT_EQ(m.stats().channel_busy[c], 1024u) << "channel " << c;
}

TEST(MemorySystem, OneInterleaveChunkTouchesOneChannel) {
  MemorySystem m(roundConfig(4), kRoundMhz);
  m.access(0, 2 * 256, 256, false, Surface::Depth);
  EXPECT_EQ(m.stats().channel_busy[0], 0u);
  EXPECT_EQ(m.stats().channel_busy[1], 0u);
  EXPECT_EQ(m.stats().channel_busy[2], 4 * kBurst);
  EXPECT_EQ(m.stats().channel_busy[3], 0u);
}

TEST(MemorySystem, BytesBySurfaceAreExact) {
  MemorySystem m(roundConfig(2), kRoundMhz);
  m.access(0, 0, 100, false, Surface::BlendArrays);
  m.access(1, 30, 7, false, Surface::BlendArrays);
  m.access(2, 4096, 2048, true, Surface::BlendArrays);
  m.access(3, 1 << 20, 333, false, Surface::Depth);
  m.access(4, 1 << 21, 64, true, Surface::Colour);
  m.access(5, 1 << 22, 1000, true, Surface::Resolve);
  m.access(6, 1 << 22, 1, false, Surface::Resolve);
  const MemoryStats& s = m.stats();
  EXPECT_EQ(s.read_bytes[unsigned(Surface::BlendArrays)], 107u);
  EXPECT_EQ(s.write_bytes[unsigned(Surface::BlendArrays)], 2048u);
  EXPECT_EQ(s.read_bytes[unsigned(Surface::Depth)], 333u);
  EXPECT_EQ(s.write_bytes[unsigned(Surface::Depth)], 0u);
  EXPECT_EQ(s.write_bytes[unsigned(Surface::Colour)], 64u);
  EXPECT_EQ(s.write_bytes[unsigned(Surface::Resolve)], 1000u);
  EXPECT_EQ(s.read_bytes[unsigned(Surface::Resolve)], 1u);
  EXPECT_EQ(s.readBytes(), 107u + 333u + 1u);
  EXPECT_EQ(s.writeBytes(), 2048u + 64u + 1000u);
  EXPECT_EQ(s.requests, 7u);
}

TEST(MemorySystem, ZeroBytesIsANoOp) {
  MemorySystem m(roundConfig(1), kRoundMhz);
  EXPECT_EQ(m.access(77, 0, 0, false, Surface::Depth), 77u);
  EXPECT_EQ(m.stats().requests, 0u);
  EXPECT_EQ(m.stats().channel_busy[0], 0u);
}

TEST(MemorySystem, EarlierNowQueuesBehindTheBusWithoutGoingBackInTime) {
  MemorySystem m(roundConfig(2), kRoundMhz);
  // 4 KiB from 0 spans both channels: 2 KiB each = 128 bus cycles.
  const Cycle first = m.access(1000, 0, 4096, false, Surface::BlendArrays);
  EXPECT_EQ(first, 1000 + kCtrl + kTrcd + kCl + 128);
  // A request from another partition stamped earlier, same channel and row:
  // its column command can issue once the row is open, but the data bus is
  // booked until `first`: it queues behind, one burst later.
  const Cycle late = m.access(0, 8192, 64, false, Surface::BlendArrays);  // channel 0, local 4096, bank 0 row 0
  ASSERT_EQ(m.channelOf(8192), 0u);
  EXPECT_EQ(late, first + kBurst);
  EXPECT_EQ(m.stats().last_completion, late);
  EXPECT_EQ(m.stats().row_hits, 64u - 2u + 1u);  // 62 hits in the stream, then this one
}

TEST(MemorySystem, EarlierNowOnAnIdleChannelIsNotDelayed) {
  MemorySystem m(roundConfig(2), kRoundMhz);
  const Cycle first = m.access(1000, 0, 256, false, Surface::BlendArrays);  // channel 0 only
  EXPECT_EQ(first, 1000 + kCtrl + kTrcd + kCl + 4 * kBurst);
  EXPECT_EQ(m.access(0, 256, 64, false, Surface::BlendArrays), kCtrl + kTrcd + kCl + kBurst);
  EXPECT_EQ(m.stats().last_completion, first);  // the maximum, not the latest call
}

TEST(MemorySystem, EarlierNowOnABusyBankDoesNotGoBackInTime) {
  MemorySystem m(roundConfig(1), kRoundMhz);
  const Cycle first = m.access(1000, 0, 64, false, Surface::Depth);  // bank 0 row 0
  // Earlier request to bank 0 row 1: the precharge cannot start before row 0
  // was opened and its transfer ended.
  const Cycle late = m.access(0, 65536, 64, false, Surface::Depth);
  EXPECT_EQ(late, first + kTrp + kTrcd + kCl + kBurst);
}

// A request of several bursts inside one interleave chunk that crosses a row
// boundary (row_bytes < interleave_bytes): the chunk's bursts go to two banks.
// Round config, 2 channels, 128 B rows: local [0, 256) of channel 0 is bank 0
// (bursts at 0, 64) and bank 1 (128, 192).
TEST(MemorySystem, ChunkCrossingARowSplitsOverBanks) {
  DramConfig c = roundConfig(2);
  c.row_bytes = 128;
  MemorySystem m(c, kRoundMhz);
  ASSERT_EQ(m.bankOf(64), 0u);
  ASSERT_EQ(m.bankOf(128), 1u);
  ASSERT_EQ(m.channelOf(192), 0u);
  // Both banks activate at 40 + tRCD = 51; bank 0's bursts at 62 and 66, bank
  // 1's wait for the bus: 70 and 74, done at 78.
  EXPECT_EQ(m.access(0, 0, 256, false, Surface::Depth), 78u);
  EXPECT_EQ(m.stats().row_misses, 2u);
  EXPECT_EQ(m.stats().row_hits, 2u);
  EXPECT_EQ(m.stats().channel_busy[0], 16u);
  EXPECT_EQ(m.stats().channel_busy[1], 0u);
  // Bank 1 row 0 is open: a later hit to local 192 pays CL only.
  EXPECT_EQ(m.access(1000, 192, 64, false, Surface::Depth), 1000 + kCtrl + kCl + kBurst);
  EXPECT_EQ(m.stats().row_hits, 3u);
}

// Coarsening (the time series reached stats.max_samples) gives the buckets a
// system sampling at twice the interval from the start would have, also for
// the bursts booked after it.
TEST(MemorySystem, CoarsenedSamplesEqualSamplingAtTwiceTheInterval) {
  MemorySystem fine(roundConfig(2), kRoundMhz), coarse(roundConfig(2), kRoundMhz);
  fine.setSampleInterval(7);
  coarse.setSampleInterval(14);
  testutil::TestLcg rnd{99, 5};
  Cycle now = 0;
  for (int i = 0; i < 400; ++i) {
    if (i == 150 || i == 300) fine.coarsenSamples();  // 7 -> 14 -> 28
    if (i == 300) coarse.coarsenSamples();            // 14 -> 28
    const uint64_t addr = rnd(1 << 16) * 64;
    const uint32_t bytes = uint32_t(64 * (1 + rnd(8)));
    const bool write = rnd(2) == 0;
    EXPECT_EQ(fine.access(now, addr, bytes, write, Surface::BlendArrays),
              coarse.access(now, addr, bytes, write, Surface::BlendArrays));
    now += rnd(40);
  }
  EXPECT_EQ(fine.drainWrites(now), coarse.drainWrites(now));  // the writes still waiting
  EXPECT_EQ(fine.stats().bus_bytes_per_interval, coarse.stats().bus_bytes_per_interval);
  uint64_t sum = 0;
  for (uint64_t b : fine.stats().bus_bytes_per_interval) sum += b;
  EXPECT_GE(sum, fine.stats().readBytes() + fine.stats().writeBytes());  // whole bursts
  EXPECT_GT(fine.stats().bus_bytes_per_interval.size(), 10u);
}

// The bus bytes of a request are bucketed burst by burst by the cycle each
// burst starts on the bus, also when one request's bursts straddle intervals.
TEST(MemorySystem, BusBytesOfOneRequestStraddleIntervals) {
  // Open row, 1 channel: bursts start at 62, 66, 70, 74.
  {
    MemorySystem m(roundConfig(1), kRoundMhz);
    m.setSampleInterval(68);
    m.access(0, 0, 256, false, Surface::Depth);
    EXPECT_EQ(m.stats().bus_bytes_per_interval, (std::vector<uint64_t>{128, 128}));
  }
  {
    MemorySystem m(roundConfig(1), kRoundMhz);
    m.setSampleInterval(7);  // buckets 8, 9, 10, 10
    m.access(0, 0, 256, false, Surface::Depth);
    std::vector<uint64_t> want(11, 0);
    want[8] = 64;
    want[9] = 64;
    want[10] = 128;
    EXPECT_EQ(m.stats().bus_bytes_per_interval, want);
  }
  // Closed page, four requests of one burst: each re-activates after the
  // previous one's data and precharge, 37 cycles apart: starts 62, 99, 136,
  // 173, done at 177.
  {
    DramConfig c = roundConfig(1);
    c.open_row = false;
    MemorySystem m(c, kRoundMhz);
    m.setSampleInterval(50);
    Cycle end = 0;
    for (uint64_t i = 0; i < 4; ++i) end = std::max(end, m.access(0, i * 64, 64, false, Surface::Depth));
    EXPECT_EQ(end, 177u);
    EXPECT_EQ(m.stats().bus_bytes_per_interval, (std::vector<uint64_t>{0, 128, 64, 64}));
    EXPECT_EQ(m.stats().row_misses, 4u);
    EXPECT_EQ(m.stats().row_hits, 0u);
  }
  // igpu timings are fractional: starts 77.625, 83.375, 89.125, 94.875 are in
  // cycles 77, 83, 89, 94.
  {
    MemorySystem m(DramConfig{}, 1150.0);
    m.setSampleInterval(1);
    EXPECT_EQ(m.access(0, 0, 256, false, Surface::Depth), 101u);  // ceil(94.875 + 5.75)
    const auto& bus = m.stats().bus_bytes_per_interval;
    ASSERT_EQ(bus.size(), 95u);
    for (size_t i = 0; i < bus.size(); ++i)
      EXPECT_EQ(bus[i], (i == 77 || i == 83 || i == 89 || i == 94) ? 64u : 0u) << i;
  }
}

TEST(MemorySystem, RejectsInvalidGeometry) {
  DramConfig c = roundConfig(1);
  c.interleave_bytes = 96;  // not a multiple of the burst
  EXPECT_THROW(MemorySystem(c, kRoundMhz), std::invalid_argument);
  c = roundConfig(1);
  c.channels = 0;
  EXPECT_THROW(MemorySystem(c, kRoundMhz), std::invalid_argument);
  c = roundConfig(1);
  EXPECT_THROW(MemorySystem(c, 0.0), std::invalid_argument);
}

TEST(MemorySystem, Deterministic) {
  auto run = [] {
    MemorySystem m(DramConfig{}, 1150.0);
    uint64_t x = 12345, sum = 0;
    for (int i = 0; i < 20000; ++i) {
      x = x * 6364136223846793005ull + 1442695040888963407ull;
      const uint64_t addr = (x >> 20) % (64u << 20);
      const uint32_t bytes = uint32_t(1 + (x >> 50) % 4096);
      sum = sum * 31 + m.access(uint64_t(i) * 3, addr, bytes, (x >> 7) & 1, Surface((x >> 9) & 3));
    }
    return std::pair{sum, m.stats().row_hits};
  };
  EXPECT_EQ(run(), run());
}

// Two callers (partitions a quantum apart) book a saturating stream out of
// time order; the per-interval bus bytes, bucketed by bus time, never exceed
// what the channels can move in an interval (plus one burst per channel that
// starts just before the boundary), and they add up to every burst moved.
TEST(MemorySystem, BusBytesPerIntervalNeverExceedBandwidth) {
  MemorySystem m(roundConfig(2), kRoundMhz);
  constexpr Cycle kInterval = 100;
  m.setSampleInterval(kInterval);
  // B streams one bank ahead of A (local address 8 KiB on), so both mostly hit open rows.
  uint64_t addr_a = 0, addr_b = 16384;
  for (int i = 0; i < 2000; ++i) {
    m.access(Cycle(i) * 2 + 500, addr_a, 256, false, Surface::BlendArrays);  // caller A, ahead
    m.access(Cycle(i) * 2, addr_b, 256, true, Surface::BlendArrays);         // caller B, behind
    addr_a += 256;
    addr_b += 256;
  }
  m.drainWrites(4500);
  const auto& bus = m.stats().bus_bytes_per_interval;
  ASSERT_FALSE(bus.empty());
  uint64_t total = 0;
  for (uint64_t b : bus) {
    EXPECT_LE(b, uint64_t(32.0 * kInterval) + 2 * 64);  // 2 channels x 16 B/cycle
    total += b;
  }
  EXPECT_EQ(total, 2u * 2000u * 256u);
  // The stream saturates the buses: the busiest interval is at least 90% full.
  EXPECT_GE(*std::max_element(bus.begin(), bus.end()), uint64_t(0.9 * 32.0 * kInterval));
}

}  // namespace
}  // namespace oit::rop
