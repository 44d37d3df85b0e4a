// The stress suite's cases (model/StressSuite.hpp): each a small frame of
// extreme inputs (denormals, alphas at and next to 0 and 1, deep stacks, equal
// depths, long merge chains), built deterministically from its seed.
#include "model/StressSuite.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <utility>

namespace oit::model::stress {

namespace {

constexpr float kDenormMin = std::numeric_limits<float>::denorm_min();
constexpr float kFltMin = std::numeric_limits<float>::min();
// The six alphas of the issue. 1 - 1e-7 is the float nearest to it (1 - 2^-23).
const std::array<float, 6> kAlphaSet{0.0f, 1e-7f, 1.0f / 255.0f, 0.5f, 1.0f - 1e-7f, 1.0f};

// Every case: a 2x2 frame with one opaque and one transparent draw and the
// camera planes; pixel (1,0) never receives a fragment, so every run also
// checks that an empty pixel resolves to the clear colour without 0/0.
class Builder {
 public:
  Builder(std::string name, std::string what, Rgb clear = {0.2f, 0.4f, 0.6f}) {
    c_.name = std::move(name);
    c_.what = std::move(what);
    c_.clear = clear;
    c_.header.width = 2;
    c_.header.height = 2;
    c_.header.camera = CameraPlanes{kNear, kFar};
    c_.header.draws = {{kOpaqueDraw, DrawClass::Opaque, "wall"}, {kGlassDraw, DrawClass::Transparent, "glass"}};
  }
  // Each fragment gets its own primitive id, so the random hashes of slab /
  // stochastic differ per fragment.
  void glass(uint16_t x, uint16_t y, float z, Rgb c, float a) {
    c_.fragments.push_back(Fragment{x, y, z, c.r, c.g, c.b, a, prim_++, kGlassDraw});
  }
  void opaque(uint16_t x, uint16_t y, float z, Rgb c) {
    c_.fragments.push_back(Fragment{x, y, z, c.r, c.g, c.b, 1.0f, prim_++, kOpaqueDraw});
  }
  void shuffle(SplitMix64& rng) {
    auto& f = c_.fragments;
    for (size_t i = f.size(); i > 1; --i) std::swap(f[i - 1], f[rng.below(uint32_t(i))]);
  }
  StressCase take() { return std::move(c_); }

