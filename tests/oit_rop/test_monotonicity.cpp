// Monotonicity (issue 21, "What must hold"): every resource knob one step
// worse (fewer partitions, smaller caches, fewer ways, lower bandwidth,
// longer latencies, coarser lock, end-of-shader release, smaller queues; the
// DRAM controller's turnarounds, tRRD, refresh, write queue and scheduler too) on
// three scenes; no frame may get faster by more than 0.5 % (a smaller
// scoreboard only by cutting the ROP cache's thrashing, below). The base is
// iris-pro-5200 with its caches scaled to the scenes (an 8 KiB ROP cache, a
// 64 KiB l2, a 256 KiB victim l3), so that every level is exercised. The l3
// holds each scene's whole working set (96 x 64 x 32 B of arrays plus depth
// and colour: about 250 KB), so no byte reaches DRAM from that base: the DRAM
// steps are taken from the same base without the l3 (the l2's misses go to
// DRAM), and each of them must move at least one scene's frame (with the l3
// none of the 18 did: the steps could not fail).
#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "oit_rop/RopTestUtil.hpp"
#include "oit_rop/config/ConfigTree.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

struct Scene {
  std::string name;
  uint32_t w, h;
  std::vector<Fragment> fs;
};

// Particles: 8x8 quads at random places and depths, random submission
// order; with `backdrop`, first an opaque wall over the frame at depth 0.6
// to 0.9 (a slope: HiZ decides only some tiles, the rest read depth tiles).
std::vector<Fragment> particles(uint32_t w, uint32_t h, unsigned quads, uint32_t seed, bool backdrop = false) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Fragment> fs;
  if (backdrop)
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x)
        fs.push_back(model::testutil::frag(uint16_t(x), uint16_t(y), 0.6f + 0.3f * float(x) / float(w), 0.2f, 0.3f,
                                           0.4f, 1.0f, model::testutil::kOpaqueDraw, 0));
  for (unsigned q = 0; q < quads; ++q) {
    const uint32_t x0 = rng() % (w - 8), y0 = rng() % (h - 8);
    const float z = u(rng), a = 0.1f + 0.5f * u(rng);
    for (uint32_t y = y0; y < y0 + 8; ++y)
      for (uint32_t x = x0; x < x0 + 8; ++x)
        fs.push_back(model::testutil::frag(uint16_t(x), uint16_t(y), z, u(rng), u(rng), u(rng), a,
                                           model::testutil::kTranspDraw, q));
  }
  return fs;
}


const std::vector<Scene>& scenes() {
  static const std::vector<Scene> s = {
      {"particles_over_wall", 96, 64, particles(96, 64, 600, 21, true)},  // depth reads, culled fragments
      {"particles", 96, 64, particles(96, 64, 600, 5)},
      {"sweeps", 64, 64, layerSweeps(64, 64, 6, 1.0f / 64.0f)},
  };
  return s;
}

// A step of the DRAM controller's: taken from the base without the l3.
bool isDramStep(const std::string& path) { return path.rfind("dram.", 0) == 0; }

// The base, with one property changed (path empty: none), checked as --set
// would be; `dram_base`: without the l3, so that DRAM is reached.
RopConfig configWith(SimEngine engine, bool dram_base, const std::string& path = "", const std::string& value = "") {
  ConfigTree t = ConfigTree::forPreset("iris-pro-5200");
  t.set("cache.size_bytes", "8KiB");
  t.set("l2.size_bytes", "64KiB");  // 4 slices x 16 sets x 16 ways x 64 B
  t.set("l2.ways", "16");
  t.set("l3.size_bytes", dram_base ? "0" : "256KiB");
  t.set("stats.interval_cycles", "100000");
  // Two bank groups without longer in-group timings: the same frames as none
  // (test_dram_bank_groups.cpp); the dram.*_l steps need them.
  t.set("dram.bank_groups", "2");
  if (!path.empty()) t.set(path, value);
  t.validate();
  RopConfig c = t.config();
  c.sim.engine = engine;
  return c;
}

