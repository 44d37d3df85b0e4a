// The configuration's cross-field validation (ConfigTree::validate): DRAM
// refresh and controller settings, the approximate engine's lock modes, cache
// geometry and sectors, rates and bandwidths, partition resume offsets.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "oit_rop/config/ConfigTestUtil.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/memory/BlendArrayCache.hpp"  // cacheGeometry

using namespace oit::rop;

namespace config_validation_test {

using namespace oit::rop::config_testutil;

// DRAM refresh is on in both presets with their memories' values (igpu DDR3
// JEDEC: 7.8 us, 260 ns for 4 Gb; dgpu GDDR5: 1.9 us, 110 ns, CONFIG.md); a
// refresh gap that cannot hold an activate, CL and one burst is refused by
// validate(), naming both properties.
TEST(ConfigTree, DramRefreshIsOnAndValidated) {
  EXPECT_EQ(ConfigTree::forPreset("igpu").config().dram.trefi_ns, 7800.0);
  EXPECT_EQ(ConfigTree::forPreset("igpu").config().dram.trfc_ns, 260.0);
  EXPECT_EQ(ConfigTree::forPreset("dgpu").config().dram.trefi_ns, 1900.0);
  EXPECT_EQ(ConfigTree::forPreset("dgpu").config().dram.trfc_ns, 110.0);
  ConfigTree t = ConfigTree::forPreset("igpu");
  t.set("dram.trefi_ns", "300");
  EXPECT_NO_THROW(t.validate());  // 40 ns left: an activate and CL (27.5 ns) and a burst (5 ns)
  t.set("dram.trefi_ns", "290");
  std::string e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("dram.trefi_ns (290 ns) minus dram.trfc_ns (260 ns) must hold an activate, CL and one burst "
                   "of 64 bytes (32.5 ns here)"),
            std::string::npos)
      << e;
  t.set("dram.trfc_ns", "0");
  e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("dram.trefi_ns > 0 needs dram.trfc_ns > 0"), std::string::npos) << e;
  t.set("dram.trefi_ns", "0");  // off
  EXPECT_NO_THROW(t.validate());
}

// The activate limits (MEMORY.md, "Activate limits"): each preset carries its
// memory's tRRD and tFAW (DDR3-1600 x8: 5 and 24 tCK; GDDR5: 9 and 36;
// GDDR6: 8 and 32), and a tFAW below 4 x tRRD, a window that could never bind,
// is refused by validate() in one line naming both; 0 turns either off.
TEST(ConfigTree, DramActivateLimitsArePresetAndValidated) {
  EXPECT_EQ(ConfigTree::forPreset("iris-pro-5200").config().dram.trrd, 5u);
  EXPECT_EQ(ConfigTree::forPreset("iris-pro-5200").config().dram.tfaw, 24u);
  EXPECT_EQ(ConfigTree::forPreset("titan-x-maxwell").config().dram.trrd, 9u);
  EXPECT_EQ(ConfigTree::forPreset("titan-x-maxwell").config().dram.tfaw, 36u);
  EXPECT_EQ(ConfigTree::forPreset("navi21").config().dram.trrd, 8u);
  EXPECT_EQ(ConfigTree::forPreset("navi21").config().dram.tfaw, 32u);
  ConfigTree t = ConfigTree::forPreset("iris-pro-5200");
  t.set("dram.tfaw", "19");
  const std::string e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("dram.tfaw (19 tCK) is below 4 x dram.trrd (5 tCK): four activates tRRD apart already span "
                   "20 tCK, so the window could never bind (JEDEC parts have tFAW >= 4 tRRD); set dram.tfaw to 0 (no "
                   "window) or at least 20"),
            std::string::npos)
      << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;  // one line
  t.set("dram.tfaw", "20");
  EXPECT_NO_THROW(t.validate());
  t.set("dram.tfaw", "0");
  EXPECT_NO_THROW(t.validate());
  t.set("dram.trrd", "0");
  EXPECT_NO_THROW(t.validate());
}

