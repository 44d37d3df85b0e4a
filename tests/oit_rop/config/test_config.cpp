// The configuration tree: typed set() of each property type, errors naming
// the closest path, the lock mode and its retired flag, bad values, the warp
// size. The registry: test_config_registry.cpp; presets: test_presets.cpp;
// JSON files and precedence: test_config_json.cpp; cross-field validation:
// test_config_validation.cpp.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "oit_rop/config/ConfigTestUtil.hpp"
#include "oit_rop/config/ConfigTree.hpp"

using namespace oit::rop;

namespace config_set_test {

using namespace oit::rop::config_testutil;

TEST(ConfigTree, SetEachType) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  t.set("lock.granularity", "quad");
  t.set("lock.release", "end_of_shader");
  t.set("input.latency_model", "fixed");
  t.set("skip.idle_cycles", "false");
  t.set("lock.mode", "none");
  t.set("dram.channel_gbps", "17.066");
  t.set("dram.channels", " 3 ");
  t.set("cache.size_bytes", "256KiB");
  t.set("input.seed", "18446744073709551615");
  const RopConfig& c = t.config();
  EXPECT_EQ(c.lock.granularity, LockGranularity::Quad);
  EXPECT_EQ(c.lock.release, LockRelease::EndOfShader);
  EXPECT_EQ(c.input.latency_model, LatencyModel::Fixed);
  EXPECT_FALSE(c.skip.idle_cycles);
  EXPECT_EQ(c.lock.mode, LockMode::None);
  EXPECT_DOUBLE_EQ(c.dram.channel_gbps, 17.066);
  EXPECT_EQ(c.dram.channels, 3u);
  EXPECT_EQ(c.cache.size_bytes, 262144u);
  EXPECT_EQ(c.input.seed, 18446744073709551615ull);
  t.set("skip.idle_cycles", "1");
  EXPECT_TRUE(t.config().skip.idle_cycles);
}

TEST(ConfigTree, UnknownPathSuggestsClosest) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  std::string e = errorOf([&] { t.set("lock.granularty", "quad"); });
  EXPECT_NE(e.find("unknown property 'lock.granularty'"), std::string::npos) << e;
  EXPECT_NE(e.find("did you mean 'lock.granularity'?"), std::string::npos) << e;
  e = errorOf([&] { t.set("channel_gbps", "1"); });  // leaf without its group
  EXPECT_NE(e.find("did you mean 'dram.channel_gbps'?"), std::string::npos) << e;
  e = errorOf([&] { t.set("lock", "1"); });
  EXPECT_NE(e.find("'lock' is a group"), std::string::npos) << e;
  EXPECT_NE(e.find("lock.capacity"), std::string::npos) << e;
  e = errorOf([&] { t.set("completely.unrelated.thing", "1"); });
  EXPECT_NE(e.find("groups: clock"), std::string::npos) << e;
  EXPECT_EQ(e.find("did you mean"), std::string::npos) << e;
}

// lock.mode names the interlock; the boolean it replaced (lock.ordered) is
// refused naming its successor, from --set and from a file alike; an unknown
// mode lists the three.
TEST(ConfigTree, LockModeAndTheRetiredOrderedFlag) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  EXPECT_EQ(t.config().lock.mode, LockMode::Ordered);  // the default: the functional model's order
  for (const auto& [name, mode] : {std::pair{"ordered", LockMode::Ordered}, std::pair{"unordered", LockMode::Unordered},
                                   std::pair{"none", LockMode::None}}) {
    t.set("lock.mode", name);
    EXPECT_EQ(t.config().lock.mode, mode);
    EXPECT_STREQ(lockModeName(mode), name);
  }
  const std::string retired =
      "'lock.ordered' was replaced by lock.mode (ordered | unordered | none): lock.ordered=true is "
      "lock.mode=ordered; lock.ordered=false is lock.mode=unordered, whose image now follows the order the fragments "
      "enter the lock (oit_rop/DESIGN.md)";
  EXPECT_EQ(errorOf([&] { t.set("lock.ordered", "false"); }), retired);
  TempFile old("old.json", R"({"lock": {"ordered": false}})");
  EXPECT_EQ(errorOf([&] { t.loadJson(old.path()); }), old.path() + ": key 'lock/ordered': " + retired);
  EXPECT_EQ(errorOf([&] { t.set("lock.mode", "sometimes"); }),
            "lock.mode: 'sometimes' is not a known value; expected one of ordered | unordered | none");
}