// One step worse, knob by knob (path = the value that is worse than the base's).
const std::vector<std::pair<std::string, std::string>>& worseSteps() {
  static const std::vector<std::pair<std::string, std::string>> v = {
      {"partitions.count", "1"},
      {"input.fragments_per_clock", "1"},
      {"input.latency_min", "80"},
      {"input.latency_max", "240"},
      {"early_depth.latency", "8"},
      {"early_depth.hierarchical", "false"},
      {"lock.capacity", "128"},
      {"lock.granularity", "quad"},
      {"lock.granularity", "tile"},
      {"lock.release", "end_of_shader"},
      {"lock.shader_tail", "40"},
      {"cache.size_bytes", "4KiB"},
      {"cache.ways", "4"},
      {"cache.miss_queue", "8"},
      {"cache.hit_latency", "20"},
      {"alu.blends_per_clock", "1"},
      {"alu.base_latency", "16"},
      {"alu.cycles_per_row_moved", "4"},
      {"alu.cycles_per_compare", "2"},
      {"l2.size_bytes", "32KiB"},
      {"l2.ways", "8"},
      {"l2.slices", "2"},
      {"l2.hit_latency", "100"},
      {"l2.bytes_per_clock", "8"},
      {"l3.size_bytes", "128KiB"},
      {"l3.ways", "8"},
      {"l3.hit_latency", "160"},
      {"l3.bytes_per_clock", "20"},
      {"dram.channels", "1"},
      {"dram.channel_gbps", "6.4"},
      {"dram.cl", "15"},
      {"dram.trcd", "15"},
      {"dram.trp", "15"},
      {"dram.tras", "40"},
      {"dram.banks", "4"},
      {"dram.controller_ns", "80"},
      {"dram.twtr", "12"},
      {"dram.trtw", "6"},
      {"dram.trrd", "6"},   // the base's 5 tCK; 4 x 6 still within its tFAW of 24
      // No dram.tfaw step: on these scenes the four-activate window hardly
      // binds (24 -> 32 tCK moved no cycle-engine frame once the l2 waits for
      // DRAM write room, and made the approximate engine's particles over the
      // wall 0.56 % faster, both partitions sooner; 40 and 48 tCK made frames
      // up to 1.25 % faster: DESIGN.md, "Monotonicity of the DRAM steps").
      // tFAW is checked against hand-derived bounds instead (test_bounds.cpp
      // DramActivateLimitFrame, memory/test_dram_bounds.cpp).
      {"dram.tccd_l", "5"},   // the base's column spacing is the 4-tCK burst
      // No dram.trrd_l step, for tFAW's reason: 5 -> 7 made the cycle engine's
      // particles 1.57 % faster (1.04 and -0.15 % on input.seed 2 and 3), the
      // partitions' mean end 0.77 % sooner, with fewer l2 misses (16,728
      // against 16,773). Longer activate spacing (tRRD, tRRD_L, tFAW) speeding
      // DRAM-bound frames is an open question (DESIGN.md, "Monotonicity of the
      // DRAM steps"); tRRD_L is checked against hand-derived bounds instead
      // (memory/test_dram_bank_groups.cpp).
      {"dram.twtr_l", "9"},   // the base's tWTR 6
      {"dram.trefi_ns", "3900"},
      {"dram.trfc_ns", "350"},
      {"dram.write_queue", "60"},
      {"dram.queue_depth", "8"},
      {"dram.scheduler", "fcfs"},
  };
  return v;
}

class Monotonicity : public ::testing::TestWithParam<SimEngine> {};