// Bank groups (MEMORY.md, "Bank groups"): off in every preset (the GDDR parts'
// 4 groups, tCCD_L 3 tCK and navi21's tWTR_L 13 are set on request: CONFIG.md),
// DDR3 has none. Broken rules are refused by validate(), one line each naming the
// parameter: groups not dividing the banks, an in-group timing below its
// between-groups value, an in-group timing without groups.
TEST(ConfigTree, DramBankGroupsArePresetAndValidated) {
  const DramConfig iris = ConfigTree::forPreset("iris-pro-5200").config().dram;
  const DramConfig titan = ConfigTree::forPreset("titan-x-maxwell").config().dram;
  const DramConfig navi = ConfigTree::forPreset("navi21").config().dram;
  EXPECT_EQ(iris.bank_groups, 1u);
  EXPECT_EQ(iris.tccd_l + iris.trrd_l + iris.twtr_l + iris.tccd_s, 0u);
  EXPECT_EQ(titan.bank_groups, 1u);
  EXPECT_EQ(titan.tccd_l + titan.trrd_l + titan.twtr_l + titan.tccd_s, 0u);
  EXPECT_EQ(navi.bank_groups, 1u);
  EXPECT_EQ(navi.tccd_l + navi.trrd_l + navi.twtr_l + navi.tccd_s, 0u);
  ConfigTree t = ConfigTree::forPreset("navi21");
  t.set("dram.tccd_l", "3");  // the part's values (CONFIG.md)
  t.set("dram.twtr_l", "13");
  t.set("dram.bank_groups", "32");  // 16 banks
  std::string e = errorOf([&] { t.validate(); });
  EXPECT_EQ(e, "invalid configuration (preset navi21): dram.bank_groups (32) must be a power of two dividing "
               "dram.banks (16): each group holds the same number of banks");
  t.set("dram.bank_groups", "4");
  t.set("dram.tccd_s", "4");
  e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("dram.tccd_l (3 tCK) is below dram.tccd_s (4 tCK)"), std::string::npos) << e;
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;  // one line
  t.set("dram.tccd_s", "0");
  t.set("dram.trrd_l", "7");  // trrd 8
  e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("dram.trrd_l (7 tCK) is below dram.trrd (8 tCK)"), std::string::npos) << e;
  t.set("dram.trrd_l", "8");
  EXPECT_NO_THROW(t.validate());
  t.set("dram.bank_groups", "1");
  e = errorOf([&] { t.validate(); });
  // Three lines: tccd_l, trrd_l and twtr_l each need groups.
  EXPECT_NE(e.find("dram.tccd_l (3 tCK) needs dram.bank_groups > 1"), std::string::npos) << e;
  EXPECT_NE(e.find("dram.twtr_l (13 tCK) needs dram.bank_groups > 1"), std::string::npos) << e;
  t.set("dram.tccd_l", "0");
  t.set("dram.trrd_l", "0");
  t.set("dram.twtr_l", "0");
  EXPECT_NO_THROW(t.validate());
}

// The write queue's watermarks out of order are refused by validate(), one
// line each naming the parameters and the rule; sizes of 0 and unknown
// schedulers by their range.
TEST(ConfigTree, DramControllerSettingsAreValidated) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  EXPECT_NO_THROW(t.validate());
  t.set("dram.write_low", "56");  // = write_high
  std::string e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("dram.write_low (56) >= dram.write_high (56): the low watermark must be below the high one"),
            std::string::npos)
      << e;
  t.set("dram.write_low", "32");
  t.set("dram.write_high", "80");
  e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("dram.write_high (80) > dram.write_queue (64): the high watermark must fit in the write queue"),
            std::string::npos)
      << e;
  t.set("dram.write_queue", "80");
  EXPECT_NO_THROW(t.validate());  // the high watermark may be the whole queue
  e = errorOf([&] { t.set("dram.write_queue", "0"); });
  EXPECT_EQ(e, "dram.write_queue: '0' is out of range; expected an integer [1, 4096] (bursts)");
  e = errorOf([&] { t.set("dram.write_high", "0"); });
  EXPECT_EQ(e, "dram.write_high: '0' is out of range; expected an integer [1, 4096] (bursts)");
  e = errorOf([&] { t.set("dram.queue_depth", "0"); });
  EXPECT_EQ(e, "dram.queue_depth: '0' is out of range; expected an integer [1, 4096] (bursts)");
  e = errorOf([&] { t.set("dram.scheduler", "fifo"); });
  EXPECT_EQ(e, "dram.scheduler: 'fifo' is not a known value; expected one of fcfs | frfcfs");
}

// The approximate engine does not model unordered or unlocked inserts: one
// line naming both settings, instead of running them as ordered.
TEST(ConfigTree, ApproximateEngineRefusesLockModesItDoesNotModel) {
  for (const char* mode : {"unordered", "none"}) {
    ConfigTree t = ConfigTree::forPreset("igpu");
    t.set("sim.engine", "approximate");
    t.set("lock.mode", mode);
    EXPECT_EQ(errorOf([&] { t.validate(); }),
              std::string("invalid configuration (preset iris-pro-5200): lock.mode=") + mode +
                  " is not modelled by sim.engine=approximate (it visits fragments in submission order, so it "
                  "cannot apply inserts in lock-entry order or race them); use sim.engine=cycle or "
                  "lock.mode=ordered");
    t.set("lock.mode", "ordered");
    EXPECT_NO_THROW(t.validate());
  }
}

