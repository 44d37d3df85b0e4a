// DRAM model: expectations are derived by hand from the formulas in
// oit_rop/memory/MEMORY.md, mostly on a "round" configuration where every timing is a
// whole number of core cycles (1000 MHz core, tCK 1 ns, 16 B per cycle).
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

DramConfig roundConfig(unsigned channels) { return testutil::roundDramConfig(channels); }
using testutil::kBurst;
using testutil::kCl;
using testutil::kCtrl;
using testutil::kRoundMhz;
using testutil::kTrcd;
using testutil::kTrp;

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

// Reference: the per-burst booking of MEMORY.md written out directly (address
// mapping by its formulas, one burst at a time), on the ticks the model uses,
// for a write queue that drains every write at once (dram.write_high = 1,
// write_low = 0, a queue too large to push back): a write is booked when it
// arrives and returns its acceptance (posted); turnarounds tWTR and tRTW apply
// burst by burst.
class ReferenceDram {
 public:
  ReferenceDram(const DramConfig& c, const MemorySystem& m)
      : c_(c),
        ctrl_(ticks(m.controllerCycles())),
        cl_(ticks(m.clCycles())),
        trcd_(ticks(m.trcdCycles())),
        trp_(ticks(m.trpCycles())),
        tras_(ticks(m.trasCycles())),
        burst_(ticks(m.burstCycles())),
        twtr_(ticks(m.twtrCycles())),
        trtw_(ticks(m.trtwCycles())),
        bus_(c.channels, 0),
        last_read_end_(c.channels, 0),
        last_write_end_(c.channels, 0),
        busy_(c.channels, 0),
        banks_(size_t(c.channels) * c.banks) {
    stats_.channel_busy.assign(c.channels, 0);
  }
  void setSampleInterval(Cycle i) { interval_ = i; }
  const MemoryStats& stats() const { return stats_; }

  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) {
    if (bytes == 0) return now;
    (write ? stats_.write_bytes : stats_.read_bytes)[unsigned(s)] += bytes;
    ++stats_.requests;
    ++requests_;
    const uint64_t arrive = (now << 16) + ctrl_;
    uint64_t done = arrive;
    const uint64_t B = c_.burst_bytes, I = c_.interleave_bytes, C = c_.channels, R = c_.row_bytes, K = c_.banks;
    for (uint64_t a = addr / B * B; a < addr + bytes; a += B) {
      const uint64_t ch = (a / I) % C;
      const uint64_t local = a / (I * C) * I + a % I;
      uint64_t bank_index = (local / R) % K;
      const uint64_t row = local / (R * K);
      if (c_.bank_hash) {
        // MEMORY.md: XOR of the row's bank-sized bit groups (K a power of two),
        // else the sum of its base-K digits, mod K.
        const bool pow2 = (K & (K - 1)) == 0;
        for (uint64_t r = row; r != 0; r /= K) bank_index = pow2 ? (bank_index ^ (r % K)) : bank_index + r % K;
        bank_index %= K;
      }
      Bank& k = banks_[ch * K + bank_index];
      uint64_t col;
      if (c_.open_row) {
        if (k.open && k.row == row) {
          ++stats_.row_hits;
          col = std::max(arrive, k.row_ready);
        } else {
          ++stats_.row_misses;
          uint64_t pre = std::max({arrive, k.row_ready, k.last_end});
          if (k.open) pre = std::max(pre, k.act + tras_) + trp_;  // tRAS, then precharge
          k.act = pre;
          k.row_ready = pre + trcd_;
          k.open = true;
          k.row = row;
          col = k.row_ready;
        }
      } else if (k.run_request == requests_ && k.row == row) {
        ++stats_.row_hits;  // closed page: a later burst of the run this request opened
        col = k.row_ready;
      } else {
        ++stats_.row_misses;  // closed page: the bank was precharged after its last run
        k.act = std::max(arrive, k.act_ready);
        k.row_ready = k.act + trcd_;
        k.run_request = requests_;
        k.row = row;
        col = k.row_ready;
      }
      if (!write) col = std::max(col, last_write_end_[ch] + twtr_);  // tWTR
      const uint64_t bus_floor = write ? std::max(bus_[ch], last_read_end_[ch] + trtw_) : bus_[ch];  // tRTW
      const uint64_t start = std::max(col + cl_, bus_floor);
      const uint64_t end = start + burst_;
      bus_[ch] = end;
      (write ? last_write_end_ : last_read_end_)[ch] = end;
      k.last_end = std::max(k.last_end, end);
      if (!c_.open_row) k.act_ready = std::max(k.last_end, k.act + tras_) + trp_;
      if (interval_) {
        const uint64_t bucket = (start >> 16) / interval_;
        if (bucket >= stats_.bus_bytes_per_interval.size()) stats_.bus_bytes_per_interval.resize(bucket + 1, 0);
        stats_.bus_bytes_per_interval[bucket] += B;
      }
      busy_[ch] += burst_;
      stats_.channel_busy[ch] = (busy_[ch] + 0xffff) >> 16;
      if (!write) done = std::max(done, end);  // a write completes when accepted
    }
    const Cycle completion = (done + 0xffff) >> 16;
    stats_.last_completion = std::max(stats_.last_completion, completion);
    return completion;
  }

 private:
  static uint64_t ticks(double cycles) { return uint64_t(std::llround(std::ldexp(cycles, 16))); }
  struct Bank {
    bool open = false;
    uint64_t row = 0, row_ready = 0, last_end = 0, act_ready = 0, act = 0;
    uint64_t run_request = 0;  // closed page: the request whose run has the row open
  };
  uint64_t requests_ = 0;
  DramConfig c_;
  uint64_t ctrl_, cl_, trcd_, trp_, tras_, burst_, twtr_, trtw_;
  std::vector<uint64_t> bus_, last_read_end_, last_write_end_, busy_;
  std::vector<Bank> banks_;
  MemoryStats stats_;
  Cycle interval_ = 0;
};

