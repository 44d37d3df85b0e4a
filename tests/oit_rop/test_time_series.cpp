// The run's time series and VCD trace: the samples of an empty frame, the
// signals the VCD traces, the sampler's period doubling under max_samples,
// peak against mean bandwidth, and that sampling never changes the timing.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstdio>
#include <cstring>
#include <cmath>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <sstream>
#include <tuple>

#include "oit_rop/RopTestUtil.hpp"
#include "oit_rop/stages/FrontEnd.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace time_series_test {

constexpr uint32_t W = 64, H = 64;

// An empty trace is a frame of 0 cycles; its series still has the one last
// sample REPORT.md promises (audit: "samples": []).
TEST(TimingRun, EmptyFrameHasOneSample) {
  const auto r = runInChild([&] { return timed("mlab", model::testutil::layers(4), {}, 16, 8, smallConfig()); });
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.stats["timing"]["cycles"].get<uint64_t>(), 0u);
  const auto& samples = r.stats["timeseries"]["samples"];
  ASSERT_EQ(samples.size(), 1u);
  EXPECT_EQ(samples[0]["cycle"].get<uint64_t>(), 0u);
  EXPECT_EQ(samples[0]["dram_bytes"].get<uint64_t>(), 0u);
}


// The VCD's DRAM signal is the time series' dram_bytes (bytes the buses moved
// per interval): it once traced bytes requested, which bunch up ahead of the
// buses (9x what the channels can move in an interval).
TEST(TimingRun, VcdTracesKeySignals) {
  const auto fs = smallScene(32, 32, 4, 2);
  const std::string path = ::testing::TempDir() + "oit_rop_trace_" + std::to_string(::getpid()) + ".vcd";
  std::remove(path.c_str());
  TimingOptions opt;
  opt.vcd_path = path;
  RopConfig cfg = smallConfig();
  cfg.stats.interval_cycles = 200;
  const auto r = runInChild([&] { return timed("mlab", {}, fs, 32, 32, cfg, opt); });
  ASSERT_TRUE(r.ok) << r.error;
  std::ifstream in(path);
  ASSERT_TRUE(in.is_open()) << path;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("lock_waiters"), std::string::npos);
  EXPECT_NE(text.find("partition0_occupancy"), std::string::npos);
  // The signal's identifier, then its value at every time stamp (a VCD lists changes only).
  std::istringstream lines(text);
  std::string line, id;
  std::map<uint64_t, uint64_t> changes;  // time (ps) -> value
  uint64_t now = 0;
  while (std::getline(lines, line)) {
    std::istringstream w(line);
    std::string a, b, c, d, e;
    w >> a >> b >> c >> d >> e;
    if (a == "$var" && e == "dram_bytes_per_interval") id = d;
    if (!line.empty() && line[0] == '#') now = std::stoull(line.substr(1));
    if (!id.empty() && !line.empty() && line[0] == 'b' && b == id) changes[now] = std::stoull(a.substr(1), nullptr, 2);
  }
  ASSERT_FALSE(id.empty());
  const auto& samples = r.stats["timeseries"]["samples"];
  ASSERT_GE(samples.size(), 5u);
  uint64_t nonzero = 0;
  // Every sample but the last, which the report adds at the frame's end (the
  // VCD holds the sampler's grid only).
  for (size_t i = 0; i + 1 < samples.size(); ++i) {
    const auto& s = samples[i];
    const auto ps = uint64_t(std::llround(double(s["cycle"].get<uint64_t>()) * 1e6 / cfg.clock.core_mhz));
    auto it = changes.upper_bound(ps);  // the last change at or before the sample
    const uint64_t traced = it == changes.begin() ? 0 : std::prev(it)->second;
    EXPECT_EQ(traced, s["dram_bytes"].get<uint64_t>()) << "cycle " << s["cycle"];
    nonzero += traced != 0;
  }
  EXPECT_GT(nonzero, 0u);
  std::remove(path.c_str());
}