TEST(ConfigTree, CrossFieldValidation) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  t.set("input.latency_min", "200");
  t.set("alu.fp32_rate", "1");
  std::string e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("input.latency_min (200) > input.latency_max (120)"), std::string::npos) << e;
  EXPECT_NE(e.find("alu.fp32_rate (1) > alu.fp16_rate (0.5)"), std::string::npos) << e;  // both listed
  t.set("input.latency_model", "fixed");  // latency_max unused
  t.set("alu.fp16_rate", "1");
  EXPECT_NO_THROW(t.validate());

  // Quad locks need tiles of whole quads (sizes are powers of two: at least 2).
  ConfigTree q = ConfigTree::forPreset("igpu");
  q.set("lock.granularity", "quad");
  q.set("partitions.tile_width", "1");
  q.set("partitions.tile_height", "1");
  q.set("cache.size_bytes", "4096");
  e = errorOf([&] { q.validate(); });
  EXPECT_NE(e.find("lock.granularity quad needs partitions.tile_width and tile_height of at least 2 (now 1 x 1)"),
            std::string::npos) << e;
  q.set("partitions.tile_width", "2");
  q.set("partitions.tile_height", "4");
  EXPECT_NO_THROW(q.validate());
  q.set("partitions.tile_width", "1");
  EXPECT_THROW(q.validate(), std::invalid_argument);
  q.set("lock.granularity", "pixel");  // any tile size for pixel and tile locks
  EXPECT_NO_THROW(q.validate());

  ConfigTree c = ConfigTree::forPreset("igpu");
  c.set("cache.size_bytes", "3000");
  e = errorOf([&] { c.validate(); });
  EXPECT_NE(e.find("cache.size_bytes (3000) is not a multiple of cache.ways x cache.line_bytes (8 x 64 = 512)"),
            std::string::npos)
      << e;

  ConfigTree d = ConfigTree::forPreset("igpu");
  d.set("dram.burst_bytes", "512");
  e = errorOf([&] { d.validate(); });
  EXPECT_NE(e.find("dram.burst_bytes (512) > dram.interleave_bytes (256)"), std::string::npos) << e;
}

TEST(ConfigTree, CacheGeometry) {
  // A copy: a reference into forPreset()'s temporary would dangle (ASan).
  const CacheConfig igpu = ConfigTree::forPreset("igpu").config().cache;
  const CacheGeometry g = cacheGeometry(igpu, 64 * 16);  // 8x8 tile, 16 bytes per pixel
  EXPECT_EQ(g.ways, 8u);
  EXPECT_EQ(g.sets, 8u);
  EXPECT_EQ(g.lines, 64u);
  const CacheGeometry odd = cacheGeometry(igpu, 64 * 36);  // AT with N = 4: 36 bytes per pixel
  EXPECT_EQ(odd.sets, 3u);
  EXPECT_EQ(odd.lines, 24u);
  // Fewer lines than ways: one fully associative set (6 lines of 10 KiB in 64 KiB).
  const CacheGeometry few = cacheGeometry(igpu, 64 * 160);
  EXPECT_EQ(few.ways, 6u);
  EXPECT_EQ(few.sets, 1u);
  EXPECT_EQ(few.lines, 6u);
  EXPECT_EQ(cacheGeometry(igpu, 64 * 1024).lines, 1u);  // exactly one 64 KiB line
  // Not even one line: refused, naming the option (was silently modelled as one line).
  const std::string e = errorOf([&] { cacheGeometry(igpu, 64 * 1280); });
  EXPECT_NE(e.find("cache.size_bytes (65536) is smaller than one line of 81920 bytes"), std::string::npos) << e;
}

// Rates and bandwidths have physical lower bounds: the rate limiters keep 2^-20
// per clock (0.001 per clock is within 0.05 %), the DRAM model 2^-16 cycles per
// burst; a slower DRAM than 0.1 GB/s or clock below 1 MHz only made frames (and
// time series) astronomically long.
TEST(ConfigTree, RateAndBandwidthBounds) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  for (const auto& [path, bad] : {std::pair{"input.fragments_per_clock", "0.0001"}, std::pair{"alu.fp32_rate", "0.0005"},
                                  std::pair{"dram.channel_gbps", "0.01"}, std::pair{"clock.core_mhz", "0.5"}}) {
    const char* p = path;  // clang 14 cannot capture a structured binding
    const char* v = bad;
    const std::string e = errorOf([&] { t.set(p, v); });
    EXPECT_NE(e.find(path), std::string::npos) << e;
    EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  }
  EXPECT_NO_THROW(t.set("input.fragments_per_clock", "0.001"));
  EXPECT_NO_THROW(t.set("dram.channel_gbps", "0.1"));
  EXPECT_NO_THROW(t.validate());
  // Too fast for the DRAM model's tick: named, with both values.
  t.set("dram.channel_gbps", "10000");
  t.set("clock.core_mhz", "1");
  t.set("dram.burst_bytes", "8");
  const std::string e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("dram.channel_gbps (10000 GB/s) at clock.core_mhz (1 MHz): a 8-byte burst takes 8e-07 core cycles"),
            std::string::npos)
      << e;
}