 private:
  StressCase c_;
  uint32_t prim_ = 0;
};

// A braced list draws left to right; a call's arguments are evaluated in an
// order each compiler picks (g++ right to left, clang left to right), so a
// call never takes two draws: the later arguments' draws are made first, into
// named values, in g++'s order, which the committed stress table was made with.
Rgb randomColour(SplitMix64& rng) { return {rng.open01(), rng.open01(), rng.open01()}; }

// n fragments at pixel (x, y), random depth in (0,1), alpha from `alpha`.
template <class AlphaFn, class ColourFn>
void randomFragments(Builder& b, SplitMix64& rng, uint16_t x, uint16_t y, unsigned n, AlphaFn alpha, ColourFn colour) {
  for (unsigned i = 0; i < n; ++i) {
    const float z = rng.open01();
    const Rgb c = colour();
    b.glass(x, y, z, c, alpha());
  }
}

// Depth 4096 on pixel (0,0) and 16 on (1,1), random depths, shuffled.
template <class AlphaFn>
StressCase depthCase(const char* name, const char* what, uint64_t seed, AlphaFn alpha, Rgb clear = {0.2f, 0.4f, 0.6f}) {
  Builder b(name, what, clear);
  SplitMix64 rng(seed);
  auto colour = [&] { return randomColour(rng); };
  randomFragments(b, rng, 0, 0, 4096, [&] { return alpha(rng); }, colour);
  randomFragments(b, rng, 1, 1, 16, [&] { return alpha(rng); }, colour);
  b.shuffle(rng);
  return b.take();
}

// Constant-colour stacks: the reference is c + (bg - c) T exactly, which the
// tests use for closed-form checks.
StressCase constantColourCase(const char* name, const char* what, float a, Rgb c, Rgb bg, uint64_t seed) {
  Builder b(name, what, bg);
  SplitMix64 rng(seed);
  for (unsigned i = 0; i < 4096; ++i) b.glass(0, 0, rng.open01(), c, a);
  for (unsigned i = 0; i < 16; ++i) {
    const Rgb random = randomColour(rng);
    b.glass(1, 1, rng.open01(), random, a);
  }
  b.shuffle(rng);
  return b.take();
}

StressCase mergeChain(const char* name, const char* what, unsigned n, float a, uint64_t seed) {
  // (0,0) front to back (every insert past k merges the two furthest rows),
  // (1,1) back to front (every insert lands in front, the back rows merge).
  // Both orders are exact for MLAB at any k in exact arithmetic, so the
  // error is the storage format's alone.
  Builder b(name, what);
  SplitMix64 rng(seed);
  for (unsigned i = 0; i < n; ++i) b.glass(0, 0, float(i + 1) / float(n + 1), randomColour(rng), a);
  for (unsigned i = 0; i < n; ++i) b.glass(1, 1, float(n - i) / float(n + 1), randomColour(rng), a);
  return b.take();
}

struct CaseDef {
  const char* name;
  StressCase (*make)();
};

const std::vector<CaseDef>& caseDefs() {
  static const std::vector<CaseDef> defs = {
      {"depth4096_alpha0.5_random",
       [] {
         return depthCase("depth4096_alpha0.5_random", "4096 fragments on one pixel, alpha 0.5, random depths and order",
                          11, [](SplitMix64&) { return 0.5f; });
       }},
      {"depth4096_alpha_uniform",
       [] {
         return depthCase("depth4096_alpha_uniform", "4096 fragments on one pixel, alpha uniform in (0,1)", 12,
                          [](SplitMix64& r) { return r.open01(); });
       }},
      {"depth4096_alpha_mixed",
       [] {
         return depthCase("depth4096_alpha_mixed",
                          "4096 fragments, alpha drawn from {0, 1e-7, 1/255, 0.5, 1-1e-7, 1}", 13,
                          [](SplitMix64& r) { return kAlphaSet[r.below(6)]; });
       }},
      {"alpha_0_x4096",
       [] {
         return depthCase("alpha_0_x4096", "4096 fragments of alpha 0: the image must be the background", 14,
                          [](SplitMix64&) { return 0.0f; }, {0.25f, 0.5f, 0.75f});
       }},
      {"alpha_1e-7_x4096",
       [] {
         return constantColourCase("alpha_1e-7_x4096", "4096 fragments of alpha 1e-7, one colour: T = (1-1e-7)^4096",
                                   1e-7f, {0.9f, 0.6f, 0.1f}, {0.1f, 0.4f, 0.9f}, 15);
       }},
      {"alpha_1div255_x4096",
       [] {
         return constantColourCase("alpha_1div255_x4096",
                                   "4096 fragments of alpha 1/255 (one unorm8 step), one colour: T = (254/255)^4096",
                                   1.0f / 255.0f, {0.9f, 0.6f, 0.1f}, {0.1f, 0.4f, 0.9f}, 16);
       }},
      {"alpha_1-1e-7_x4096",
       [] {
         return depthCase("alpha_1-1e-7_x4096", "4096 fragments of alpha 1-1e-7: transmittance underflows", 17,
                          [](SplitMix64&) { return 1.0f - 1e-7f; });
       }},
      {"alpha_1_x4096",
       [] {
         return depthCase("alpha_1_x4096", "4096 fragments of alpha 1: the image is the nearest fragment's colour",
                          18, [](SplitMix64&) { return 1.0f; });
       }},
      {"alpha_1_then_more",
       [] {
         // (0,0): the alpha-1 front fragment is submitted first, (1,1): last.
         // 4095 random fragments behind it (z > 0.3) either way.
         Builder b("alpha_1_then_more",
                   "alpha-1 front fragment (z 0.25) submitted first (0,0) / last (1,1), 4095 behind it");
         SplitMix64 rng(19);
         const Rgb front{0.8f, 0.3f, 0.1f};
         b.glass(0, 0, 0.25f, front, 1.0f);
         for (unsigned i = 0; i < 4095; ++i) {
           const float a = rng.open01();
           const Rgb c = randomColour(rng);
           b.glass(0, 0, 0.3f + 0.65f * rng.open01(), c, a);
         }
         for (unsigned i = 0; i < 4095; ++i) {
           const float a = rng.open01();
           const Rgb c = randomColour(rng);
           b.glass(1, 1, 0.3f + 0.65f * rng.open01(), c, a);
         }
         b.glass(1, 1, 0.25f, front, 1.0f);
         return b.take();
       }},
      {"equal_depths_512",
       [] {
         // Tie rule: a later-submitted fragment is in front (painter's order).
         Builder b("equal_depths_512", "512 fragments at one depth (0,0); 3 at one depth (1,1); 64 on two depths (0,1)");
         SplitMix64 rng(20);
         for (unsigned i = 0; i < 512; ++i) {
           const float a = rng.open01();
           b.glass(0, 0, 0.5f, randomColour(rng), a);
         }
         b.glass(1, 1, 0.5f, {1, 0, 0}, 0.5f);
         b.glass(1, 1, 0.5f, {0, 1, 0}, 0.5f);
         b.glass(1, 1, 0.5f, {0, 0, 1}, 0.5f);
         for (unsigned i = 0; i < 64; ++i) {
           const float a = rng.open01();
           b.glass(0, 1, (i % 2) ? 0.25f : 0.75f, randomColour(rng), a);
         }
         return b.take();
       }},
      {"depth_0_1_denormal",
       [] {
         // Depth 0, -0 (ties with 0), denormals, FLT_MIN, 1 - 2^-24 and 1
         // (no opaque fragment, so z = 1 is not culled).
         Builder b("depth_0_1_denormal",
                   "depths 0, -0, denormals, FLT_MIN, 0.5, 1-2^-24, 1: 9 fragments scrambled (0,0), 1024 (1,1)");
         const std::array<float, 9> depths{0.0f, -0.0f, kDenormMin, 2 * kDenormMin,
                                           std::nextafter(kFltMin, 0.0f), kFltMin, 0.5f,
                                           std::nextafter(1.0f, 0.0f), 1.0f};
         const std::array<unsigned, 9> order{6, 2, 8, 0, 5, 3, 1, 7, 4};
         SplitMix64 rng(21);
         for (unsigned i : order) b.glass(0, 0, depths[i], randomColour(rng), 0.5f);
         for (unsigned i = 0; i < 1024; ++i) {
           const float a = rng.open01();
           const Rgb c = randomColour(rng);
           b.glass(1, 1, depths[rng.below(9)], c, a);
         }
         return b.take();
       }},
      {"merge_chain_8bit_1024",
       [] {
         return mergeChain("merge_chain_8bit_1024",
                           "1024 fragments of alpha 0.02, sorted front to back (0,0) / back to front (1,1)", 1024, 0.02f,
                           22);
       }},
      {"merge_chain_fp16_4096",
       [] {
         return mergeChain("merge_chain_fp16_4096",
                           "4096 fragments of alpha 1e-3, sorted front to back (0,0) / back to front (1,1)", 4096, 1e-3f,
                           23);
       }},
      {"wboit_weight_max",
       [] {
         // z = 0 gives the 3e3 weight cap of every wboit equation. (0,0): 64
         // alpha-1 fragments of one colour (sum w a = 192000 > 5e4 clamp and
         // > fp16 65504); (1,1): 16 of them (48000, below both); (0,1): 64 of
         // alpha 0.5 and random colours (96000).
         Builder b("wboit_weight_max", "depth 0 (weight cap 3e3): 64 / 16 alpha-1 and 64 alpha-0.5 fragments",
                   {0.0f, 0.0f, 0.0f});
         SplitMix64 rng(24);
         const Rgb c{1.0f, 0.5f, 0.25f};
         for (unsigned i = 0; i < 64; ++i) b.glass(0, 0, 0.0f, c, 1.0f);
         for (unsigned i = 0; i < 16; ++i) b.glass(1, 1, 0.0f, c, 1.0f);
         for (unsigned i = 0; i < 64; ++i) b.glass(0, 1, 0.0f, randomColour(rng), 0.5f);
         return b.take();
       }},
      {"wboit_weight_min",
       [] {
         // z = 1 gives the smallest weights (eq. 10: 1e-2 a); with alpha 1e-7
         // the sum of w a (~4e-6) sits under the 1e-4 denominator clamp and
         // below fp16's smallest subnormal.
         Builder b("wboit_weight_min", "depth 1 (weight floor): 4096 alpha-1e-7 (0,0), 4096 alpha-1/255 (1,1)");
         SplitMix64 rng(25);
         for (unsigned i = 0; i < 4096; ++i) b.glass(0, 0, 1.0f, randomColour(rng), 1e-7f);
         for (unsigned i = 0; i < 4096; ++i) b.glass(1, 1, 1.0f, randomColour(rng), 1.0f / 255.0f);
         return b.take();
       }},
      {"opaque_in_front",
       [] {
         // (0,0): opaque at 0.3 submitted mid-stream, 2048 transparent around
         // it plus 8 exactly at 0.3 (culled: at the opaque depth). (1,1):
         // opaque at depth 0 submitted last culls all 256 transparent. (0,1):
         // two opaque at equal depth (the first wins), 64 transparent.
         Builder b("opaque_in_front", "opaque surfaces at 0.3 / 0 / equal depths with transparent fragments around them");
         SplitMix64 rng(26);
         for (unsigned i = 0; i < 2048; ++i) {
           if (i == 1000) b.opaque(0, 0, 0.3f, {0.1f, 0.7f, 0.2f});
           if (i % 256 == 0) {
             const float a = rng.open01();
             b.glass(0, 0, 0.3f, randomColour(rng), a);
           }
           {
             const float a = rng.open01();
             const Rgb c = randomColour(rng);
             b.glass(0, 0, rng.open01(), c, a);
           }
         }
         for (unsigned i = 0; i < 256; ++i) {
           const float a = rng.open01();
           const Rgb c = randomColour(rng);
           b.glass(1, 1, rng.open01(), c, a);
         }
         b.opaque(1, 1, 0.0f, {0.9f, 0.8f, 0.7f});
         b.opaque(0, 1, 0.6f, {0.5f, 0.5f, 0.0f});
         for (unsigned i = 0; i < 64; ++i) {
           const float a = rng.open01();
           const Rgb c = randomColour(rng);
           b.glass(0, 1, rng.open01(), c, a);
         }
         b.opaque(0, 1, 0.6f, {0.0f, 0.5f, 0.5f});
         return b.take();
       }},
      {"tail_count_70000",
       [] {
         // 70000 > 65535: the packed hybrid tail's 16-bit count saturates and
         // its fp16 alpha sum stops growing; wavg's count grows past 2^16.
         Builder b("tail_count_70000", "70000 fragments of alpha in (0,0.01) on one pixel: 16-bit counters saturate");
         SplitMix64 rng(27);
         for (unsigned i = 0; i < 70000; ++i) {
           const float a = 0.01f * rng.open01();
           const Rgb c = randomColour(rng);
           b.glass(0, 0, rng.open01(), c, a);
         }
         return b.take();
       }},
      {"white_on_white",
       [] {
         // (0,0): colour 1 over a white background, exact answer 1; (1,1):
         // colour 0 over it, exact answer T. Rounding must not leave [0,1].
         Builder b("white_on_white", "colour 1 over background 1 (exact 1), colour 0 (1,1), alphas from the issue's set",
                   {1.0f, 1.0f, 1.0f});
         SplitMix64 rng(28);
         for (unsigned i = 0; i < 1024; ++i) {
           const float a = kAlphaSet[rng.below(6)];
           b.glass(0, 0, rng.open01(), {1, 1, 1}, a);
         }
         for (unsigned i = 0; i < 1024; ++i) {
           const float a = kAlphaSet[rng.below(6)];
           b.glass(1, 1, rng.open01(), {0, 0, 0}, a);
         }
         return b.take();
       }},
      {"alpha_denormal_x4096",
       [] {
         return depthCase("alpha_denormal_x4096", "4096 fragments of denormal / FLT_MIN alpha (a > 0 yet a c underflows)",
                          29, [](SplitMix64& r) {
                            const std::array<float, 3> a{kDenormMin, kFltMin / 2, kFltMin};
                            return a[r.below(3)];
                          });
       }},
  };
  return defs;
}

}  // namespace

const std::vector<std::string>& caseNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const CaseDef& d : caseDefs()) v.emplace_back(d.name);
    return v;
  }();
  return names;
}

StressCase makeCase(std::string_view name) {
  for (const CaseDef& d : caseDefs())
    if (name == d.name) return d.make();
  std::string valid;
  for (const CaseDef& d : caseDefs()) valid += (valid.empty() ? "" : ", ") + std::string(d.name);
  throw std::invalid_argument("unknown stress case '" + std::string(name) + "' (valid: " + valid + ")");
}

}  // namespace oit::model::stress