TEST_P(Monotonicity, NoResourceOneStepWorseMakesAFrameFaster) {
  model::AlgorithmParams p;
  p.layers = 4;
  p.format = model::StorageFormat::Rgba8T8Z32;
  double worst = -1;  // the largest speed-up any step gave (negative: every step slowed the frame)
  std::string worst_what;
  std::set<std::string> dram_steps_that_moved;
  for (const Scene& sc : scenes()) {
    ChildRun refs[2];  // [dram_base]
    for (const bool dram_base : {false, true}) {
      const RopConfig b = configWith(GetParam(), dram_base);
      refs[dram_base] = runInChild([&] { return timed("mlab", p, sc.fs, sc.w, sc.h, b); });
      ASSERT_TRUE(refs[dram_base].ok) << refs[dram_base].error;
    }
    // The two bases: no DRAM byte with the l3, some without it.
    const auto dramBytes = [](const ChildRun& x) {
      return x.stats["memory"]["dram_read_bytes"]["total"].get<uint64_t>() +
             x.stats["memory"]["dram_write_bytes"]["total"].get<uint64_t>();
    };
    EXPECT_EQ(dramBytes(refs[false]), 0u) << sc.name;
    EXPECT_GT(dramBytes(refs[true]), 0u) << sc.name;
    for (const auto& [path, value] : worseSteps()) {
      const ChildRun& ref = refs[isDramStep(path)];
      const double base_cycles = double(ref.stats["timing"]["cycles"].get<uint64_t>());
      const RopConfig worse = configWith(GetParam(), isDramStep(path), path, value);
      const auto r = runInChild([&] { return timed("mlab", p, sc.fs, sc.w, sc.h, worse); });
      ASSERT_TRUE(r.ok) << sc.name << " " << path << "=" << value << ": " << r.error;
      const double cycles = double(r.stats["timing"]["cycles"].get<uint64_t>());
      if (isDramStep(path) && cycles != base_cycles) dram_steps_that_moved.insert(path + "=" + value);
      const auto why = [](const ChildRun& x) {
        const auto& m = x.stats["memory"];
        return "cache misses " + std::to_string(x.stats["cache"]["misses"].get<uint64_t>()) + ", l2 misses " +
               std::to_string(m["levels"][1]["misses"].get<uint64_t>()) + ", DRAM bytes " +
               std::to_string(m["dram_read_bytes"]["total"].get<uint64_t>() +
                              m["dram_write_bytes"]["total"].get<uint64_t>()) +
               ", lock waits " + std::to_string(x.stats["lock"]["wait_cycles"].get<uint64_t>());
      };
      const double faster = 1 - cycles / base_cycles;
      if (faster > worst) {
        worst = faster;
        worst_what = sc.name + " " + path + "=" + value;
      }
      // The one documented exception: a smaller scoreboard holds fewer
      // fragments in flight, so fewer lines compete for a small ROP cache
      // (DESIGN.md, PixelLock: "a larger scoreboard can make a frame slower
      // when the cache is small"). It may make a frame faster, but only with
      // fewer ROP-cache misses, and by no more than they fell.
      if (path == "lock.capacity" && faster > 0.005) {
        const double misses = double(r.stats["cache"]["misses"].get<uint64_t>());
        const double base_misses = double(ref.stats["cache"]["misses"].get<uint64_t>());
        EXPECT_LE(faster, 1 - misses / base_misses) << sc.name << ": a smaller scoreboard " << 100 * faster
                                                    << " % faster, ROP-cache misses " << misses << " against "
                                                    << base_misses;
        continue;
      }
      // The second exception (issue 22, inserts cost their work): a wider
      // shader-latency spread spaces a pixel's fragments further apart, so in a
      // lock-bound frame fewer of them wait for the one before (particles, cycle
      // engine: lock waits 1,033,411 -> 861,073, the frame 0.54 % faster). Only
      // with fewer lock waits, and by under 1 %.
      if (path == "input.latency_max" && faster > 0.005) {
        EXPECT_LT(r.stats["lock"]["wait_cycles"].get<double>(), ref.stats["lock"]["wait_cycles"].get<double>())
            << sc.name;
        EXPECT_LT(faster, 0.01) << sc.name << ": " << why(r) << " against " << why(ref);
        continue;
      }
      // The third exception (issue 21, the approximate engine's in-order early
      // depth): the same ROP cache in 4 ways instead of 8 (twice the sets)
      // missed less on particles over the wall (18,074 against 18,167 misses)
      // and the approximate engine's frame came out 0.63 % faster (the cycle
      // engine's under 0.5 %): fewer ways with more sets is not always worse
      // for LRU. Only with fewer ROP-cache misses, and by under 1 %.
      if (path == "cache.ways" && faster > 0.005) {
        EXPECT_LT(r.stats["cache"]["misses"].get<double>(), ref.stats["cache"]["misses"].get<double>()) << sc.name;
        EXPECT_LT(faster, 0.01) << sc.name << ": " << why(r) << " against " << why(ref);
        continue;
      }
      // The fourth exception (the partitions' share of the DRAM; DESIGN.md,
      // "Monotonicity of the DRAM steps"): from the DRAM base the scenes'
      // two partitions are each bound by their ROP cache's miss queue (a
      // fill's latency sets their rate), they share the DRAM, and the frame
      // ends with the later one. A DRAM step changes how their requests meet
      // on the shared banks and bus, and that moves fill latency from one
      // partition to the other by more than the step itself costs. Since the
      // l2 waits for DRAM write room (CacheLevel: a miss is ready no earlier
      // than its dirty victim's acceptance) the cases on the default seed
      // are: cycle engine, dram.trrd 5 -> 6 on particles 0.84 % faster (the
      // earlier partition ending 765 cycles later, the later one 970
      // sooner); approximate engine, dram.queue_depth 64 -> 8 and
      // dram.scheduler fcfs on sweeps 0.80 % (the earlier partition 69
      // cycles later). (Before, with the l2's write-backs held outside the
      // write queue for free, dram.write_queue 64 -> 60 made the approximate
      // engine's particles 1.07 % faster, and the bound here was 1.5 %.)
      // Either engine: only when some partition ended later (the DRAM's
      // service moved between them), with the DRAM bytes within 0.5 %, the
      // partitions' mean end no more than 0.5 % sooner (the work was shared
      // out differently, not served faster), and by under 2 %. The speed-ups
      // are systematic, not one seed's noise: over input.seed 1-4, dram.trrd
      // 5 -> 6 on particles (cycle) 0.84, 1.13, 0.40 %; dram.queue_depth 8 and
      // fcfs on sweeps (approximate) 0.80, 0.73, 0.75 %; a scheduler that
      // favours neither partition's row hits (FCFS, a shorter window, later
      // activates) can finish the later one sooner, the unfairness of FR-FCFS
      // between requesters that memory-scheduling work describes. With bank
      // groups, dram.trrd_l 5 -> 7 made the cycle engine's particles 1.57 %
      // faster (1.04 and -0.15 % on seeds 2 and 3).
      if (isDramStep(path) && faster > 0.005) {
        const auto& parts = r.stats["timing"]["per_partition"];
        const auto& base_parts = ref.stats["timing"]["per_partition"];
        bool one_later = false;
        for (size_t i = 0; i < parts.size(); ++i)
          one_later |= parts[i]["end_cycle"].get<uint64_t>() > base_parts[i]["end_cycle"].get<uint64_t>();
        EXPECT_TRUE(one_later) << sc.name << ": " << path << " = " << value << " made every partition faster";
        EXPECT_LT(std::abs(double(dramBytes(r)) / double(dramBytes(ref)) - 1), 0.005) << sc.name << ": " << path << " = " << value;
        double end_sum = 0, base_end_sum = 0;
        for (size_t i = 0; i < parts.size(); ++i) {
          end_sum += parts[i]["end_cycle"].get<double>();
          base_end_sum += base_parts[i]["end_cycle"].get<double>();
        }
        EXPECT_GT(end_sum, 0.995 * base_end_sum) << sc.name << ": " << path << " = " << value
                                                 << " made the partitions' mean end " << 100 * (1 - end_sum / base_end_sum)
                                                 << " % sooner";
        EXPECT_LT(faster, 0.02) << sc.name << ": " << path << " = " << value << ": " << why(r) << " against "
                                 << why(ref);
        continue;
      }
      EXPECT_GE(cycles, base_cycles * 0.995)
          << sc.name << ": " << path << " = " << value << " made the frame " << 100.0 * (1 - cycles / base_cycles)
          << " % faster (" << cycles << " against " << base_cycles << " cycles; " << why(r) << " against "
          << why(ref) << ")";
    }
  }
  RecordProperty("largest_speedup_percent", std::to_string(100 * worst) + " (" + worst_what + ")");
  for (const auto& [path, value] : worseSteps()) {
    if (isDramStep(path)) {
      EXPECT_TRUE(dram_steps_that_moved.count(path + "=" + value))
          << path << " = " << value << " moved no scene's frame: the step does not test the DRAM controller";
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Validation, Monotonicity, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