void expectSameStats(const MemoryStats& got, const MemoryStats& want, const std::string& what) {
  EXPECT_EQ(got.read_bytes, want.read_bytes) << what;
  EXPECT_EQ(got.write_bytes, want.write_bytes) << what;
  EXPECT_EQ(got.requests, want.requests) << what;
  EXPECT_EQ(got.row_hits, want.row_hits) << what;
  EXPECT_EQ(got.row_misses, want.row_misses) << what;
  EXPECT_EQ(got.channel_busy, want.channel_busy) << what;
  EXPECT_EQ(got.last_completion, want.last_completion) << what;
  EXPECT_EQ(got.bus_bytes_per_interval, want.bus_bytes_per_interval) << what;
}

struct Geometry {
  unsigned channels, banks, row_bytes, burst_bytes, interleave_bytes;
};

// Seeded random request streams (unaligned starts, 1 B .. 8 KiB, reads and
// writes, writers slightly out of time order) on regular and odd geometries,
// both row policies and several sample intervals: every completion and every
// stats field equals the burst-by-burst reference.
TEST(MemorySystem, MatchesBurstByBurstReferenceOnRandomStreams) {
  const Geometry geometries[] = {
      {1, 8, 8192, 64, 256},   // igpu-like, 1 channel
      {2, 8, 8192, 64, 256},   // igpu
      {4, 16, 4096, 64, 256},  // dgpu
      {3, 6, 8192, 64, 256},   // non-power-of-two channels and banks
      {2, 5, 320, 64, 192},    // rows of 5 bursts, chunks of 3: chunks cross rows
      {3, 3, 128, 64, 256},    // rows shorter than a chunk
      {4, 7, 96, 32, 96},      // row = chunk, odd everything
      {1, 3, 192, 64, 128},    // one channel, rows not a multiple of the chunk
      {2, 2, 64, 64, 64},      // one burst per row and per chunk
  };
  struct Timing {
    double mhz, gbps, tck, ctrl;
  };
  const Timing timings[] = {{1000.0, 16.0, 1.0, 40.0}, {1150.0, 12.8, 1.25, 40.0}, {1600.0, 56.0, 0.667, 100.0}};
  testutil::TestLcg rnd{0x9e3779b97f4a7c15ull, 17};
  int cases = 0;
  for (const Geometry& g : geometries) {
    for (bool open : {true, false}) {
      for (bool hash : {false, true}) {
        for (Cycle interval : {Cycle(0), Cycle(1), Cycle(7), Cycle(10000)}) {
          const Timing& t = timings[cases % 3];
          DramConfig c;
          c.channels = g.channels;
          c.banks = g.banks;
          c.row_bytes = g.row_bytes;
          c.burst_bytes = g.burst_bytes;
          c.interleave_bytes = g.interleave_bytes;
          c.open_row = open;
          c.bank_hash = hash;
          c.channel_gbps = t.gbps;
          c.tck_ns = t.tck;
          c.controller_ns = t.ctrl;
          c.cl = 11 + unsigned(cases % 5);
          c.trcd = 11;
          c.trp = 9 + unsigned(cases % 7);
          c.twtr = unsigned(cases % 9);  // 0 .. 8 tCK
          c.trtw = unsigned(cases % 4);
          c.write_high = 1;  // every write drains when it arrives
          c.write_low = 0;
          c.write_queue = 1u << 30;  // and never waits for room
          c.scheduler = DramScheduler::Fcfs;  // reads in booking order
          c.trefi_ns = 0;                     // the reference has no refresh
          MemorySystem m(c, t.mhz);
          ReferenceDram ref(c, m);
          m.setSampleInterval(interval);
          ref.setSampleInterval(interval);
          const std::string what = std::to_string(g.channels) + " ch " + std::to_string(g.banks) + " banks row " +
                                   std::to_string(g.row_bytes) + " il " + std::to_string(g.interleave_bytes) +
                                   (open ? " open" : " closed") + (hash ? " hashed" : "") + " interval " +
                                   std::to_string(interval);
          // A small address range (many row hits and conflicts) or a large one.
          const uint64_t range = (cases % 2) ? (uint64_t(1) << 20) : (uint64_t(1) << 34);
          Cycle now = 0;
          uint64_t addr = 0;
          uint32_t bytes = 1;
          for (int i = 0; i < 3000; ++i) {
            const uint64_t kind = rnd(12);
            // 10: streaming on from the previous request, 11: the same address again.
            if (kind == 10)
              addr += bytes;
            else if (kind == 9)
              addr = rnd(range) / 2048 * 2048;
            else if (kind != 11)
              addr = rnd(range);
            if (kind < 3)
              bytes = uint32_t(1 + rnd(64));
            else if (kind < 6)
              bytes = uint32_t(1 + rnd(8192));
            else
              bytes = uint32_t(64) << rnd(6);  // 64 B .. 2 KiB
            // Mostly forward in time, bursty, sometimes a writer up to a quantum
            // behind. (Reads stay in time order: with FCFS a read that arrived
            // before an earlier booking may take the bus time it left idle,
            // which the reference does not model; test_dram_scheduler.cpp has
            // that.)
            const bool write = rnd(2) == 1;
            const Cycle at = write && rnd(4) == 0 ? now - std::min<Cycle>(now, rnd(1000)) : now;
            now += rnd(4) == 0 ? rnd(400) : 0;
            const Surface s = Surface(rnd(kSurfaceCount));
            const Cycle want = ref.access(at, addr, bytes, write, s);
            ASSERT_EQ(m.access(at, addr, bytes, write, s), want) << what << ", request " << i;
          }
          expectSameStats(m.stats(), ref.stats(), what);
          // A change of interval on the way keeps the series consistent too.
          if (interval) {
            m.setSampleInterval(interval * 3);
            ref.setSampleInterval(interval * 3);
            for (int i = 0; i < 200; ++i) {
              addr = rnd(range);
              bytes = uint32_t(1 + rnd(4096));
              EXPECT_EQ(m.access(now + Cycle(i), addr, bytes, false, Surface::Colour),
                        ref.access(now + Cycle(i), addr, bytes, false, Surface::Colour))
                  << what;
            }
            expectSameStats(m.stats(), ref.stats(), what + " (interval changed)");
          }
          EXPECT_GT(m.stats().row_misses, 0u) << what;
          if (open) {
            EXPECT_GT(m.stats().row_hits, 0u) << what;
          }
          ++cases;
        }
      }
    }
  }
  EXPECT_EQ(cases, 9 * 2 * 2 * 4);
}

