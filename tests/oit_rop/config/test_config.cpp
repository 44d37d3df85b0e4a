// The configuration tree: presets, typed set(), errors, JSON files, precedence,
// round trip, and that every RopConfig field is registered.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <unistd.h>

#include "oit_rop/memory/BlendArrayCache.hpp"
#include "oit_rop/config/ConfigTree.hpp"

using namespace oit::rop;

namespace {

// Message of the std::invalid_argument `f` throws ("" if it does not throw).
template <class F>
std::string errorOf(F&& f) {
  try {
    f();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

class TempFile {
 public:
  TempFile(const std::string& name, const std::string& text)
      : path_((std::filesystem::temp_directory_path() /
               ("oitsim_cfg_" + std::to_string(::getpid()) + "_" + name)).string()) {
    std::ofstream(path_) << text;
  }
  ~TempFile() { std::filesystem::remove(path_); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

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

}  // namespace

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
  EXPECT_EQ(fieldCount<DramConfig>(), 23u);
  EXPECT_EQ(ConfigTree::forPreset("igpu").properties().size(), 90u);  // 52 + 20 (issue 21's levels) + 7 (its DRAM controller) + stats.level_miss_classes + 10 (issue 22: alu work costs, abuffer.*)
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
  // Apart from its caches it is the struct's base.
  RopConfig base;
  base.l2 = c.l2;
  base.l3 = c.l3;
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
