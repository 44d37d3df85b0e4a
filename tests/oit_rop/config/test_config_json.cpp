// Configuration files: nested and dotted JSON keys, errors naming the file and
// the key, number overflow, repeated keys, the precedence preset < file <
// --set, resolve errors and the JSON round trip.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "oit_rop/config/ConfigTestUtil.hpp"
#include "oit_rop/config/ConfigTree.hpp"

using namespace oit::rop;

namespace config_json_test {

using namespace oit::rop::config_testutil;

TEST(ConfigTree, JsonNestedAndDotted) {
  TempFile f("nested.json", R"({
    "lock": {"granularity": "quad", "mode": "unordered"},
    "dram.channels": 4,
    "dram": {"channel_gbps": 20.5},
    "cache": {"size_bytes": "128KiB"},
    // comments are allowed
    "skip.idle_cycles": false
  })");
  ConfigTree t = ConfigTree::forPreset("igpu");
  t.loadJson(f.path());
  const RopConfig& c = t.config();
  EXPECT_EQ(c.lock.granularity, LockGranularity::Quad);
  EXPECT_EQ(c.lock.mode, LockMode::Unordered);
  EXPECT_EQ(c.dram.channels, 4u);
  EXPECT_DOUBLE_EQ(c.dram.channel_gbps, 20.5);
  EXPECT_EQ(c.cache.size_bytes, 131072u);
  EXPECT_FALSE(c.skip.idle_cycles);
  EXPECT_EQ(c.clock.core_mhz, 1150.0);  // untouched
}

TEST(ConfigTree, JsonErrorsNameFileAndKey) {
  ConfigTree t = ConfigTree::forPreset("igpu");
  TempFile typo("typo.json", R"({"lock": {"granularty": "quad"}})");
  std::string e = errorOf([&] { t.loadJson(typo.path()); });
  EXPECT_NE(e.find(typo.path() + ": key 'lock/granularty': unknown property 'lock.granularty'; did you mean "
                                 "'lock.granularity'?"),
            std::string::npos)
      << e;
  TempFile type("type.json", R"({"dram.channels": true})");
  e = errorOf([&] { t.loadJson(type.path()); });
  EXPECT_NE(e.find(type.path() + ": key 'dram.channels': dram.channels: 'true' has the wrong JSON type (boolean)"),
            std::string::npos)
      << e;
  TempFile neg("neg.json", R"({"dram": {"channels": -1}})");
  e = errorOf([&] { t.loadJson(neg.path()); });
  EXPECT_NE(e.find("key 'dram/channels'"), std::string::npos) << e;
  EXPECT_NE(e.find("out of range"), std::string::npos) << e;
  TempFile huge("huge.json", R"({"input.seed": 18446744073709551616})");  // 2^64: JSON reads it as a double
  e = errorOf([&] { t.loadJson(huge.path()); });
  EXPECT_NE(e.find("input.seed: '1.8446744073709552e+19' is out of range"), std::string::npos) << e;
  TempFile twice("twice.json", R"({"dram": {"channels": 2}, "dram.channels": 4})");
  e = errorOf([&] { t.loadJson(twice.path()); });
  EXPECT_NE(e.find("dram.channels is given twice"), std::string::npos) << e;
  TempFile broken("broken.json", "{\"dram\": {\"channels\": 2,}");
  e = errorOf([&] { t.loadJson(broken.path()); });
  EXPECT_NE(e.find(broken.path() + ": not valid JSON"), std::string::npos) << e;
  TempFile other("other.json", R"({"preset": "dgpu"})");
  e = errorOf([&] { t.loadJson(other.path()); });
  EXPECT_NE(e.find("pass --preset dgpu"), std::string::npos) << e;
  e = errorOf([&] { t.loadJson("/nonexistent/x.json"); });
  EXPECT_EQ(e, "/nonexistent/x.json: cannot open config file");
}

// Every parse problem of a config file names the file: nlohmann's number
// overflow (an out_of_range, not a parse_error) included.
TEST(ConfigTree, JsonNumberOverflowNamesTheFile) {
  TempFile f("overflow.json", R"({"dram":{"channel_gbps":1e400}})");
  const std::string e = errorOf([&] { resolveConfig("igpu", f.path(), {}); });
  EXPECT_EQ(e, f.path() + ": not valid JSON: [json.exception.out_of_range.406] number overflow parsing '1e400'");
  ConfigTree t = ConfigTree::forPreset("igpu");
  EXPECT_EQ(errorOf([&] { t.loadJson(f.path()); }), e);
  TempFile syntax("syntax.json", "{\"lock\": {\"capacity\": 64}\n  \"x\": 1}");
  const std::string s = errorOf([&] { resolveConfig("igpu", syntax.path(), {}); });
  EXPECT_NE(s.find(syntax.path() + ": not valid JSON: [json.exception.parse_error.101] parse error at line 2, column 5"),
            std::string::npos)
      << s;
}