// ---- Refresh (dram.trefi_ns / trfc_ns) on the round configuration ----
// One channel, tREFI 1000 cycles, tRFC 100: windows [1000, 1100), [2000, 2100) ...
DramConfig refreshConfig(unsigned channels) {
  DramConfig c = roundConfig(channels);
  c.trefi_ns = 1000;
  c.trfc_ns = 100;
  return c;
}

TEST(MemorySystem, RefreshLeavesTimesBeforeTheFirstWindow) {
  // On by default with DDR3's JEDEC values (7.8 us, 4 Gb: 260 ns).
  EXPECT_EQ(DramConfig{}.trefi_ns, 7800.0);
  EXPECT_EQ(DramConfig{}.trfc_ns, 260.0);
  MemorySystem m(refreshConfig(1), kRoundMhz);
  // Before the first window nothing changes: closed bank, then a row hit.
  EXPECT_EQ(m.access(0, 0, 64, false, Surface::Depth), kCtrl + kTrcd + kCl + kBurst);   // 66
  EXPECT_EQ(m.access(900, 64, 64, false, Surface::Depth), 900 + kCtrl + kCl + kBurst);  // 955, ends before 1000
  EXPECT_EQ(m.stats().row_hits, 1u);
}

TEST(MemorySystem, ARunMeetingARefreshWaitsForItsEndOnAClosedRow) {
  MemorySystem m(refreshConfig(1), kRoundMhz);
  EXPECT_EQ(m.access(0, 0, 64, false, Surface::Depth), 66u);  // row 0 of bank 0 open
  // A row hit at 950 would put its data on the bus at 1001-1005, inside the
  // window [1000, 1100): it waits for the window's end, and the refresh closed
  // the row: activate at 1100, data at 1100 + tRCD + CL, done 4 cycles later.
  EXPECT_EQ(m.access(950, 64, 64, false, Surface::Depth), 1100 + kTrcd + kCl + kBurst);  // 1126
  EXPECT_EQ(m.stats().row_hits, 0u);
  EXPECT_EQ(m.stats().row_misses, 2u);
  EXPECT_EQ(m.stats().channel_busy[0], 2 * kBurst);  // the window is not busy time
}

