// Bank groups (dram.bank_groups, tccd_s, tccd_l, trrd_l, twtr_l; MEMORY.md
// "Bank groups"): streams against bounds derived by hand. On the round
// configuration (DramTestConfig.hpp: 1 tCK = 1 core cycle, 64 B burst = 4
// cycles, controller 40, CL = tRCD = tRP = 11, tRAS 0, no refresh, plain map:
// bank b, row r at (r x 8 + b) x 8 KiB) with 4 bank groups, group = bank mod 4,
// so banks 0 and 4 share group 0, bank 1 is in group 1. The controller meets
// each bound exactly there; on the presets' DRAM within 3 % above it, never
// below.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/memory/DramActivateWindow.hpp"
#include "oit_rop/memory/DramTestConfig.hpp"
#include "oit_rop/memory/MemorySystem.hpp"
#include "oit_rop/TestLcg.hpp"

namespace oit::rop {
namespace {

using testutil::kBurst;
using testutil::kCl;
using testutil::kCtrl;
using testutil::kRoundMhz;
using testutil::kTrcd;
using testutil::roundDramConfig;

// The round configuration on one channel with 4 bank groups.
DramConfig grouped(unsigned tccd_l) {
  DramConfig c = roundDramConfig(1);
  c.bank_groups = 4;
  c.tccd_l = tccd_l;
  return c;
}

// Reads at cycle 0 (a deep queue); the cycle the last data is on the bus.
Cycle readAllAtZero(MemorySystem& m, const std::vector<uint64_t>& addrs) {
  Cycle end = 0;
  for (uint64_t a : addrs) end = std::max(end, m.access(0, a, 64, false, Surface::BlendArrays));
  return end;
}

// n one-burst reads rotating over `banks` (each in its row 0, the columns in
// turn): row hits after each bank's first read.
std::vector<uint64_t> rowHitsOver(const std::vector<unsigned>& banks, unsigned n, unsigned row_bytes) {
  std::vector<uint64_t> a;
  const unsigned columns = row_bytes / 64;
  for (unsigned i = 0; i < n; ++i)
    a.push_back(uint64_t(banks[i % banks.size()]) * row_bytes + uint64_t(i / banks.size() % columns) * 64);
  return a;
}

// --- DramActivateWindow with groups (ticks are plain numbers here) ---

// tRRD 4 between groups, tRRD_L 10 inside one.
TEST(DramBankGroups, ActivateWindowKeepsTrrdLInsideAGroup) {
  DramActivateWindow w(4, 0, 10);
  w.record(0, 0);
  EXPECT_EQ(w.earliest(1, 1), 4u);   // another group: 0 + tRRD
  EXPECT_EQ(w.earliest(1, 0), 10u);  // the same group: 0 + tRRD_L
  w.record(4, 1);
  EXPECT_EQ(w.earliest(5, 0), 10u);  // group 0's 0 + 10 (group 1's 4 + 4 = 8 too)
  EXPECT_EQ(w.earliest(5, 1), 14u);  // group 1's 4 + 10
  EXPECT_EQ(w.earliest(5, 2), 8u);   // a third group: 4 + tRRD
  // Booked out of time order: 100 (group 0) and 130 (group 1) kept.
  DramActivateWindow r(4, 0, 10);
  r.record(100, 0);
  r.record(130, 1);
  EXPECT_EQ(r.earliest(105, 1), 105u);  // 5 after group 0's, 25 before group 1's own
  EXPECT_EQ(r.earliest(105, 0), 110u);  // 100 + tRRD_L; 20 before 130 (another group)
  EXPECT_EQ(r.earliest(125, 0), 125u);  // 25 after 100, 5 before 130 (>= tRRD)
  EXPECT_EQ(r.earliest(125, 1), 140u);  // 5 before group 1's 130: past it by tRRD_L
  EXPECT_EQ(r.earliest(128, 2), 134u);  // within tRRD of 130: past it by tRRD
}

// Without a longer in-group value the groups are not looked at: the window
// places every activate as before.
TEST(DramBankGroups, ActivateWindowWithoutTrrdLIsTheOldWindow) {
  DramActivateWindow plain(10, 50), same(10, 50, 10);
  for (uint64_t t : {0, 10, 20, 30}) {
    plain.record(t);
    same.record(t, unsigned(t / 10) % 2);
  }
  for (uint64_t t : {5, 31, 45, 50, 60})
    for (unsigned g : {0u, 1u}) EXPECT_EQ(same.earliest(t, g), plain.earliest(t)) << t;
}

// --- Column commands: tCCD_L inside a group, tCCD_S between groups ---

// One bank's row, 128 one-burst reads (row hits after the first), tCCD_L 6:
// the first activates at ctrl = 40, its data at 40 + tRCD + CL = 62; every
// further burst of the group waits tCCD_L after the previous one's start
// (the bus would allow 4): the last (k = 127) ends at 62 + 6 x 127 + 4 =
// 828. Over banks 0 and 4 (group 0 both) the same: 828 for 128 reads. Over
// banks 0-3 (four groups), each group's bursts 16 cycles apart, the bus
// binds: 62 + 4 x 128 = 574, as without groups.
TEST(DramBankGroups, RowHitStreamToOneGroupIsPacedByTccdL) {
  const DramConfig c = grouped(6);
  MemorySystem one(c, kRoundMhz);
  EXPECT_EQ(readAllAtZero(one, rowHitsOver({0}, 128, c.row_bytes)), kCtrl + kTrcd + kCl + 6 * 127 + kBurst);
  EXPECT_EQ(one.stats().row_hits, 127u);
  MemorySystem two(c, kRoundMhz);
  EXPECT_EQ(readAllAtZero(two, rowHitsOver({0, 4}, 128, c.row_bytes)), kCtrl + kTrcd + kCl + 6 * 127 + kBurst);
  MemorySystem spread(c, kRoundMhz);
  EXPECT_EQ(readAllAtZero(spread, rowHitsOver({0, 1, 2, 3}, 128, c.row_bytes)),
            kCtrl + kTrcd + kCl + 128 * kBurst);
  // One request of the whole row is one run: its bursts tCCD_L apart, the same 828.
  MemorySystem run(c, kRoundMhz);
  EXPECT_EQ(run.access(0, 0, c.row_bytes, false, Surface::BlendArrays), kCtrl + kTrcd + kCl + 6 * 127 + kBurst);
  // The bus time counted is the data's (128 bursts), not the idle between them.
  EXPECT_EQ(run.stats().channel_busy[0], 128 * kBurst);
}

// With refresh a run is placed whole between two windows: it may hold the
// first burst and then one per tCCD_L in the room a window leaves (tREFI 1000
// ns, tRFC 100, round: 1000 - 100 - tRCD - CL = 878 cycles): (878 - 4) / 6 + 1
// = 146 bursts with tCCD_L 6, 878 / 4 = 219 back to back.
TEST(DramBankGroups, ARunBetweenRefreshesHoldsFewerBurstsTccdLApart) {
  DramConfig c = grouped(6);
  c.trefi_ns = 1000;
  c.trfc_ns = 100;
  EXPECT_EQ(DramTimings(c, kRoundMhz).max_run_bursts, 146u);
  c.tccd_l = 0;
  EXPECT_EQ(DramTimings(c, kRoundMhz).max_run_bursts, 219u);
}

// tCCD_S longer than a burst (6 against 4) spaces every column command on the
// channel, groups or not: 128 reads over banks 0-3 end at 62 + 6 x 127 + 4.
TEST(DramBankGroups, TccdSLongerThanABurstSpacesEveryBurst) {
  DramConfig c = roundDramConfig(1);
  c.tccd_s = 6;
  MemorySystem m(c, kRoundMhz);
  EXPECT_EQ(readAllAtZero(m, rowHitsOver({0, 1, 2, 3}, 128, c.row_bytes)), kCtrl + kTrcd + kCl + 6 * 127 + kBurst);
}

// The presets' DRAM with their parts' bank groups (4, tCCD_L 3 tCK: CONFIG.md;
// off in the presets themselves) on one channel (open rows, refresh off): a row-hit stream
// in one bank moves a burst per tCCD_L (titan-x-maxwell: 3 tCK x 0.667 ns at
// 1075 MHz = 2.151 cycles against a 1.229-cycle burst; navi21: 3 tCK x 0.5 ns
// at 2015 MHz = 3.023 against 2.015); the same reads over one bank of each
// group move a burst per burst time. Bound: ctrl + tRCD + CL + (n - 1) x
// spacing + burst; within 3 % above, never below.
TEST(DramBankGroups, PresetsRowHitStreamsAgainstTheirBounds) {
  for (const char* preset : {"titan-x-maxwell", "navi21"}) {
    const RopConfig rc = presetConfig(preset);
    DramConfig d = rc.dram;
    ASSERT_EQ(d.bank_groups, 1u) << preset;
    d.bank_groups = 4;
    d.tccd_l = 3;
    d.channels = 1;
    d.trefi_ns = d.trfc_ns = 0;
    MemorySystem probe(d, rc.clock.core_mhz);
    // One bank per group (the hashed map: the first rows whose bank lands in each group).
    std::vector<uint64_t> base(4, ~uint64_t(0));
    for (uint64_t r = 0; r < 64; ++r) {
      const unsigned g = probe.bankGroupOf(r * d.row_bytes);
      if (base[g] == ~uint64_t(0)) base[g] = r * d.row_bytes;
    }
    const unsigned n = 2000, columns = d.row_bytes / d.burst_bytes;
    const double first = probe.controllerCycles() + probe.trcdCycles() + probe.clCycles() + probe.burstCycles();
    ASSERT_GT(probe.ccdLCycles(), probe.burstCycles()) << preset;
    for (bool spread : {false, true}) {
      MemorySystem m(d, rc.clock.core_mhz);
      std::vector<uint64_t> a;
      for (unsigned i = 0; i < n; ++i)
        a.push_back((spread ? base[i % 4] : base[0]) + uint64_t((spread ? i / 4 : i) % columns) * d.burst_bytes);
      Cycle end = 0;
      for (uint64_t x : a) end = std::max(end, m.access(0, x, d.burst_bytes, false, Surface::BlendArrays));
      const double bound = first + (n - 1) * (spread ? m.burstCycles() : m.ccdLCycles());
      EXPECT_GE(double(end), bound) << preset << (spread ? " over the groups" : " one group");
      EXPECT_LE(double(end), 1.03 * bound) << preset << (spread ? " over the groups" : " one group") << ": "
                                           << 100 * (double(end) / bound - 1) << " % above";
    }
  }
}

// --- Activates: tRRD_L inside a group ---

// Closed page, two banks in turn, tRRD 4, tRRD_L 20. Banks 0 and 4 (group 0):
// a bank's chain (tRCD + CL + burst + tRP = 37) allows an activate every 18.5
// cycles over the two, tRRD_L only every 20: activate k at 40 + 20 k, its
// data ending 26 later; k = 499: 40 + 9,980 + 26 = 10,046. Banks 0 and 1
// (two groups): tRRD 4 lets bank 1 activate at 44, then each bank every 37
// (bank 0 at 40 + 37 j, bank 1 at 44 + 37 j, 33 apart the other way): the
// last (bank 1, j = 249) at 44 + 9,213, ending at 9,283.
TEST(DramBankGroups, ActivatesInOneGroupAreTrrdLApart) {
  DramConfig c = grouped(0);
  c.open_row = false;
  c.trrd = 4;
  c.trrd_l = 20;
  MemorySystem same(c, kRoundMhz);
  std::vector<uint64_t> a04, a01;
  for (unsigned i = 0; i < 500; ++i) {
    // Each visit to a new row of its bank: (row x 8 + bank) x row_bytes.
    a04.push_back((uint64_t(i / 2) * c.banks + (i % 2 ? 4 : 0)) * c.row_bytes);
    a01.push_back((uint64_t(i / 2) * c.banks + i % 2) * c.row_bytes);
  }
  EXPECT_EQ(readAllAtZero(same, a04), kCtrl + 20 * 499 + kTrcd + kCl + kBurst);
  EXPECT_EQ(same.stats().row_misses, 500u);
  MemorySystem other(c, kRoundMhz);
  EXPECT_EQ(readAllAtZero(other, a01), kCtrl + 4 + 249 * (kTrcd + kCl + kBurst + testutil::kTrp) + kTrcd + kCl + kBurst);
}

// --- Write to read: tWTR_L inside a group ---

// Writes one by one (write_high 1), tWTR 6, tWTR_L 15. A write to bank 0
// (group 0) at cycle 0 is accepted at 40 and drained at once: activate 40,
// data 62-66. A read at cycle 0 to bank 4 (group 0, idle: activate 40,
// column command ready at 51) waits tWTR_L after the group's write data: its
// command at 66 + 15 = 81, data 92-96. To bank 1 (group 1) the channel's tWTR
// alone: 72, data 83-87. Without tWTR_L both are 87.
TEST(DramBankGroups, WriteToReadInOneGroupWaitsTwtrL) {
  DramConfig c = grouped(0);
  c.twtr = 6;
  c.twtr_l = 15;
  c.write_queue = 1;
  c.write_high = 1;
  c.write_low = 0;
  const auto readAfterWrite = [&](const DramConfig& cfg, unsigned bank) {
    MemorySystem m(cfg, kRoundMhz);
    EXPECT_EQ(m.access(0, 0, 64, true, Surface::BlendArrays), kCtrl);
    return m.access(0, uint64_t(bank) * cfg.row_bytes, 64, false, Surface::BlendArrays);
  };
  EXPECT_EQ(readAfterWrite(c, 4), 66 + 15 + kCl + kBurst);
  EXPECT_EQ(readAfterWrite(c, 1), 66 + 6 + kCl + kBurst);
  DramConfig flat = c;
  flat.twtr_l = 0;
  EXPECT_EQ(readAfterWrite(flat, 4), 66 + 6 + kCl + kBurst);
}

// --- No distinction, no change ---

// Bank groups without longer in-group timings (tccd_l, trrd_l, twtr_l 0) book
// a random mixed stream exactly as no groups do: the groups only matter
// through their _L values.
TEST(DramBankGroups, GroupsWithoutLongTimingsChangeNothing) {
  for (bool open : {true, false}) {
    DramConfig flat = roundDramConfig(2);
    flat.open_row = open;
    flat.bank_hash = true;
    flat.trrd = 4;
    flat.tfaw = 20;
    flat.trefi_ns = 3900;
    flat.trfc_ns = 160;
    DramConfig g = flat;
    g.bank_groups = 4;
    MemorySystem a(flat, kRoundMhz), b(g, kRoundMhz);
    testutil::TestLcg rnd{0x5eedull, 17};
    Cycle now = 0;
    for (unsigned i = 0; i < 4000; ++i) {
      now += rnd(7);
      const uint64_t addr = rnd(1u << 22) & ~uint64_t(63);
      const uint32_t bytes = 64u << rnd(3);
      const bool write = rnd(3) == 0;
      ASSERT_EQ(b.access(now, addr, bytes, write, Surface::BlendArrays),
                a.access(now, addr, bytes, write, Surface::BlendArrays))
          << "request " << i;
    }
    EXPECT_EQ(b.drainWrites(now), a.drainWrites(now));
    EXPECT_EQ(b.stats().row_hits, a.stats().row_hits);
  }
}

// --- Bad configurations: one line naming the parameter and the rule ---

TEST(DramBankGroups, BadConfigurationsAreRefused) {
  DramConfig c = roundDramConfig(1);  // 8 banks
  c.bank_groups = 16;
  ASSERT_EQ(DramTimings::bankGroupProblems(c).size(), 1u);
  EXPECT_EQ(DramTimings::bankGroupProblems(c)[0],
            "dram.bank_groups (16) must be a power of two dividing dram.banks (8): each group holds the same number "
            "of banks");
  EXPECT_THROW(MemorySystem(c, kRoundMhz), std::invalid_argument);
  c.bank_groups = 4;
  c.tccd_s = 4;
  c.tccd_l = 3;
  EXPECT_EQ(DramTimings::bankGroupProblems(c)[0],
            "dram.tccd_l (3 tCK) is below dram.tccd_s (4 tCK): inside a bank group the spacing is at least the one "
            "between groups; set dram.tccd_l to 0 (no distinction) or at least 4");
  c.tccd_l = 0;
  c.trrd = 5;
  c.trrd_l = 4;
  EXPECT_NE(DramTimings::bankGroupProblems(c)[0].find("dram.trrd_l (4 tCK) is below dram.trrd (5 tCK)"),
            std::string::npos);
  c.trrd_l = 0;
  c.twtr_l = 5;  // twtr 6
  EXPECT_NE(DramTimings::bankGroupProblems(c)[0].find("dram.twtr_l (5 tCK) is below dram.twtr (6 tCK)"),
            std::string::npos);
  c.twtr_l = 6;
  EXPECT_TRUE(DramTimings::bankGroupProblems(c).empty());
  c.bank_groups = 1;
  EXPECT_EQ(DramTimings::bankGroupProblems(c)[0],
            "dram.twtr_l (6 tCK) needs dram.bank_groups > 1: without bank groups every bank keeps dram.twtr (6 tCK); "
            "set dram.twtr_l to 0 or dram.bank_groups to the part's groups");
  EXPECT_THROW(MemorySystem(c, kRoundMhz), std::invalid_argument);
}

}  // namespace
}  // namespace oit::rop