// Partitions resume 1 to N ps after each quantum boundary (round robin): the
// largest offset must stay below half a core cycle.
TEST(ConfigTree, PartitionResumeOffsetsFitInHalfACycle) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  t.set("clock.core_mhz", "10000");  // 100 ps cycles: offsets up to 49 ps
  t.set("partitions.count", "49");
  EXPECT_NO_THROW(t.validate());
  t.set("partitions.count", "50");
  const std::string e = errorOf([&] { t.validate(); });
  EXPECT_NE(e.find("partitions.count (50) at clock.core_mhz (10000 MHz): partition resume offsets of up to 50 ps do "
                   "not fit in half a 100.0 ps cycle"),
            std::string::npos)
      << e;
}

// The memory hierarchy's rules: one line naming the parameter and the rule each.
TEST(ConfigTree, CacheLinesAndSharedLevelsAreValidated) {
  const auto problem = [](std::vector<std::string> sets) {
    return errorOf([&] { resolveConfig("iris-pro-5200", "", sets); });
  };
  EXPECT_NE(problem({"cache.size_bytes=1024", "cache.ways=1", "cache.line_bytes=2048"}).find("cache.line_bytes"),
            std::string::npos);  // out of range (at most 1024) already
  // (A ROP-cache line never exceeds the cache: lines are at most 1 KiB, caches at least 1 KiB.)
  std::string e = problem({"cache.line_bytes=128", "cache.sector_bytes=48"});
  EXPECT_NE(e.find("cache.sector_bytes (48) must be a power of two dividing cache.line_bytes (128)"),
            std::string::npos) << e;
  e = problem({"cache.line_bytes=64", "cache.sector_bytes=128"});
  EXPECT_NE(e.find("cache.sector_bytes (128) must be a power of two dividing cache.line_bytes (64)"),
            std::string::npos) << e;
  e = problem({"cache.line_bytes=1024", "cache.sector_bytes=16"});
  EXPECT_NE(e.find("cache.line_bytes (1024) holds 64 sectors of cache.sector_bytes (16); at most 32"),
            std::string::npos) << e;
  e = problem({"cache.line_bytes=128"});  // the LLC's lines are 64 bytes
  EXPECT_NE(e.find("l2.line_bytes (64) is smaller than cache.line_bytes (128): a line of the level above must fit in "
                   "one l2 line"),
            std::string::npos) << e;
  e = problem({"l2.line_bytes=128"});  // the eDRAM's lines are 64 bytes
  EXPECT_NE(e.find("l3.line_bytes (64) is smaller than l2.line_bytes (128)"), std::string::npos) << e;
  e = problem({"l2.size_bytes=0"});
  EXPECT_NE(e.find("l3.size_bytes is set but l2.size_bytes is 0"), std::string::npos) << e;
  e = problem({"l2.size_bytes=5000000"});
  EXPECT_NE(e.find("l2.size_bytes (5000000) is not a multiple of l2.slices x l2.ways x l2.line_bytes (4 x 12 x 64 = "
                   "3072)"),
            std::string::npos) << e;
  e = problem({"l2.size_bytes=1024", "l2.ways=1", "l2.slices=1", "l2.line_bytes=4096"});
  EXPECT_NE(e.find("l2.line_bytes (4096) is larger than the cache, l2.size_bytes (1024)"), std::string::npos) << e;
  e = problem({"l3.sector_bytes=24"});
  EXPECT_NE(e.find("l3.sector_bytes (24) must be a power of two dividing l3.line_bytes (64)"), std::string::npos)
      << e;
  // One violation is one line; several are listed one line each.
  e = problem({"l2.size_bytes=0"});
  EXPECT_EQ(e.find('\n'), std::string::npos) << e;
  e = problem({"cache.sector_bytes=48", "l2.size_bytes=0"});
  EXPECT_NE(e.find(":\n  cache.sector_bytes (48)"), std::string::npos) << e;
  EXPECT_NE(e.find("\n  l3.size_bytes is set"), std::string::npos) << e;
  EXPECT_NO_THROW(resolveConfig("iris-pro-5200", "", {"l3.size_bytes=0", "l2.size_bytes=0"}));
}

}  // namespace config_validation_test
