// The property registry: every RopConfig field is a property, each with a
// unit and a description; the printed table and the presets' Markdown table
// list every property.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "oit_rop/config/ConfigTestUtil.hpp"
#include "oit_rop/config/ConfigTree.hpp"

using namespace oit::rop;

namespace config_registry_test {

using namespace oit::rop::config_testutil;

// Number of members of an aggregate (C++20: the largest N for which T{a1..aN} compiles).
struct AnyInit {
  template <class U>
  operator U() const;
};
template <class T, class... A>
constexpr size_t fieldCount() {
  if constexpr (requires { T{A{}..., AnyInit{}}; })
    return fieldCount<T, A..., AnyInit>();
  else
    return sizeof...(A);
}

size_t propertiesUnder(const std::string& section) {
  size_t n = 0;
  for (const auto& p : ConfigTree::forPreset("igpu").properties())
    if (p.path.rfind(section + ".", 0) == 0) ++n;
  return n;
}

TEST(ConfigTree, EveryFieldIsAProperty) {
  // A field added to RopConfig without a registry row fails here.
  EXPECT_EQ(propertiesUnder("clock"), fieldCount<ClockConfig>());
  EXPECT_EQ(propertiesUnder("partitions"), fieldCount<PartitionConfig>());
  EXPECT_EQ(propertiesUnder("input"), fieldCount<InputConfig>());
  EXPECT_EQ(propertiesUnder("early_depth"), fieldCount<EarlyDepthConfig>());
  EXPECT_EQ(propertiesUnder("lock"), fieldCount<LockConfig>());
  EXPECT_EQ(propertiesUnder("cache"), fieldCount<CacheConfig>());
  EXPECT_EQ(propertiesUnder("memory"), fieldCount<MemoryLayoutConfig>());
  EXPECT_EQ(propertiesUnder("l2"), fieldCount<SharedCacheConfig>());
  EXPECT_EQ(propertiesUnder("l3"), fieldCount<SharedCacheConfig>());
  EXPECT_EQ(propertiesUnder("alu"), fieldCount<AluConfig>());
  EXPECT_EQ(propertiesUnder("dram"), fieldCount<DramConfig>());
  EXPECT_EQ(propertiesUnder("stats"), fieldCount<StatsConfig>());
  EXPECT_EQ(propertiesUnder("skip"), fieldCount<SkipConfig>());
  EXPECT_EQ(propertiesUnder("sim"), fieldCount<SimConfig>());
  EXPECT_EQ(fieldCount<ClockConfig>(), 1u);  // the counter itself works
  EXPECT_EQ(fieldCount<DramConfig>(), 30u);
  EXPECT_EQ(ConfigTree::forPreset("igpu").properties().size(), 97u);  // 52 + 20 (issue 21's levels) + 7 (its DRAM controller) + stats.level_miss_classes + 10 (issue 22: alu work costs, abuffer.*) + dram.trrd, dram.tfaw + dram.bank_groups, tccd_s, tccd_l, trrd_l, twtr_l
}

TEST(ConfigTree, PropertiesHaveUnitsAndDescriptions) {
  std::set<std::string> paths;
  for (const auto& p : ConfigTree::forPreset("dgpu").properties()) {
    EXPECT_TRUE(paths.insert(p.path).second) << "duplicate " << p.path;
    EXPECT_FALSE(p.description.empty()) << p.path;
    EXPECT_FALSE(p.allowed.empty()) << p.path;
    EXPECT_EQ(p.value, p.default_value) << p.path;
  }
  const auto props = ConfigTree::forPreset("igpu").properties();
  auto get = [&](const std::string& path) {
    for (const auto& p : props)
      if (p.path == path) return p;
    ADD_FAILURE() << path;
    return PropertyInfo{};
  };
  EXPECT_EQ(get("clock.core_mhz").unit, "MHz");
  EXPECT_EQ(get("dram.channel_gbps").unit, "GB/s");
  EXPECT_EQ(get("cache.size_bytes").unit, "bytes");
  EXPECT_EQ(get("input.fragments_per_clock").unit, "fragments/clock");
  EXPECT_EQ(get("lock.granularity").type, PropertyType::Enum);
  EXPECT_EQ(get("lock.granularity").allowed, "pixel | quad | tile");
  EXPECT_EQ(get("lock.per_primitive").allowed, "true | false");
  EXPECT_EQ(get("lock.per_primitive").value, "true");
  EXPECT_EQ(get("partitions.tile_width").allowed, "[1, 64], power of two");
  EXPECT_EQ(get("alu.fp16_rate").allowed, "[0.001, 1]");
  EXPECT_NE(get("alu.fp16_rate").description.find("[inferred]"), std::string::npos);
  EXPECT_TRUE(get("alu.fp16_rate").inferred);
  EXPECT_FALSE(get("clock.core_mhz").inferred);
}

TEST(ConfigTree, DescribeListsEveryProperty) {
  ConfigTree t = ConfigTree::forPreset("dgpu");
  t.set("lock.granularity", "quad");
  const std::string d = t.describe();
  for (const auto& p : t.properties()) EXPECT_NE(d.find(p.path + " "), std::string::npos) << p.path;
  EXPECT_NE(d.find("preset titan-x-maxwell"), std::string::npos);
  // The changed row shows the preset's value as the default; unchanged rows do not.
  const size_t row = d.find("lock.granularity");
  const std::string line = d.substr(row, d.find('\n', row) - row);
  EXPECT_NE(line.find("quad"), std::string::npos) << line;
  EXPECT_NE(line.find("pixel"), std::string::npos) << line;
  EXPECT_EQ(d[d.rfind('\n', row) + 1], '*');
  const size_t mhz = d.find("clock.core_mhz");
  EXPECT_EQ(d[d.rfind('\n', mhz) + 1], ' ');
}

TEST(ConfigTree, MarkdownTableHasEveryPreset) {
  const std::string md = presetTableMarkdown();
  EXPECT_NE(md.find("| property | unit | iris-pro-5200 | titan-x-maxwell | navi21 |"), std::string::npos);
  EXPECT_NE(md.find("| `dram.channel_gbps` | GB/s | 12.8 | 56 | 32 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| `l2.size_bytes` | bytes | 6291456 | 3145728 | 4194304 (i) |"), std::string::npos) << md;
  EXPECT_NE(md.find("pixel \\| quad \\| tile"), std::string::npos) << md;  // pipes escaped in cells
  // Every row has the header's 6 cells: no unescaped '|' inside a value or description.
  size_t rows = 0;
  for (size_t b = 0, e; b < md.size(); b = e + 1) {
    e = md.find('\n', b);
    if (e == std::string::npos) e = md.size();
    const std::string line = md.substr(b, e - b);
    if (line.empty()) continue;
    size_t pipes = 0;
    for (size_t k = 0; k < line.size(); ++k) pipes += line[k] == '|' && (k == 0 || line[k - 1] != '\\');
    EXPECT_EQ(pipes, 8u) << line;
    ++rows;
  }
  EXPECT_EQ(rows, 2u + ConfigTree::forPreset("igpu").properties().size());
}

}  // namespace config_registry_test
