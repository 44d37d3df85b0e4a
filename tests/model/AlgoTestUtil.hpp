// Shared helpers of test_algorithms*.cpp and test_renderer*.cpp.
#pragma once

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "model/FunctionalRenderer.hpp"
#include "model/MemorySource.hpp"
#include "model/OitAlgorithm.hpp"

namespace oit::model::testutil {

inline constexpr uint32_t kOpaqueDraw = 0;
inline constexpr uint32_t kTranspDraw = 1;
inline constexpr uint32_t kTranspDraw2 = 2;

inline TraceHeader header(uint32_t w, uint32_t h) {
  TraceHeader t;
  t.width = w;
  t.height = h;
  t.draws = {{kOpaqueDraw, DrawClass::Opaque, "opaque"},
             {kTranspDraw, DrawClass::Transparent, "glass"},
             {kTranspDraw2, DrawClass::Transparent, "smoke"}};
  return t;
}

inline Fragment frag(uint16_t x, uint16_t y, float z, float r, float g, float b, float a,
                     uint32_t draw = kTranspDraw, uint32_t prim = 0) {
  return Fragment{x, y, z, r, g, b, a, prim, draw};
}

inline RenderResult render(std::string_view algo, const AlgorithmParams& p, const std::vector<Fragment>& fs,
                           uint32_t w, uint32_t h, RenderOptions opt = {}, TraceHeader hdr = {}) {
  if (hdr.width == 0) hdr = header(w, h);
  MemorySource src(hdr, fs, 7);  // odd batch size: batches straddle pixels
  auto a = makeAlgorithm(algo, p);
  return FunctionalRenderer(opt).render(src, *a);
}

inline AlgorithmParams layers(unsigned k, StorageFormat f = StorageFormat::Fp32) {
  AlgorithmParams p;
  p.layers = k;
  p.format = f;
  return p;
}

// Random transparent scene: every pixel gets 1..maxDepth fragments with
// distinct random depths (no ties), random colours and alphas in (0,1],
// submitted in random order interleaved across pixels.
inline std::vector<Fragment> randomScene(uint32_t w, uint32_t h, unsigned maxDepth, uint32_t seed,
                                         unsigned minDepth = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<Fragment> fs;
  uint32_t prim = 0;
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x) {
      const unsigned n = minDepth + rng() % (maxDepth - minDepth + 1);
      for (unsigned i = 0; i < n; ++i) {
        // One draw per declarator: a call's arguments are evaluated in an
        // order the compiler picks, so draws inside frag(...) gave other
        // scenes under clang than under g++. Kept in g++'s order (last first).
        const float a = 0.05f + 0.95f * u(rng), b = u(rng), g = u(rng), r = u(rng), z = 0.05f + 0.9f * u(rng);
        fs.push_back(frag(uint16_t(x), uint16_t(y), z, r, g, b, a, kTranspDraw, prim++));
      }
    }
  std::shuffle(fs.begin(), fs.end(), rng);
  return fs;
}

inline double maxDiff(const Image& a, const Image& b) {
  double m = 0;
  for (size_t i = 0; i < a.pixels.size(); ++i) {
    m = std::max({m, std::abs(double(a.pixels[i].r) - b.pixels[i].r),
                  std::abs(double(a.pixels[i].g) - b.pixels[i].g),
                  std::abs(double(a.pixels[i].b) - b.pixels[i].b)});
  }
  return m;
}

inline bool allFinite(const Image& img) {
  for (const Rgb& p : img.pixels)
    if (!std::isfinite(p.r) || !std::isfinite(p.g) || !std::isfinite(p.b)) return false;
  return true;
}

}  // namespace oit::model::testutil
