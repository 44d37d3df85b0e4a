// DramTimings: the DRAM's timings in ticks (2^-16 core cycles, rounded up)
// and the refresh windows (MEMORY.md, "units" and "refresh").
#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "oit_rop/memory/DramTestConfig.hpp"
#include "oit_rop/memory/DramTimings.hpp"

namespace oit::rop {
namespace {

using testutil::kRoundMhz;
using testutil::roundDramConfig;

constexpr uint64_t kTick = DramTimings::kTicksPerCycle;

TEST(DramTimings, RoundConfigIsWholeCycles) {
  const DramTimings t(roundDramConfig(2), kRoundMhz);
  EXPECT_DOUBLE_EQ(t.bytes_per_cycle, 16.0);
  EXPECT_EQ(t.ctrl, 40 * kTick);
  EXPECT_EQ(t.cl, 11 * kTick);
  EXPECT_EQ(t.trcd, 11 * kTick);
  EXPECT_EQ(t.trp, 11 * kTick);
  EXPECT_EQ(t.tras, 0u);
  EXPECT_EQ(t.burst, 4 * kTick);
  EXPECT_EQ(t.refresh_period, 0u);
}

TEST(DramTimings, IgpuPresetConversions) {
  // DDR3-1600 at 1150 MHz core: 12.8 GB/s -> 11.13 B/cycle, a 64 B burst 5.75
  // cycles, 11 tCK of 1.25 ns = 13.75 ns = 15.8125 cycles, 40 ns = 46 cycles,
  // tRAS 28 tCK = 35 ns = 40.25 cycles.
  const DramTimings t(DramConfig{}, 1150.0);
  EXPECT_NEAR(t.bytes_per_cycle, 12.8e9 / 1150e6, 1e-12);
  EXPECT_DOUBLE_EQ(DramTimings::cycles(t.burst), 5.75);
  EXPECT_DOUBLE_EQ(DramTimings::cycles(t.cl), 15.8125);
  EXPECT_DOUBLE_EQ(DramTimings::cycles(t.ctrl), 46.0);
  EXPECT_DOUBLE_EQ(DramTimings::cycles(t.tras), 40.25);
}

TEST(DramTimings, TicksRoundUpButKeepExactValues) {
  EXPECT_EQ(DramTimings::ticks(5.75), 5 * kTick + kTick * 3 / 4);
  EXPECT_EQ(DramTimings::ticks(1.0 / 3), kTick / 3 + 1);       // 21845.33 -> 21846
  EXPECT_EQ(DramTimings::ticks(0.1 * 3), 19661u);              // 0.30000000000000004 cycles: 19660.8 -> 19661
  EXPECT_EQ(DramTimings::ticks(2.0 + 1e-12), 2 * kTick);       // noise below 1e-9 is taken as exact
  EXPECT_EQ(DramTimings::ceilCycles(2 * kTick), 2u);
  EXPECT_EQ(DramTimings::ceilCycles(2 * kTick + 1), 3u);
}

// A bandwidth too low for the tick arithmetic is refused as such (a vanishing
// bandwidth used to overflow to 0 ticks and be reported as "too high"; the
// configuration's ranges and its burst-time check keep runs far from both ends).
TEST(DramTimings, RefusesBandwidthsTheTicksCannotHold) {
  auto messageOf = [](double gbps, double mhz) {
    DramConfig c = roundDramConfig(1);
    c.channel_gbps = gbps;
    try {
      DramTimings t(c, mhz);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(messageOf(1e-300, kRoundMhz).find("channel_gbps too low"), std::string::npos) << messageOf(1e-300, kRoundMhz);
  EXPECT_NE(messageOf(1e-12, kRoundMhz).find("channel_gbps too low"), std::string::npos);
  EXPECT_EQ(messageOf(0.1, 1.0), "no error");  // the configurable extremes
  EXPECT_EQ(messageOf(10000, 10000), "no error");
}

// One channel, tREFI 1000 cycles, tRFC 100: windows [1000, 1100), [2000, 2100) ...;
// a second channel's are half a period later.
TEST(DramTimings, RefreshWindowsAreStaggeredOverChannels) {
  DramConfig c = roundDramConfig(2);
  c.trefi_ns = 1000;
  c.trfc_ns = 100;
  const DramTimings t(c, kRoundMhz);
  EXPECT_EQ(t.refresh_period, 1000 * kTick);
  EXPECT_EQ(t.refresh_rfc, 100 * kTick);
  EXPECT_EQ(t.refresh_off[0], 0u);
  EXPECT_EQ(t.refresh_off[1], 500 * kTick);
  EXPECT_EQ(t.lastRefreshStart(0, 999 * kTick), 0u);  // no window before the first period
  EXPECT_EQ(t.lastRefreshStart(0, 2050 * kTick), 2000 * kTick);
  EXPECT_EQ(t.lastRefreshStart(1, 2050 * kTick), 1500 * kTick);
  EXPECT_EQ(t.refreshOverlapEnd(0, 950 * kTick, 1001 * kTick), 1100 * kTick);
  EXPECT_EQ(t.refreshOverlapEnd(0, 950 * kTick, 1000 * kTick), 0u);  // ends as the window starts
  EXPECT_EQ(t.refreshOverlapEnd(0, 1050 * kTick, 1060 * kTick), 1100 * kTick);  // inside one
  EXPECT_EQ(t.refreshOverlapEnd(0, 1100 * kTick, 1900 * kTick), 0u);
  EXPECT_EQ(t.refreshOverlapEnd(1, 1100 * kTick, 1900 * kTick), 1600 * kTick);
}

// A run is placed whole between two refresh windows, on a bank the refresh
// left closed; a longer run is booked in parts of max_run_bursts:
// (tREFI - tRFC - tRCD - CL) / burst = (1000 - 100 - 22) / 4 = 219 bursts.
// Only a gap that cannot hold an activate, CL and one burst (26 cycles) is
// refused.
TEST(DramTimings, RefreshGapsHoldRunsOfBoundedLength) {
  DramConfig base = roundDramConfig(1);
  base.trefi_ns = 1000;
  base.trfc_ns = 100;
  EXPECT_EQ(DramTimings::refreshProblem(base, kRoundMhz), "");
  EXPECT_EQ(DramTimings(base, kRoundMhz).max_run_bursts, 219u);
  DramConfig c = base;
  c.trfc_ns = 1000 - 26;
  EXPECT_EQ(DramTimings::refreshProblem(c, kRoundMhz), "");
  EXPECT_EQ(DramTimings(c, kRoundMhz).max_run_bursts, 1u);
  c.trfc_ns = 1000 - 26 + 1;
  EXPECT_EQ(DramTimings::refreshProblem(c, kRoundMhz),
            "dram.trefi_ns (1000 ns) minus dram.trfc_ns (975 ns) must hold an activate, CL and one burst of 64 bytes "
            "(26.0 ns here)");
  EXPECT_THROW(DramTimings(c, kRoundMhz), std::invalid_argument);
  c = base;
  c.trfc_ns = 0;
  EXPECT_NE(DramTimings::refreshProblem(c, kRoundMhz).find("needs dram.trfc_ns > 0"), std::string::npos);
  c.trefi_ns = 0;  // no refresh: tRFC is not used, runs are not limited
  EXPECT_EQ(DramTimings::refreshProblem(c, kRoundMhz), "");
  EXPECT_EQ(DramTimings(c, kRoundMhz).max_run_bursts, ~uint64_t(0));
}

}  // namespace
}  // namespace oit::rop
