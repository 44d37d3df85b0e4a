// The activate-rate limits (dram.trrd, dram.tfaw; MEMORY.md "Activate limits"):
// the window's placement rule, and streams against bounds derived by hand. On
// the round configuration (DramTestConfig.hpp: 1 tCK = 1 core cycle, 64 B
// burst = 4 cycles, controller 40, CL = tRCD = tRP = 11, tRAS 0, no refresh)
// the controller meets each bound exactly; on the presets' DRAM within 3 %
// above it, never below.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/memory/DramActivateWindow.hpp"
#include "oit_rop/memory/DramTestConfig.hpp"
#include "oit_rop/memory/MemorySystem.hpp"

namespace oit::rop {
namespace {

using testutil::kBurst;
using testutil::kCl;
using testutil::kCtrl;
using testutil::kRoundMhz;
using testutil::kTrcd;
using testutil::kTrp;
using testutil::roundDramConfig;

// --- DramActivateWindow (ticks are plain numbers here) ---

TEST(DramActivateWindow, InOrderIsLastPlusTrrdAndFourthLastPlusTfaw) {
  DramActivateWindow w(10, 50);
  EXPECT_EQ(w.earliest(7), 7u);  // nothing yet
  for (uint64_t t : {0, 10, 20, 30}) {
    ASSERT_EQ(w.earliest(t), t);
    w.record(t);
  }
  EXPECT_EQ(w.earliest(31), 50u);  // the fifth: 0 + tFAW (tRRD alone would allow 40)
  w.record(50);
  EXPECT_EQ(w.earliest(50), 60u);  // 50 + tRRD; the window 10..50 holds four, 10 + 50 = 60 too
  EXPECT_EQ(w.earliest(1000), 1000u);
}

TEST(DramActivateWindow, NoLimitsNeverMoves) {
  DramActivateWindow w(0, 0);
  EXPECT_FALSE(w.limited());
  w.record(5);
  w.record(5);
  EXPECT_EQ(w.earliest(5), 5u);
  EXPECT_EQ(w.size(), 0u);  // nothing is kept
}

// Booked out of time order (a partition behind inside its quantum): the
// activate goes into the time before the latest ones if both limits allow it
// there, else after them.
TEST(DramActivateWindow, AnEarlierActivateFitsBeforeTheLatestOnesWhenTheLimitsAllow) {
  DramActivateWindow w(10, 50);
  for (uint64_t t : {100, 110, 120, 130}) w.record(t);
  EXPECT_EQ(w.earliest(40), 40u);  // five activates 40..130 span 90 >= 50
  EXPECT_EQ(w.earliest(79), 79u);  // 79..130: 51 >= 50, and 79 + 10 <= 100
  EXPECT_EQ(w.earliest(80), 80u);  // exactly tFAW: allowed
  // 81..130 would be five in 49 < tFAW; 91..99 also within tRRD of 100; every
  // tick up to 140 is within tRRD of one of them, 140 makes 100..140 five in
  // 40: the first allowed tick is 100 + tFAW = 150.
  EXPECT_EQ(w.earliest(81), 150u);
  EXPECT_EQ(w.earliest(95), 150u);
  DramActivateWindow r(10, 0);  // tRRD only: a hole of 2 x tRRD between two activates takes one
  r.record(100);
  r.record(120);
  EXPECT_EQ(r.earliest(105), 110u);
  EXPECT_EQ(r.earliest(111), 130u);
}

// It keeps the latest kKeep (64) activates by time: 100 of them 2 apart (100
// .. 298), tRRD 1: 172 .. 298 are kept, so 172 is taken and 173 free; an
// activate asked for before all of them goes no earlier than the oldest kept
// (the time before is taken as full: 170 -> 173), and one recorded there is
// dropped.
TEST(DramActivateWindow, RemembersTheLatestByTime) {
  DramActivateWindow w(1, 0);
  for (uint64_t t = 0; t < 100; ++t) w.record(100 + 2 * t);
  EXPECT_EQ(w.size(), DramActivateWindow::kKeep);
  EXPECT_EQ(w.earliest(172), 173u);
  EXPECT_EQ(w.earliest(171), 173u);
  EXPECT_EQ(w.earliest(170), 173u);
  EXPECT_EQ(w.earliest(175), 175u);
  w.record(50);
  EXPECT_EQ(w.size(), DramActivateWindow::kKeep);
  EXPECT_EQ(w.earliest(60), 173u);
}

// --- The controller ---

struct ReadRequest {
  uint64_t addr;
  uint32_t bytes;
};

// Books every read at cycle 0 (a deep queue); returns the cycle the last data
// is on the bus.
Cycle readStreamEnd(MemorySystem& m, const std::vector<ReadRequest>& rs) {
  Cycle end = 0;
  for (const ReadRequest& r : rs) end = std::max(end, m.access(0, r.addr, r.bytes, false, Surface::BlendArrays));
  return end;
}

// N one-burst reads rotating over the first `used` of a channel's `banks`
// banks, each visit to a new row (plain map: bank b, row r at (r x banks + b)
// x row_bytes).
std::vector<ReadRequest> overBanks(unsigned n, unsigned used, unsigned banks, unsigned row_bytes) {
  std::vector<ReadRequest> rs;
  for (unsigned i = 0; i < n; ++i) rs.push_back({(uint64_t(i / used) * banks + i % used) * row_bytes, 64});
  return rs;
}

// The round configuration on one channel, closed page, with these limits.
DramConfig closedPage(unsigned trrd, unsigned tfaw) {
  DramConfig c = roundDramConfig(1);
  c.open_row = false;
  c.trrd = trrd;
  c.tfaw = tfaw;
  return c;
}

// A closed-page stream over all 8 banks: every read activates its bank. Without
// limits a bank's chain (tRCD + CL + burst + tRP = 37) over 8 banks allows an
// activate every 4.625 cycles, the bus a burst every 4: 800 reads end at
// ctrl + tRCD + CL + 4 + 99 x 37 + 7 x 4.625, i.e. they are bank-bound at
// ctrl + 26 + 99 x 37 + ... (checked as the limits-off reference below). With
// tRRD 4 and tFAW 40 the channel activates four times in 12 cycles and waits
// for the window: activate k at ctrl + 40 floor(k / 4) + 4 (k mod 4) (each
// bank is reused 8 activates = 80 cycles later, long ready; the bursts are 4
// apart: no bus wait), its data ending tRCD + CL + burst = 26 later. k = 799:
// 40 + 40 x 199 + 12 + 26 = 8,038 cycles: 4 reads per 40 cycles, the bus
// 40 % busy.
TEST(DramActivateLimits, ClosedPageOverAllBanksIsFourActivatesPerTfaw) {
  DramConfig c = closedPage(4, 40);
  MemorySystem m(c, kRoundMhz);
  EXPECT_EQ(readStreamEnd(m, overBanks(800, 8, c.banks, c.row_bytes)), kCtrl + 40 * 199 + 3 * 4 + kTrcd + kCl + kBurst);
  EXPECT_EQ(m.stats().row_misses, 800u);
  // Off, the banks bound it: 800 reads, 100 per bank, a bank's activates 37
  // apart: bank 7's last at 7 x 4 + 99 x 37 after the first (the first
  // activates 4 apart behind the bus), ending 26 later: 40 + 28 + 3,663 + 26.
  c.trrd = c.tfaw = 0;
  MemorySystem off(c, kRoundMhz);
  EXPECT_EQ(readStreamEnd(off, overBanks(800, 8, c.banks, c.row_bytes)), kCtrl + 7 * kBurst + 99 * (kTrcd + kCl + kBurst + kTrp) +
                                                                    kTrcd + kCl + kBurst);
}

// Two banks in turn, closed page: a bank's chain (37) allows an activate every
// 18.5 cycles over the two, tRRD = 20 only every 20: activate k at ctrl + 20 k,
// data ending 26 later; k = 499: 40 + 9,980 + 26 = 10,046. The same stream
// open-row, each read to a new row of its bank (row misses): a bank's chain is
// then its precharge, activate and data (tRP + tRCD + CL + burst = 37 from the
// previous data's end... its activates 11 + 26 = 37 apart), again under 2 x 20:
// tRRD bounds it too, activate k at ctrl + 20 k, the first without tRP.
TEST(DramActivateLimits, TwoBankAlternationIsOneActivatePerTrrd) {
  DramConfig c = closedPage(20, 0);
  MemorySystem closed(c, kRoundMhz);
  EXPECT_EQ(readStreamEnd(closed, overBanks(500, 2, c.banks, c.row_bytes)), kCtrl + 20 * 499 + kTrcd + kCl + kBurst);
  c.open_row = true;
  MemorySystem open(c, kRoundMhz);
  EXPECT_EQ(readStreamEnd(open, overBanks(500, 2, c.banks, c.row_bytes)), kCtrl + 20 * 499 + kTrcd + kCl + kBurst);
  EXPECT_EQ(open.stats().row_misses, 500u);
}

// Limits that never bind give the very same bookings: the 16-bank open-row
// stream is bus-bound (a burst, and so an activate, every 4 cycles), so
// tRRD 4 and tFAW 16 (the fifth activate 16 after the first) hold already; a
// row-hit stream activates once.
TEST(DramActivateLimits, LimitsThatDoNotBindChangeNothing) {
  DramConfig c = roundDramConfig(1);
  c.banks = 16;
  std::vector<ReadRequest> rs = overBanks(1600, 16, c.banks, c.row_bytes);
  for (unsigned i = 0; i < 400; ++i) rs.push_back({uint64_t(i % 128) * 64, 64});  // then row hits in bank 0
  MemorySystem off(c, kRoundMhz);
  std::vector<Cycle> want;
  for (const ReadRequest& r : rs) want.push_back(off.access(0, r.addr, r.bytes, false, Surface::BlendArrays));
  c.trrd = 4;
  c.tfaw = 16;
  MemorySystem on(c, kRoundMhz);
  for (size_t i = 0; i < rs.size(); ++i)
    ASSERT_EQ(on.access(0, rs[i].addr, rs[i].bytes, false, Surface::BlendArrays), want[i]) << "request " << i;
  EXPECT_EQ(on.stats().row_misses, off.stats().row_misses);
  EXPECT_EQ(want[1599], kCtrl + kTrcd + kCl + 1600 * kBurst);  // bus-bound, as without limits
}

// The presets' DRAM on one channel, closed page, refresh off, one-burst reads
// over every bank: the bound is the largest of the bus (N bursts), a bank's
// chain (its activates max(tRCD + CL + burst, tRAS) + tRP apart) and the
// activate limits (activate k no earlier than max(k tRRD, floor(k / 4) tFAW)
// after the first), plus the first read's tRCD + CL + burst. iris-pro-5200
// (DDR3-1600 at 1150 MHz: burst 5.75 cycles, tRRD 5 tCK = 7.1875, tFAW 24 tCK
// = 34.5: 8.625 per activate): tFAW binds, the bus at most 5.75 / 8.625 = 67 %
// busy. titan-x-maxwell (GDDR5 at 1075 MHz: burst 1.23 cycles, tRRD 9 tCK =
// 6.45 cycles, tFAW = 4 tRRD): 19 % of the bus. navi21 (GDDR6 at 2015 MHz:
// burst 2.015 cycles, tRRD 8 tCK = 8.06, tFAW = 4 tRRD): 25 %. (Each bank is
// reused after `banks` activates, later than its chain allows.)
TEST(DramActivateLimits, PresetsClosedPageIsBoundByTheActivateWindow) {
  for (const char* preset : {"iris-pro-5200", "titan-x-maxwell", "navi21"}) {
    RopConfig rc = presetConfig(preset);
    DramConfig d = rc.dram;
    d.channels = 1;
    d.trefi_ns = d.trfc_ns = 0;
    d.bank_hash = false;
    d.open_row = false;
    MemorySystem m(d, rc.clock.core_mhz);
    ASSERT_GT(m.tfawCycles(), 0.0) << preset;
    const unsigned n = 100 * d.banks;
    const double k = n - 1;
    const double burst = m.burstCycles();
    const double chain = std::max(m.trcdCycles() + m.clCycles() + burst, m.trasCycles()) + m.trpCycles();
    const double acts = std::max(k * m.trrdCycles(), double((n - 1) / 4) * m.tfawCycles());
    const double bound = m.controllerCycles() + m.trcdCycles() + m.clCycles() + burst +
                         std::max({k * burst, 99 * chain, acts});
    EXPECT_EQ(acts, std::max({k * burst, 99 * chain, acts})) << preset << ": the window binds";
    const double got = double(readStreamEnd(m, overBanks(n, d.banks, d.banks, d.row_bytes)));
    EXPECT_GE(got, bound) << preset;
    EXPECT_LE(got, 1.03 * bound) << preset << ": " << 100 * (got / bound - 1) << " % above";
  }
}

// The wait for the window is the bank's side of the controller: a read whose
// activate waits for tFAW is charged dram_bank_conflict (DramQueueParts::bank),
// not the bus. Round configuration, closed page, tFAW 400: reads 0-3 (banks
// 0-3, at cycle 0) activate at 40, 44, 48, 52 (tRRD 4), their data on the bus
// until 78; read 4 (bank 4), asked at cycle 100 (at the controller 140), waits
// for 40 + 400 = 440: its column command 440 + 11, data 462-466 against an
// idle controller's 140 + 22 = 162: 300 cycles of queueing, all of them its
// bank's (the bus idles meanwhile).
TEST(DramActivateLimits, TheWaitIsTheBanks) {
  const DramConfig c = closedPage(4, 400);
  MemorySystem m(c, kRoundMhz);
  for (unsigned i = 0; i < 4; ++i) m.access(0, uint64_t(i) * c.row_bytes, 64, false, Surface::BlendArrays);
  m.resetProbe();
  EXPECT_EQ(m.access(100, 4ull * c.row_bytes, 64, false, Surface::BlendArrays), 440 + kTrcd + kCl + kBurst);
  const DramQueueParts& q = m.probe().queue;
  EXPECT_EQ(q.bank, 300 * DramTimings::kTicksPerCycle);
  EXPECT_EQ(q.bus, 0u);
  EXPECT_EQ(q.turnaround, 0u);
  EXPECT_EQ(q.refresh, 0u);
}

TEST(DramActivateLimits, TfawBelowFourTrrdIsRefused) {
  DramConfig c = roundDramConfig(1);
  c.trrd = 5;
  c.tfaw = 19;
  EXPECT_EQ(DramTimings::activateProblem(c),
            "dram.tfaw (19 tCK) is below 4 x dram.trrd (5 tCK): four activates tRRD apart already span 20 tCK, so "
            "the window could never bind (JEDEC parts have tFAW >= 4 tRRD); set dram.tfaw to 0 (no window) or at "
            "least 20");
  EXPECT_THROW(MemorySystem(c, kRoundMhz), std::invalid_argument);
  c.tfaw = 20;
  EXPECT_EQ(DramTimings::activateProblem(c), "");
  c.tfaw = 0;  // tRRD alone
  EXPECT_EQ(DramTimings::activateProblem(c), "");
}

}  // namespace
}  // namespace oit::rop
