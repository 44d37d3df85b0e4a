// The DRAM controller's read scheduling (dram.scheduler, dram.queue_depth;
// MEMORY.md, "scheduling"): a read may take bus time an older booking left
// idle, never moving it. Hand-derived on the round configuration
// (DramTestConfig.hpp: 1 cycle = 1 tCK, burst 4, controller 40, CL = tRCD =
// tRP = 11, tRAS 0), and on the dgpu DRAM against bounds.
#include <gtest/gtest.h>

#include <algorithm>
#include <functional>
#include <queue>
#include <string>
#include <vector>

#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/memory/DramTestConfig.hpp"
#include "oit_rop/memory/MemorySystem.hpp"

namespace oit::rop {
namespace {

using testutil::kBurst;
using testutil::kCl;
using testutil::kCtrl;
using testutil::gddr5FourChannels;
using testutil::kRoundMhz;
using testutil::kTrcd;
using testutil::kTrp;

DramConfig roundWith(DramScheduler s, unsigned queue_depth = 64) {
  DramConfig c = testutil::roundDramConfig(1);
  c.scheduler = s;
  c.queue_depth = queue_depth;
  return c;
}

// Bank 0 row 0 and bank 1 row 0 open (reads at 0: data 62-66 and 66-70).
// At 100 a read of bank 0 row 1: precharge at 140, activate 151, data 173-177;
// the bus idles from 70 to 173. At 101 a read hitting bank 1's open row could
// have its data at 141 + CL = 152:
// - FR-FCFS takes the idle bus: 152-156;
// - FCFS keeps arrival order: after the row miss, 177-181.
Cycle hitAfterMiss(DramConfig c, bool one_more = false) {
  MemorySystem m(c, kRoundMhz);
  EXPECT_EQ(m.access(0, 0, 64, false, Surface::BlendArrays), 66u);
  EXPECT_EQ(m.access(0, 8192, 64, false, Surface::BlendArrays), 70u);
  EXPECT_EQ(m.access(100, 65536, 64, false, Surface::BlendArrays), 177u);  // bank 0 row 1
  // With one_more, a read of bank 0 row 2 after it: precharge once the miss's
  // data ended (177), data 210-214; the bus idles 177-210 before it.
  if (one_more) {
    EXPECT_EQ(m.access(100, 2 * 65536, 64, false, Surface::BlendArrays), 214u);
  }
  return m.access(101, 8192 + 64, 64, false, Surface::BlendArrays);
}

TEST(DramScheduler, ARowHitTakesTheBusARowMissLeavesIdle) {
  EXPECT_EQ(hitAfterMiss(roundWith(DramScheduler::FrFcfs)), 101 + kCtrl + kCl + kBurst);  // 156
  EXPECT_EQ(hitAfterMiss(roundWith(DramScheduler::Fcfs)), 181u);
  // The window counts the bursts booked since the idle time was left (the
  // miss's own one, then the extra read's): a read may pass fewer than
  // queue_depth. queue_depth 1 is FCFS; with the extra read, queue_depth 2
  // lets the hit pass only the extra read (177-181), 3 both (152-156).
  EXPECT_EQ(hitAfterMiss(roundWith(DramScheduler::FrFcfs, 1)), 181u);
  EXPECT_EQ(hitAfterMiss(roundWith(DramScheduler::FrFcfs, 2), true), 181u);
  EXPECT_EQ(hitAfterMiss(roundWith(DramScheduler::FrFcfs, 3), true), 156u);
}

// First come, first served by arrival: a read stamped at 90 (a partition
// behind inside its quantum, booked after the miss stamped at 100) arrived
// first, so FCFS serves it in the idle bus time: data 141-145. One stamped at
// 101 came after the miss and waits for it.
TEST(DramScheduler, FcfsServesAReadThatArrivedFirstInIdleBusTime) {
  MemorySystem m(roundWith(DramScheduler::Fcfs), kRoundMhz);
  m.access(0, 0, 64, false, Surface::BlendArrays);
  m.access(0, 8192, 64, false, Surface::BlendArrays);
  EXPECT_EQ(m.access(100, 65536, 64, false, Surface::BlendArrays), 177u);
  EXPECT_EQ(m.access(90, 8192 + 64, 64, false, Surface::BlendArrays), 90 + kCtrl + kCl + kBurst);  // 145
  EXPECT_EQ(m.access(101, 8192 + 128, 64, false, Surface::BlendArrays), 181u);
}

// A read in idle bus time after a write waits tWTR + CL after the write's
// data. Bank 0 row 0 read at 0 (62-66), a write to bank 1 row 0 written at
// once (write_high 1): tRTW after the read, 68-72. At 100 the row miss of
// bank 0 (data 173-177) leaves 72-173 idle after the write. A read of bank 1's
// row stamped at 30 (arrived first) could have data at 70 + CL = 81, but tWTR
// 6 + CL 11 after the write's end puts it at 89-93 (tWTR 0: 83-87).
TEST(DramScheduler, AReadInIdleBusTimeKeepsTheWriteToReadTurnaround) {
  for (unsigned twtr : {6u, 0u}) {
    DramConfig c = roundWith(DramScheduler::Fcfs);
    c.twtr = twtr;
    c.trtw = 2;
    c.write_high = 1;
    c.write_low = 0;
    MemorySystem m(c, kRoundMhz);
    EXPECT_EQ(m.access(0, 0, 64, false, Surface::BlendArrays), 66u);
    EXPECT_EQ(m.access(0, 8192, 64, true, Surface::BlendArrays), kCtrl);  // posted, written at once
    EXPECT_EQ(m.access(100, 65536, 64, false, Surface::BlendArrays), 177u);
    EXPECT_EQ(m.access(30, 8192 + 64, 64, false, Surface::BlendArrays), 72 + twtr + kCl + kBurst) << twtr;
  }
}

// A closed loop of W reads in flight (like a cache's miss queue): each read
// is issued when the oldest in flight completes. One read in G opens a new
// row in one of 15 other banks (a row miss, the bank's last activate long
// ago), the others hit bank 0's open row. Unloaded latencies: a hit ctrl +
// CL + burst (round: 55), a miss ctrl + tRP + tRCD + CL + burst (77). Each
// slot serves its reads one after another, so the N reads take at least
// sum(latency) / W (the latency bound):
// - FR-FCFS: hits do not wait for the miss ahead of them, within 3 % of it;
// - FCFS: every hit issued behind a miss completes after it, so each
//   window of W reads (each holds a miss) takes the miss's latency: N / W x 77.
Cycle closedLoop(const DramConfig& c, double mhz, unsigned w, unsigned g, unsigned n) {
  MemorySystem m(c, mhz);
  std::priority_queue<Cycle, std::vector<Cycle>, std::greater<Cycle>> slots;
  for (unsigned i = 0; i < w; ++i) slots.push(0);
  Cycle end = 0;
  unsigned misses = 0;
  for (unsigned i = 0; i < n; ++i) {
    const Cycle t = slots.top();
    slots.pop();
    uint64_t addr = uint64_t(i % (c.row_bytes / 64)) * 64;  // bank 0, row 0
    if (i % g == 0) {
      const uint64_t bank = 1 + misses % 15, row = 1 + (misses / 15) % 2;  // alternate rows: a miss each time
      addr = (row * c.banks + bank) * c.row_bytes;
      ++misses;
    }
    const Cycle done = m.access(t, addr, 64, false, Surface::BlendArrays);
    end = std::max(end, done);
    slots.push(done);
  }
  EXPECT_EQ(m.stats().row_misses, uint64_t(misses) + 1);  // and bank 0's first activate
  return end;
}

TEST(DramScheduler, ClosedLoopOfReadsWithRowMisses) {
  constexpr unsigned kW = 8, kG = 4, kN = 4800;
  DramConfig c = roundWith(DramScheduler::FrFcfs);
  c.banks = 16;
  const double hit = kCtrl + kCl + kBurst, miss = kCtrl + kTrp + kTrcd + kCl + kBurst;  // 55, 77
  const double bound = kN * ((kG - 1) * hit + miss) / kG / kW;                         // 36,300
  const double fr = double(closedLoop(c, kRoundMhz, kW, kG, kN));
  EXPECT_GE(fr, bound);
  EXPECT_LE(fr, bound * 1.03);
  c.scheduler = DramScheduler::Fcfs;
  const double fcfs = double(closedLoop(c, kRoundMhz, kW, kG, kN));
  EXPECT_GE(fcfs, bound);
  EXPECT_NEAR(fcfs, double(kN) / kW * miss, 0.01 * double(kN) / kW * miss);  // 46,200: 41.6 % of the bus busy
  // The dgpu DRAM (one channel, no refresh): ctrl 121.6, tRP = tRCD = CL =
  // 19.47, burst 1.39 cycles; a miss bank's last activate is over tRAS ago.
  // 64 reads in flight: latency bound 45,656 cycles, FCFS N / W x miss =
  // 54,416 (48.8 % of the bus busy), FR-FCFS 57.8 %.
  RopConfig d = gddr5FourChannels();  // the dgpu of these figures
  d.dram.channels = 1;
  d.dram.trefi_ns = d.dram.trfc_ns = 0;
  d.dram.bank_hash = false;
  MemorySystem probe(d.dram, d.clock.core_mhz);
  const double dhit = probe.controllerCycles() + probe.clCycles() + probe.burstCycles();
  const double dmiss = dhit + probe.trpCycles() + probe.trcdCycles();
  const double dbound = 19200.0 * ((kG - 1) * dhit + dmiss) / kG / 64;
  const double dfr = double(closedLoop(d.dram, d.clock.core_mhz, 64, kG, 19200));
  EXPECT_GE(dfr, dbound);
  EXPECT_LE(dfr, dbound * 1.03);
  d.dram.scheduler = DramScheduler::Fcfs;
  const double dfcfs = double(closedLoop(d.dram, d.clock.core_mhz, 64, kG, 19200));
  EXPECT_NEAR(dfcfs, 19200.0 / 64 * dmiss, 0.01 * 19200.0 / 64 * dmiss);
  EXPECT_LT(dfr, dfcfs * 0.9);
}

// A mixed stream on the dgpu's four channels: 2 KiB lines read and written
// back alternately (a tile's fill and a victim's write-back), all issued at
// once; reads in one region, writes in another (banks 8 apart). Each line is
// 8 bursts per channel. Per channel, with first = ctrl + tRCD + CL, b = burst,
// r2w = tRTW, w2r = tWTR + CL:
// (dgpu: first 160.53, b 1.3897, r2w 1.6221, w2r 25.954 cycles.)
// - an FCFS controller writing each write when it comes: every line pair
//   switches twice, end = first + N (16 b + r2w) + (N - 1) w2r = 15,327:
//   44.2 % of the bus busy (the issue quotes 58 % for an FCFS controller on
//   a mixed stream);
// - the presets' controller (FR-FCFS, write queue 64/56/32): at 56 waiting
//   bursts it writes 3 lines (down to 32), at lines 7, 10, ..., 304 of 305
//   (100 batches with reads after them), then 40 bursts at the drain after
//   the last read: end = first + 16 N b + 101 r2w + 100 w2r = 9,702: 69.9 %.
TEST(DramScheduler, MixedReadWriteLinesOnTheDgpuChannels) {
  RopConfig d = gddr5FourChannels();  // the dgpu of these figures
  d.dram.trefi_ns = d.dram.trfc_ns = 0;
  d.dram.bank_hash = false;
  constexpr unsigned kLines = 305;
  const uint64_t writes = (uint64_t(1) << 26) + 8 * 4096 * 4;  // +16 MiB local: row + 256, bank + 8
  auto end = [&](const DramConfig& c) {
    MemorySystem m(c, d.clock.core_mhz);
    Cycle e = 0;
    for (unsigned i = 0; i < kLines; ++i) {
      e = std::max(e, m.access(0, uint64_t(i) * 2048, 2048, false, Surface::BlendArrays));
      m.access(0, writes + uint64_t(i) * 2048, 2048, true, Surface::BlendArrays);
    }
    e = std::max(e, m.drainWrites(0));
    const double busy = double(m.stats().channel_busy[0]) / double(e);
    EXPECT_EQ(m.stats().channel_busy[0], m.stats().channel_busy[3]);
    return std::pair{double(e), busy};
  };
  MemorySystem probe(d.dram, d.clock.core_mhz);
  const double b = probe.burstCycles(), r2w = probe.trtwCycles(), w2r = probe.twtrCycles() + probe.clCycles();
  const double first = probe.controllerCycles() + probe.trcdCycles() + probe.clCycles();
  DramConfig fcfs = d.dram;
  fcfs.scheduler = DramScheduler::Fcfs;
  fcfs.write_high = 1;
  fcfs.write_low = 0;
  const auto [fcfs_end, fcfs_busy] = end(fcfs);
  const double fcfs_bound = first + kLines * (16 * b + r2w) + (kLines - 1) * w2r;
  EXPECT_GE(fcfs_end, fcfs_bound);
  EXPECT_LE(fcfs_end, fcfs_bound * 1.03);
  EXPECT_LT(fcfs_busy, 0.45);
  const auto [full_end, full_busy] = end(d.dram);
  const double full_bound = first + 16 * kLines * b + 101 * r2w + 100 * w2r;
  EXPECT_GE(full_end, full_bound);
  EXPECT_LE(full_end, full_bound * 1.03);
  EXPECT_GT(full_busy, 0.68);
}

}  // namespace
}  // namespace oit::rop