// JSON parsers keep the last of a repeated key silently; a config file must not.
TEST(ConfigTree, JsonRepeatedKeyInOneObjectIsAnError) {
  TempFile top("dup_top.json", R"({"lock":{"capacity":64},"lock":{"capacity":32}})");
  std::string e = errorOf([&] { resolveConfig("igpu", top.path(), {}); });
  EXPECT_EQ(e, top.path() +
                   ": key 'lock' appears twice in the same JSON object (the second would silently replace the "
                   "first); give each key once");
  TempFile nested("dup_nested.json", R"({"dram":{"channels":2, "banks":4, "channels":4}})");
  ConfigTree t = ConfigTree::forPreset("igpu");
  e = errorOf([&] { t.loadJson(nested.path()); });
  EXPECT_NE(e.find(nested.path() + ": key 'dram/channels' appears twice in the same JSON object"), std::string::npos)
      << e;
  // The same key in different objects is fine.
  TempFile ok("dup_ok.json",
              R"({"early_depth":{"enabled":true}, "skip":{"early_depth":false}, "lock":{"capacity":32}})");
  const RopConfig c = resolveConfig("igpu", ok.path(), {});
  EXPECT_EQ(c.lock.capacity, 32u);
  EXPECT_FALSE(c.skip.early_depth);
}

TEST(ConfigTree, PrecedencePresetFileSet) {
  TempFile f("prec.json", R"({"dram": {"channels": 3, "banks": 4}, "clock.core_mhz": 900})");
  // dgpu (titan-x-maxwell) preset: 6 channels, 16 banks, 1075 MHz; file: 3 channels, 4 banks, 900 MHz; set: 5 channels.
  const RopConfig c = resolveConfig("dgpu", f.path(), {"dram.channels=5"});
  EXPECT_EQ(c.dram.channels, 5u);                // --set beats the file
  EXPECT_EQ(c.dram.banks, 4u);                   // the file beats the preset
  EXPECT_DOUBLE_EQ(c.clock.core_mhz, 900.0);     // the file beats the preset
  EXPECT_DOUBLE_EQ(c.dram.channel_gbps, 56.0);   // the preset where nobody overrides
  EXPECT_EQ(c.preset, "titan-x-maxwell");
  // Later --set wins over an earlier one.
  EXPECT_EQ(resolveConfig("igpu", "", {"dram.channels=2", "dram.channels=7"}).dram.channels, 7u);
  EXPECT_EQ(resolveConfig("", "", {}), presetConfig("iris-pro-5200"));  // the default preset
}

TEST(ConfigTree, ResolveErrors) {
  std::string e = errorOf([] { resolveConfig("igpu", "", {"lock.granularity"}); });
  EXPECT_EQ(e, "--set 'lock.granularity': expected path=value, e.g. --set lock.granularity=quad");
  e = errorOf([] { resolveConfig("igpu", "", {"=quad"}); });
  EXPECT_NE(e.find("--set '=quad': expected path=value"), std::string::npos) << e;
  e = errorOf([] { resolveConfig("igpu", "", {"lock.granularity=hex"}); });
  EXPECT_NE(e.find("--set 'lock.granularity=hex': lock.granularity: 'hex' is not a known value"), std::string::npos)
      << e;
  e = errorOf([] { resolveConfig("igpu", "", {"input.latency_max=10"}); });  // validated at the end
  EXPECT_NE(e.find("input.latency_min (40) > input.latency_max (10)"), std::string::npos) << e;
  // An override may repair what the file broke: validation runs once, at the end.
  TempFile f("repair.json", R"({"input": {"latency_min": 500}})");
  EXPECT_EQ(resolveConfig("igpu", f.path(), {"input.latency_max=600"}).input.latency_max, 600u);
}

TEST(ConfigTree, JsonRoundTrip) {
  for (const std::string& preset : presetNames()) {
    ConfigTree t = ConfigTree::forPreset(preset);
    // Move every kind of property off its preset value.
    t.set("lock.granularity", "tile");
    t.set("clock.core_mhz", "1234.5678901234567");
    t.set("input.seed", "18446744073709551615");
    t.set("skip.lazy_merge", "false");
    t.set("dram.tck_ns", "0.1");
    const nlohmann::json j = t.toJson();
    EXPECT_EQ(j["lock"]["granularity"], "tile");
    EXPECT_EQ(j["preset"], preset);
    TempFile f("rt_" + preset + ".json", j.dump(2));
    ConfigTree back = ConfigTree::forPreset(preset);
    back.loadJson(f.path());
    EXPECT_EQ(back.config(), t.config()) << preset;
    EXPECT_NE(back.config(), ConfigTree::forPreset(preset).config());
    // Without --preset, the file's "preset" key selects the preset.
    EXPECT_EQ(resolveConfig("", f.path(), {}), t.config()) << preset;
  }
}

}  // namespace config_json_test