TEST(ConfigTree, BadValues) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  std::string e = errorOf([&] { t.set("lock.granularity", "diagonal"); });
  EXPECT_EQ(e, "lock.granularity: 'diagonal' is not a known value; expected one of pixel | quad | tile");
  e = errorOf([&] { t.set("dram.channels", "0"); });
  EXPECT_EQ(e, "dram.channels: '0' is out of range; expected an integer [1, 64]");
  e = errorOf([&] { t.set("clock.core_mhz", "fast"); });
  EXPECT_EQ(e, "clock.core_mhz: 'fast' is not a number; expected a number [1, 10000] (MHz)");
  e = errorOf([&] { t.set("clock.core_mhz", "0"); });
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  e = errorOf([&] { t.set("dram.channels", "-2"); });
  EXPECT_NE(e.find("not a non-negative integer"), std::string::npos) << e;
  e = errorOf([&] { t.set("dram.channels", "2.5"); });
  EXPECT_NE(e.find("not a non-negative integer"), std::string::npos) << e;
  e = errorOf([&] { t.set("partitions.tile_width", "12"); });
  EXPECT_NE(e.find("not a power of two"), std::string::npos) << e;
  e = errorOf([&] { t.set("partitions.tile_width", "128"); });
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  e = errorOf([&] { t.set("skip.fast_clear", "maybe"); });
  EXPECT_NE(e.find("not a boolean"), std::string::npos) << e;
  e = errorOf([&] { t.set("dram.channels", "4KiB"); });  // suffixes only for bytes
  EXPECT_NE(e.find("not a non-negative integer"), std::string::npos) << e;
  e = errorOf([&] { t.set("input.seed", "18446744073709551616"); });
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  // A stage takes at least one cycle: 0 was accepted and ran as 1.
  e = errorOf([&] { t.set("input.latency_min", "0"); });
  EXPECT_EQ(e, "input.latency_min: '0' is out of range; expected an integer [1, 1000000] (cycles)");
  // The shared levels keep 2 x quantum cycles of port bookings: at most 100000.
  e = errorOf([&] { t.set("sim.quantum_cycles", "1000000"); });
  EXPECT_EQ(e, "sim.quantum_cycles: '1000000' is out of range; expected an integer [1, 100000] (cycles)");
  e = errorOf([&] { t.set("early_depth.latency", "0"); });
  EXPECT_EQ(e, "early_depth.latency: '0' is out of range; expected an integer [1, 10000] (cycles)");
  // A number past the double range is a range error too (it said "not a number").
  e = errorOf([&] { t.set("clock.core_mhz", "1e400"); });
  EXPECT_EQ(e, "clock.core_mhz: '1e400' is out of range; expected a number [1, 10000] (MHz)");
  e = errorOf([&] { t.set("preset", "dgpu"); });
  EXPECT_NE(e.find("--preset"), std::string::npos) << e;
  // A failed set leaves the tree unchanged.
  EXPECT_EQ(t.config(), ConfigTree::forPreset("igpu").config());
}

// input.warp_size: a power of two from 1 to 1024; both presets keep 1 (every
// fragment draws its own shader latency).
TEST(ConfigTree, WarpSize) {
  for (const std::string& preset : presetNames()) EXPECT_EQ(ConfigTree::forPreset(preset).config().input.warp_size, 1u);
  ConfigTree t = ConfigTree::forPreset("igpu");
  std::string e = errorOf([&] { t.set("input.warp_size", "3"); });
  EXPECT_EQ(e, "input.warp_size: '3' is not a power of two; expected an integer [1, 1024], power of two (fragments)");
  e = errorOf([&] { t.set("input.warp_size", "0"); });
  EXPECT_NE(e.find("input.warp_size: '0' is out of range"), std::string::npos) << e;
  e = errorOf([&] { t.set("input.warp_size", "2048"); });
  EXPECT_NE(e.find("input.warp_size: '2048' is out of range"), std::string::npos) << e;
  e = errorOf([] { resolveConfig("igpu", "", {"input.warp_size=3"}); });
  EXPECT_EQ(e.rfind("--set 'input.warp_size=3': input.warp_size: '3' is not a power of two", 0), 0u) << e;
  EXPECT_EQ(t.config(), ConfigTree::forPreset("igpu").config());  // refused values leave the tree unchanged

  t.set("input.warp_size", "64");
  EXPECT_EQ(t.config().input.warp_size, 64u);
  EXPECT_NO_THROW(t.validate());
  EXPECT_EQ(resolveConfig("dgpu", "", {"input.warp_size=64"}).input.warp_size, 64u);
  // The effective configuration lists it, changed from the preset's 1.
  const std::string d = t.describe();
  const size_t row = d.find("input.warp_size ");
  ASSERT_NE(row, std::string::npos) << d;
  const std::string line = d.substr(row, d.find('\n', row) - row);
  EXPECT_NE(line.find(" 64 "), std::string::npos) << line;
  EXPECT_NE(line.find("fragments"), std::string::npos) << line;
  EXPECT_NE(line.find(" 1 "), std::string::npos) << line;  // the preset's value
  EXPECT_EQ(d[d.rfind('\n', row) + 1], '*');
  EXPECT_EQ(t.toJson()["input"]["warp_size"], 64);
}

}  // namespace config_set_test