TEST(MemorySystem, ARefreshBetweenTwoAccessesClosesTheRowWithoutAPrecharge) {
  MemorySystem m(refreshConfig(1), kRoundMhz);
  EXPECT_EQ(m.access(0, 0, 64, false, Surface::Depth), 66u);
  // After the window: the row is closed (a miss), but the refresh precharged
  // the bank: tRCD + CL, no tRP.
  EXPECT_EQ(m.access(1200, 64, 64, false, Surface::Depth), 1200 + kCtrl + kTrcd + kCl + kBurst);
  // Opened after the window: the next access hits.
  EXPECT_EQ(m.access(1300, 128, 64, false, Surface::Depth), 1300 + kCtrl + kCl + kBurst);
  EXPECT_EQ(m.stats().row_hits, 1u);
  EXPECT_EQ(m.stats().row_misses, 2u);
  // A request arriving inside a window waits for its end.
  EXPECT_EQ(m.access(1950, 192, 64, false, Surface::Depth), 2100 + kTrcd + kCl + kBurst);
}

TEST(MemorySystem, RefreshWindowsAreStaggeredOverChannels) {
  // Two channels: channel 0 refreshes at 1000, 2000 ..., channel 1 at 1500, 2500 ...
  MemorySystem m(refreshConfig(2), kRoundMhz);
  ASSERT_EQ(m.channelOf(0), 0u);
  ASSERT_EQ(m.channelOf(256), 1u);
  // At 1450 on channel 0: activate 1490, data 1512-1516, between its windows.
  EXPECT_EQ(m.access(1450, 0, 64, false, Surface::Depth), 1450 + kCtrl + kTrcd + kCl + kBurst);
  // The same on channel 1 meets its window [1500, 1600).
  EXPECT_EQ(m.access(1450, 256, 64, false, Surface::Depth), 1600 + kTrcd + kCl + kBurst);
}

// A stream of B bytes takes at least B / bandwidth / (1 - tRFC / tREFI), and
// at most that with every window also costing a re-activation and one burst.
TEST(MemorySystem, RefreshTakesItsShareOfTheBandwidth) {
  constexpr uint64_t kBursts = 4096;
  const auto streamEnd = [&](const DramConfig& c) {
    MemorySystem m(c, kRoundMhz);
    Cycle done = 0;
    for (uint64_t i = 0; i < kBursts; ++i) done = std::max(done, m.access(0, i * 64, 64, false, Surface::BlendArrays));
    EXPECT_EQ(m.stats().channel_busy[0], kBursts * kBurst);
    return done;
  };
  const double busy = double(kBursts * kBurst);  // 16,384 cycles of data
  const Cycle plain = streamEnd(roundConfig(1));
  EXPECT_LE(plain, Cycle(busy) + kCtrl + kTrcd + kCl + 64);
  const Cycle refreshed = streamEnd(refreshConfig(1));
  const double period = 1000, rfc = 100, per_window = rfc + kTrcd + kCl + kBurst;
  EXPECT_GE(double(refreshed), busy * period / (period - rfc));                  // >= 18,204
  EXPECT_LE(double(refreshed), busy * period / (period - per_window) + period);  // <= 19,746
}

// Closed page: a request's run is placed whole between two refreshes, like an
// open-row run on a closed bank.
TEST(MemorySystem, ClosedPageRunMeetingARefreshWaitsForItsEnd) {
  DramConfig c = refreshConfig(1);
  c.open_row = false;
  DramConfig plain = c;
  plain.trefi_ns = plain.trfc_ns = 0;
  // Two bursts at 940: the run activates at 980, its data would be on the bus
  // at 1002-1010, inside [1000, 1100): it activates at 1100 instead.
  MemorySystem m(c, kRoundMhz), p(plain, kRoundMhz);
  EXPECT_EQ(p.access(940, 0, 128, false, Surface::Depth), 980 + kTrcd + kCl + 2 * kBurst);   // 1010 without refresh
  EXPECT_EQ(m.access(940, 0, 128, false, Surface::Depth), 1100 + kTrcd + kCl + 2 * kBurst);  // 1130
  EXPECT_EQ(m.stats().row_misses, 1u);
  EXPECT_EQ(m.stats().row_hits, 1u);
  EXPECT_EQ(m.stats().channel_busy[0], 2 * kBurst);
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
