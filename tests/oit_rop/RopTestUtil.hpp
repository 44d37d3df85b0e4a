// Helpers of the oit_rop timing tests. SystemC elaborates once per process, so
// every timing run of a test happens in a forked child (runTimingInChildren)
// that sends back the stats, counts and the image.
#pragma once

#include <gtest/gtest.h>

#include <cstring>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "model/AlgoTestUtil.hpp"
#include "model/MemorySource.hpp"
#include "oit_rop/ChildRuns.hpp"
#include "oit_rop/TimingRun.hpp"

namespace oit::rop::testutil {

struct ChildRun {
  bool ok = false;
  std::string error;
  nlohmann::json stats;
  model::Image image;
  model::RenderCounts counts;
};

inline ChildRun runInChild(const std::function<TimingResult()>& f) {
  ChildRun cr;
  try {
    std::vector<TimingResult> r = runTimingInChildren({[&](const auto&) { return f(); }}, {});
    cr.ok = true;
    cr.stats = std::move(r[0].stats);
    cr.image = std::move(r[0].image);
    cr.counts = r[0].counts;
  } catch (const std::exception& e) {
    cr.error = e.what();
  }
  return cr;
}

// A small scene: an opaque backdrop over the left 2/3 of the frame at random
// depths, transparent fragments of two draws (random depths, some behind the
// backdrop, some with a = 0), submitted interleaved.
inline std::vector<Fragment> smallScene(uint32_t w, uint32_t h, unsigned max_depth, uint32_t seed) {
  using namespace model::testutil;
  std::vector<Fragment> fs;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w * 2 / 3; ++x) {
      // One draw per declarator, in g++'s order of the arguments they were once (AlgoTestUtil.hpp).
      const float b = u(rng), g = u(rng), r = u(rng), z = 0.5f + 0.5f * u(rng);
      fs.push_back(frag(uint16_t(x), uint16_t(y), z, r, g, b, 1.0f, kOpaqueDraw));
    }
  auto tr = randomScene(w, h, max_depth, seed + 1);
  for (size_t i = 0; i < tr.size(); ++i) {
    tr[i].draw = (i % 3 == 0) ? kTranspDraw2 : kTranspDraw;
    if (i % 17 == 0) tr[i].a = 0.0f;
  }
  // Opaque first in half of the cases, interleaved otherwise: submission order
  // must not matter for the opaque pre-pass.
  std::vector<Fragment> out;
  size_t oi = 0, ti = 0;
  while (oi < fs.size() || ti < tr.size()) {
    if (oi < fs.size() && (ti >= tr.size() || rng() % 3 == 0)) out.push_back(fs[oi++]);
    else if (ti < tr.size()) out.push_back(tr[ti++]);
  }
  return out;
}

// `layers` fragments per pixel over a w x h frame, layer by layer, raster
// order within a layer, layer l nearer than the last (depth 1 - (l + 1) x
// depth_step), one primitive each: a streaming scene.
inline std::vector<Fragment> layerSweeps(uint32_t w, uint32_t h, unsigned layers, float depth_step) {
  std::vector<Fragment> fs;
  uint32_t prim = 0;
  for (unsigned l = 0; l < layers; ++l)
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x)
        fs.push_back(model::testutil::frag(uint16_t(x), uint16_t(y), 1.0f - float(l + 1) * depth_step, 0.5f, 0.25f,
                                           0.125f, 0.25f, model::testutil::kTranspDraw, prim++));
  return fs;
}

inline RopConfig smallConfig() {
  RopConfig c;
  c.stats.interval_cycles = 500;
  return c;
}

// The scene the approximate engine is measured against the cycle engine on
// (ApproximateTiming.CloseToTheCycleEngine, ApproximateLockConflicts): 192 x
// 128, depth up to 24 over an opaque backdrop (smallScene, seed 3), under
// mlab with k = 4 rows of rgba8t8z32.
struct MlabAgreementScene {
  static constexpr uint32_t W = 192, H = 128;
  std::vector<Fragment> fs = smallScene(W, H, 24, 3);
  model::AlgorithmParams p = [] {
    model::AlgorithmParams q;
    q.layers = 4;
    q.format = model::StorageFormat::Rgba8T8Z32;
    return q;
  }();
};

// Every algorithm's name, for tests instantiated over all of them (paramName names each case).
inline std::vector<std::string> allAlgorithmNames() {
  std::vector<std::string> v;
  for (const auto& a : model::algorithmNames()) v.emplace_back(a.name);
  return v;
}
inline std::string paramName(const ::testing::TestParamInfo<std::string>& info) { return info.param; }

// Both timing engines, for tests instantiated over them (engineName names each case).
inline const std::vector<SimEngine> kBothEngines = {SimEngine::CycleStepped, SimEngine::Approximate};
inline std::string engineName(const ::testing::TestParamInfo<SimEngine>& info) {
  return info.param == SimEngine::Approximate ? "Approximate" : "Cycle";
}

inline TimingResult timed(const std::string& algo, const model::AlgorithmParams& p, const std::vector<Fragment>& fs,
                          uint32_t w, uint32_t h, const RopConfig& cfg, TimingOptions opt = {}) {
  model::MemorySource src(model::testutil::header(w, h), fs, 333);
  auto a = model::makeAlgorithm(algo, p);
  return runTiming(src, *a, cfg, opt);
}

// Bit-identical images (NaN-safe, unlike ==).
inline bool sameBits(const model::Image& a, const model::Image& b) {
  return a.width == b.width && a.height == b.height &&
         std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(model::Rgb)) == 0;
}

}  // namespace oit::rop::testutil