// When the series reaches stats.max_samples its period doubles; the VCD keeps
// its finer earlier samples, so it traces each DRAM sample's period beside it
// (audit: the DRAM signal doubled in scale with nothing marking it).
TEST(TimingRun, VcdTracesThePeriodOfEachDramSample) {
  const std::string path = ::testing::TempDir() + "oitsim_vcd_period_" + std::to_string(::getpid()) + ".vcd";
  std::remove(path.c_str());  // a stale file from an earlier run must not be read as this run's
  RopConfig cfg = smallConfig();
  cfg.stats.interval_cycles = 100;
  cfg.stats.max_samples = 4;
  const auto fs = smallScene(W, H, 6, 3);
  const auto r = runInChild([&] {
    TimingOptions opt;
    opt.vcd_path = path;
    return timed("mlab", model::testutil::layers(4), fs, W, H, cfg, opt);
  });
  ASSERT_TRUE(r.ok) << r.error;
  std::ifstream in(path);
  ASSERT_TRUE(in.is_open()) << path;
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::istringstream lines(text);
  std::string line, id;
  std::vector<uint64_t> periods;  // every value the period signal takes, in order
  while (std::getline(lines, line)) {
    std::istringstream w(line);
    std::string a, b, c, d, e;
    w >> a >> b >> c >> d >> e;
    if (a == "$var" && e == "dram_interval_cycles") id = d;
    if (!id.empty() && !line.empty() && line[0] == 'b' && b == id) {
      const uint64_t v = std::stoull(a.substr(1), nullptr, 2);
      if (v != 0) periods.push_back(v);  // 0: the initial value, before the first sample
    }
  }
  ASSERT_FALSE(id.empty());
  ASSERT_GE(periods.size(), 2u);
  EXPECT_EQ(periods.front(), 100u);
  for (size_t i = 1; i < periods.size(); ++i) EXPECT_EQ(periods[i], 2 * periods[i - 1]);  // changes only double
  const uint64_t final_interval = r.stats["timeseries"]["interval_cycles"].get<uint64_t>();
  EXPECT_TRUE(periods.back() == final_interval || 2 * periods.back() == final_interval) << final_interval;
  std::remove(path.c_str());
}

