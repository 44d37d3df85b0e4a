// The presets (iris-pro-5200, titan-x-maxwell, navi21): names, aliases and
// their values.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "oit_rop/config/ConfigTestUtil.hpp"
#include "oit_rop/config/ConfigTree.hpp"

using namespace oit::rop;

namespace presets_test {

using namespace oit::rop::config_testutil;

TEST(ConfigTree, PresetNamesAndAliases) {
  EXPECT_EQ(presetNames(), (std::vector<std::string>{"iris-pro-5200", "titan-x-maxwell", "navi21"}));
  EXPECT_EQ(canonicalPresetName("igpu"), "iris-pro-5200");
  EXPECT_EQ(canonicalPresetName("dgpu"), "titan-x-maxwell");
  EXPECT_EQ(canonicalPresetName("navi21"), "navi21");
  const std::string e = errorOf([] { ConfigTree::forPreset("apu"); });
  EXPECT_NE(e.find("unknown preset 'apu'"), std::string::npos) << e;
  EXPECT_NE(e.find("iris-pro-5200, titan-x-maxwell, navi21"), std::string::npos) << e;
  EXPECT_NE(e.find("igpu = iris-pro-5200"), std::string::npos) << e;
  // An alias is the preset it names, under the preset's own name.
  EXPECT_EQ(ConfigTree::forPreset("igpu").config(), ConfigTree::forPreset("iris-pro-5200").config());
  EXPECT_EQ(ConfigTree::forPreset("dgpu").config(), ConfigTree::forPreset("titan-x-maxwell").config());
  EXPECT_EQ(ConfigTree::forPreset("igpu").preset(), "iris-pro-5200");
  // A file written for an alias loads under the preset (and the other way round).
  TempFile f("alias.json", R"({"preset": "igpu", "lock": {"capacity": 64}})");
  EXPECT_EQ(resolveConfig("iris-pro-5200", f.path(), {}).lock.capacity, 64u);
  EXPECT_EQ(resolveConfig("", f.path(), {}).preset, "iris-pro-5200");
}

TEST(ConfigTree, IrisPro5200Preset) {
  const ConfigTree t = ConfigTree::forPreset("iris-pro-5200");
  const RopConfig& c = t.config();
  EXPECT_EQ(c.preset, "iris-pro-5200");
  EXPECT_DOUBLE_EQ(c.clock.core_mhz, 1150.0);
  EXPECT_DOUBLE_EQ(c.dram.channels * c.dram.channel_gbps, 25.6);  // dual-channel DDR3-1600
  EXPECT_EQ(c.partitions.count * c.alu.blends_per_clock, 4u);     // 4 px/clk in total
  EXPECT_EQ(c.cache.size_bytes, 64u * 1024);                      // 2 x 64 KiB over 2 partitions
  EXPECT_EQ(c.cache.line_bytes, 64u);
  EXPECT_EQ(c.l2.size_bytes, 6u << 20);     // the 6 MB LLC
  EXPECT_EQ(c.l3.size_bytes, 128u << 20);   // the 128 MB eDRAM
  EXPECT_TRUE(c.l3.victim_only);            // filled with the LLC's evictions
  EXPECT_EQ(c.dram.cl, 11u);
  EXPECT_EQ(c.dram.trcd, 11u);
  EXPECT_EQ(c.dram.trp, 11u);
  EXPECT_DOUBLE_EQ(c.dram.tck_ns, 1.25);
  EXPECT_EQ(c.dram.banks, 8u);
  EXPECT_EQ(c.dram.trrd, 5u);   // DDR3-1600 x8: max(4 nCK, 6 ns)
  EXPECT_EQ(c.dram.tfaw, 24u);  // 30 ns
  // Apart from its caches and activate limits it is the struct's base.
  RopConfig base;
  base.l2 = c.l2;
  base.l3 = c.l3;
  base.dram.trrd = c.dram.trrd;
  base.dram.tfaw = c.dram.tfaw;
  EXPECT_EQ(c, base);
  EXPECT_NO_THROW(t.validate());
}

TEST(ConfigTree, TitanXMaxwellPreset) {
  const ConfigTree t = ConfigTree::forPreset("titan-x-maxwell");
  const RopConfig& c = t.config();
  EXPECT_DOUBLE_EQ(c.clock.core_mhz, 1075.0);
  EXPECT_DOUBLE_EQ(c.dram.channels * c.dram.channel_gbps, 336.0);  // 384-bit GDDR5 at 7 Gbps
  EXPECT_EQ(c.partitions.count, 6u);                               // six memory controllers
  EXPECT_EQ(c.partitions.count * c.alu.blends_per_clock, 96u);     // 96 ROPs
  EXPECT_EQ(c.l2.size_bytes, 3u << 20);
  EXPECT_EQ(c.l2.slices, 6u);
  EXPECT_EQ(c.l3.size_bytes, 0u);
  EXPECT_EQ(c.dram.cl, 24u);
  EXPECT_DOUBLE_EQ(c.dram.tck_ns, 0.667);
  EXPECT_EQ(c.dram.banks, 16u);
  EXPECT_NO_THROW(t.validate());
}

TEST(ConfigTree, Navi21Preset) {
  const ConfigTree t = ConfigTree::forPreset("navi21");
  const RopConfig& c = t.config();
  EXPECT_DOUBLE_EQ(c.clock.core_mhz, 2015.0);
  EXPECT_DOUBLE_EQ(c.dram.channels * c.dram.channel_gbps, 512.0);  // 256-bit GDDR6 at 16 Gbps
  EXPECT_EQ(c.partitions.count * c.alu.blends_per_clock, 128u);    // 128 ROPs
  EXPECT_EQ(c.l2.size_bytes, 4u << 20);
  EXPECT_EQ(c.l3.size_bytes, 128u << 20);  // Infinity Cache
  EXPECT_FALSE(c.l3.victim_only);
  EXPECT_NO_THROW(t.validate());
}

}  // namespace presets_test
