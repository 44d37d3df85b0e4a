// DRAM refresh (MemorySystem): refresh windows every tREFI staggered over the
// channels, a run that meets one waits for its end, the row it closes, its
// share of the bandwidth (values by hand on the round configuration; MEMORY.md).
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
namespace dram_refresh_test {

using namespace testutil;  // the round configuration's timings (DramTestConfig.hpp)
DramConfig roundConfig(unsigned channels) { return roundDramConfig(channels); }

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

}  // namespace dram_refresh_test
}  // namespace oit::rop