// Peak is the busiest interval's rate, the last (cut short by the end of the
// frame) over the part of it the frame covers; it is never below the mean.
TEST(TimingRun, PeakBandwidthIsAtLeastMeanAndAtMostTheChannels) {
  const auto fs = smallScene(W, H, 4, 5);
  for (const uint64_t interval : {100u, 500u, 1700u, 100000u}) {
    SCOPED_TRACE(interval);
    RopConfig cfg = smallConfig();
    cfg.stats.interval_cycles = interval;
    const auto r = runInChild([&] { return timed("mlab", {}, fs, W, H, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    const auto& m = r.stats["memory"];
    const double peak = m["peak_gbps"], mean = m["mean_gbps"];
    EXPECT_GT(mean, 0.0);
    EXPECT_GE(peak, mean);
    EXPECT_LE(peak, m["channel_peak_gbps"].get<double>() * (1 + 1e-12));
  }
}

// A time series that reaches stats.max_samples merges pairs and doubles its
// period: the report is then the one a run at the doubled period gives (every
// sample, and the peak bandwidth computed from the same buckets). Two
// partitions: their resume order does not depend on the sampler's period.
TEST(TimingRun, TimeSeriesStaysBelowMaxSamplesAsIfSampledAtTheLongerPeriod) {
  const auto fs = smallScene(W, H, 4, 5);
  RopConfig capped = smallConfig();
  ASSERT_EQ(capped.partitions.count, 2u);
  capped.stats.interval_cycles = 3;
  capped.stats.max_samples = 8;
  const auto a = runInChild([&] { return timed("mlab", {}, fs, W, H, capped); });
  ASSERT_TRUE(a.ok) << a.error;
  const auto& ts = a.stats["timeseries"];
  const uint64_t interval = ts["interval_cycles"];
  EXPECT_LE(ts["samples"].size(), 8u);  // < 8 on the grid, plus the frame's end
  EXPECT_GE(ts["samples"].size(), 4u);
  EXPECT_GT(interval, 3u);
  EXPECT_EQ(interval % 3, 0u);
  EXPECT_TRUE(std::has_single_bit(interval / 3)) << interval;  // 3 x 2^k

  RopConfig direct = smallConfig();
  direct.stats.interval_cycles = interval;
  const auto b = runInChild([&] { return timed("mlab", {}, fs, W, H, direct); });
  ASSERT_TRUE(b.ok) << b.error;
  EXPECT_EQ(a.stats["timing"]["cycles"], b.stats["timing"]["cycles"]);
  EXPECT_EQ(ts, b.stats["timeseries"]);
  EXPECT_EQ(a.stats["memory"]["peak_gbps"], b.stats["memory"]["peak_gbps"]);
}

// Partitions resume in round-robin order at every quantum boundary, so the
// sampler's period (its own timed wake-ups) cannot change the order their DRAM
// requests are booked in: two partitions, same cycles and bytes at any period.
TEST(TimingRun, SamplerPeriodDoesNotChangeTheTiming) {
  const auto fs = smallScene(W, H, 4, 5);
  std::vector<ChildRun> runs;
  for (const uint64_t interval : {3u, 97u, 1000u, 10000u}) {
    RopConfig cfg = smallConfig();
    ASSERT_EQ(cfg.partitions.count, 2u);
    cfg.stats.interval_cycles = interval;
    runs.push_back(runInChild([&] { return timed("abuffer", {}, fs, W, H, cfg); }));
    ASSERT_TRUE(runs.back().ok) << runs.back().error;
  }
  for (size_t i = 1; i < runs.size(); ++i) {
    EXPECT_EQ(runs[i].stats["timing"]["cycles"], runs[0].stats["timing"]["cycles"]) << i;
    EXPECT_EQ(runs[i].stats["timing"]["per_partition"], runs[0].stats["timing"]["per_partition"]) << i;
    EXPECT_EQ(runs[i].stats["memory"]["dram_read_bytes"], runs[0].stats["memory"]["dram_read_bytes"]) << i;
    EXPECT_EQ(runs[i].stats["memory"]["row_misses"], runs[0].stats["memory"]["row_misses"]) << i;
  }
}

// The series ends with a sample at the frame's end cycle, nothing in flight, and
// its dram_bytes add up to every byte the buses moved (whole bursts, so at least
// the bytes requested); a frame shorter than one interval has that sample only.
// Every multiple of the interval up to the frame's end has its sample, whatever
// the quantum (partitions run up to a quantum ahead of SystemC time; the grid
// points of the frame's last quantum were missing, their bytes lumped into the
// final sample).
TEST(TimingRun, TimeSeriesEndsAtTheFrameEndAndAddsUpToTheBusBytes) {
  const auto fs = smallScene(W, H, 4, 5);
  for (const auto& [interval, quantum] : {std::pair<uint64_t, uint64_t>{500, 200}, {300, 1000}, {1000, 100000},
                                          {100000000, 200}}) {
    SCOPED_TRACE(std::to_string(interval) + " cycles, quantum " + std::to_string(quantum));
    RopConfig cfg = smallConfig();
    cfg.stats.interval_cycles = interval;
    cfg.sim.quantum_cycles = quantum;
    const auto r = runInChild([&] { return timed("mlab", {}, fs, W, H, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    const auto& samples = r.stats["timeseries"]["samples"];
    ASSERT_FALSE(samples.empty());
    EXPECT_EQ(samples.back()["cycle"], r.stats["timing"]["cycles"]);
    EXPECT_EQ(samples.back()["scoreboard_occupancy"], 0);
    uint64_t sum = 0;
    for (const auto& s : samples) sum += s["dram_bytes"].get<uint64_t>();
    const auto& m = r.stats["memory"];
    const uint64_t requested = m["dram_read_bytes"]["total"].get<uint64_t>() + m["dram_write_bytes"]["total"].get<uint64_t>();
    EXPECT_GE(sum, requested);
    EXPECT_LT(sum, requested + requested / 10);  // partial bursts only
    const uint64_t cycles = r.stats["timing"]["cycles"];
    ASSERT_EQ(samples.size(), (cycles + interval - 1) / interval);
    for (size_t i = 0; i + 1 < samples.size(); ++i) EXPECT_EQ(samples[i]["cycle"].get<uint64_t>(), (i + 1) * interval);
  }
}

}  // namespace time_series_test
