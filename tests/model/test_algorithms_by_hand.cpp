// Per-pixel OIT algorithms against hand-computed values, algorithm by algorithm:
// mlab, alpha, the weighted family, adaptive, slab, stochastic, hybrid.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "AlgoTestUtil.hpp"
#include "ThreeFragments.hpp"
#include "model/AlgorithmDetail.hpp"

using namespace oit;
using namespace oit::model;
using namespace oit::model::testutil;

TEST(Mlab, OneLayerExactForSortedInput) {
  // Pixel (0,0) front to back, (1,0) back to front, 10 fragments each.
  std::vector<Fragment> fs;
  for (int i = 0; i < 10; ++i) {
    const float c = 0.1f * i;
    fs.push_back(frag(0, 0, 0.05f + 0.09f * i, c, 1 - c, 0.5f, 0.2f + 0.07f * i));
    fs.push_back(frag(1, 0, 0.95f - 0.09f * i, 1 - c, 0.3f, c, 0.9f - 0.08f * i));
  }
  RenderOptions opt;
  opt.clear_colour = {0.2f, 0.4f, 0.6f};
  const Image ref = render("abuffer", {}, fs, 2, 1, opt).image;
  const RenderResult r = render("mlab", layers(1), fs, 2, 1, opt);
  EXPECT_LT(maxDiff(r.image, ref), 1e-6);
  EXPECT_EQ(r.counts.merged, 18u);  // every fragment after the first of a pixel
  EXPECT_EQ(r.counts.stored, 2u);
  // k-buffer with one layer keeps only the nearest: far from the reference.
  EXPECT_GT(maxDiff(render("kbuffer", layers(1), fs, 2, 1, opt).image, ref), 0.05);
}

TEST(Mlab, FragmentBetweenMergedRowsIsCompositedBehind) {
  // k = 1: z .5 and .9 merge into one row at z .5; then z .7 arrives and lands
  // behind the merged row (MLAB's approximation), not between.
  const float a1 = 0.5f, a2 = 0.5f, a3 = 0.5f;
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 1, 0, 0, a1), frag(0, 0, 0.9f, 0, 1, 0, a2),
                              frag(0, 0, 0.7f, 0, 0, 1, a3)};
  const Rgb got = render("mlab", layers(1), fs, 1, 1).image.pixels[0];
  EXPECT_EQ(got, (Rgb{0.5f, 0.25f, 0.125f}));  // red, then green, then blue behind
  const Rgb ref = render("abuffer", {}, fs, 1, 1).image.pixels[0];
  EXPECT_EQ(ref, (Rgb{0.5f, 0.125f, 0.25f}));  // red, blue, green
  // k = 2 has room: exact.
  EXPECT_EQ(render("mlab", layers(2), fs, 1, 1).image.pixels[0], ref);
}

TEST(Mlab, QuantisedRowsRoundToNearest) {
  // p = a c = (.125, .25, .5), T = .5 -> unorm8 codes 32, 64, 128 (round to nearest).
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 0.25f, 0.5f, 1.0f, 0.5f)};
  const Rgb got = render("mlab", layers(2, StorageFormat::Rgba8T8Z32), fs, 1, 1).image.pixels[0];
  EXPECT_EQ(got, (Rgb{32 / 255.0f, 64 / 255.0f, 128 / 255.0f}));
}

// Three fragments of mixed depth over a clear colour, hand-computed.
namespace {
const Rgb kBg{0.25f, 0.5f, 0.75f};
Rgb renderThree(std::string_view name, AlgorithmParams p = {}) {
  RenderOptions opt;
  opt.clear_colour = kBg;
  return render(name, p, threeFragments(), 1, 1, opt).image.pixels[0];
}
void expectNear(Rgb got, double r, double g, double b, double tol, const std::string& what) {
  EXPECT_NEAR(got.r, r, tol) << what;
  EXPECT_NEAR(got.g, g, tol) << what;
  EXPECT_NEAR(got.b, b, tol) << what;
}
}  // namespace

TEST(Alpha, OverBlendingInSubmissionOrder) {
  // C1 = .5 red + .5 bg; C2 = .25 green + .75 C1; C3 = .75 blue + .25 C2.
  EXPECT_EQ(renderThree("alpha"), (Rgb{0.1171875f, 0.109375f, 0.8203125f}));
  // The reference sorts by depth: red, blue, green.
  // T = .5 * .75 * .25 = .09375.
  expectNear(renderThree("abuffer"), 0.5 + 0.25 * 0.09375, 0.5 * 0.25 * 0.25 + 0.5 * 0.09375,
             0.5 * 0.75 + 0.75 * 0.09375, 1e-7, "abuffer");
}

TEST(Weighted, WeightedSumByHand) {
  // S = (.5, .25, .75), sum a = 1.5: C = bg + S - 1.5 bg.
  EXPECT_EQ(renderThree("wsum"), (Rgb{0.375f, 0.0f, 0.375f}));
  // Leaves [0,1] below: clamped.
  RenderOptions opt;
  opt.clear_colour = {1, 1, 1};
  std::vector<Fragment> fs = {frag(0, 0, 0.2f, 0, 0, 0, 0.75f), frag(0, 0, 0.3f, 0, 0, 0, 0.75f)};
  EXPECT_EQ(render("wsum", {}, fs, 1, 1, opt).image.pixels[0], (Rgb{0, 0, 0}));
}

TEST(Weighted, WeightedAverageByHand) {
  // avg = S / 1.5 = (1/3, 1/6, 1/2); T = (1 - 1.5/3)^3 = .125.
  expectNear(renderThree("wavg"), 0.875 / 3 + 0.125 * 0.25, 0.875 / 6 + 0.125 * 0.5, 0.4375 + 0.125 * 0.75,
             1e-6, "wavg");
}

TEST(Weighted, WeightedAverageEmptyAndZeroAlphaGiveBackground) {
  RenderOptions opt;
  opt.clear_colour = kBg;
  std::vector<Fragment> fs = {frag(0, 0, 0.2f, 1, 1, 1, 0.0f)};  // pixel 1 gets nothing
  const Image img = render("wavg", {}, fs, 2, 1, opt).image;
  EXPECT_EQ(img.pixels[0], kBg);
  EXPECT_EQ(img.pixels[1], kBg);
}

TEST(Weighted, WboitEq10ByHand) {
  // w = a max(.01, 3e3 (1-d)^3): .5*1536 = 768, .25*24 = 6, .75*375 = 281.25; the
  // accumulator adds w (a c, a): a w = 384, 1.5 and 210.9375 (a enters twice).
  const double A = 384 + 1.5 + 210.9375, R = 0.5 * 0.75 * 0.25;
  expectNear(renderThree("wboit"), 384 / A * (1 - R) + 0.25 * R, 1.5 / A * (1 - R) + 0.5 * R,
             210.9375 / A * (1 - R) + 0.75 * R, 1e-6, "wboit eq10");
}

TEST(Weighted, WboitViewSpaceWeightsNeedCamera) {
  AlgorithmParams p;
  p.weight = 7;
  EXPECT_THROW(renderThree("wboit", p), std::invalid_argument);
  p.camera = CameraPlanes{1.0f, 101.0f};
  // z_view = n f / (f - d (f - n)) = 101 / (101 - 100 d).
  auto zv = [](double d) { return 101.0 / (101.0 - 100.0 * d); };
  auto w7 = [](double z) {
    return std::clamp(10.0 / (1e-5 + std::pow(z / 5, 2) + std::pow(z / 200, 6)), 1e-2, 3e3);
  };
  auto w8 = [](double z) {
    return std::clamp(10.0 / (1e-5 + std::pow(z / 10, 3) + std::pow(z / 200, 6)), 1e-2, 3e3);
  };
  auto w9 = [](double z) { return std::clamp(0.03 / (1e-5 + std::pow(z / 200, 4)), 1e-2, 3e3); };
  const double R = 0.5 * 0.75 * 0.25;
  for (int eq : {7, 8, 9}) {
    p.weight = eq;
    auto w = [&](double d) { return eq == 7 ? w7(zv(d)) : eq == 8 ? w8(zv(d)) : w9(zv(d)); };
    // a w(z, a) = a^2 clamp(...): alphas .5, .25, .75.
    const double wr = 0.25 * w(0.2), wg = 0.0625 * w(0.8), wb = 0.5625 * w(0.5), A = wr + wg + wb;
    expectNear(renderThree("wboit", p), wr / A * (1 - R) + 0.25 * R, wg / A * (1 - R) + 0.5 * R,
               wb / A * (1 - R) + 0.75 * R, 1e-5, "wboit eq" + std::to_string(eq));
  }
  // Camera from the trace header works too: the same pixel as from the parameters.
  p.weight = 8;
  const auto from_params = renderThree("wboit", p);
  TraceHeader h = header(1, 1);
  h.camera = CameraPlanes{1.0f, 101.0f};
  p.camera.reset();
  RenderOptions opt;
  opt.clear_colour = kBg;
  const Rgb from_header = render("wboit", p, threeFragments(), 1, 1, opt, h).image.pixels[0];
  EXPECT_EQ(from_header.r, from_params.r);
  EXPECT_EQ(from_header.g, from_params.g);
  EXPECT_EQ(from_header.b, from_params.b);
}

// ---------------------------------------------------------------- adaptive
// Stress-suite repro: more than k fragments at one depth. Every candidate
// node has zero area there; removing node 1 each time ("first minimum wins")
// left the front node with the whole stack's vis, so the second fragment was
// shaded with vis 2^-8 (green 0.052). Now the smallest visibility step goes
// (equal alphas: the last node), so the front k - 1 fragments stay exact.
TEST(Adaptive, EqualDepthStackKeepsFrontNodesExact) {
  // 8 fragments at z .5, a .5, green first, alternating: the last (red) is in front.
  std::vector<Fragment> fs;
  for (int i = 0; i < 8; ++i) fs.push_back(frag(0, 0, 0.5f, i % 2 ? 1.0f : 0.0f, i % 2 ? 0.0f : 1.0f, 0, 0.5f));
  RenderOptions opt;
  opt.clear_colour = {0.2f, 0.4f, 0.6f};
  const double T = 1.0 / 256, bgR = 0.2f, bgG = 0.4f, bgB = 0.6f;
  // Reference: front to back red, green, ... with vis 2^-i: red .5 + .125 +
  // 2^-5 + 2^-7, green .25 + 2^-4 + 2^-6 + 2^-8, plus T bg.
  const Rgb ref = render("abuffer", {}, fs, 1, 1, opt).image.pixels[0];
  expectNear(ref, 0.6640625 + T * bgR, 0.33203125 + T * bgG, T * bgB, 1e-7, "reference");
  // k = 4 keeps nodes (seq 7, 6, 5) exact: vis 1, .5, .25, then node seq 4
  // holds vis .125 for seq 4 and the total 2^-8 for everything behind it:
  // red .5 + .25 .5 + 2 (2^-8 .5), green .5 .5 + .125 .5 + 2 (2^-8 .5).
  const Rgb got = render("adaptive", layers(4), fs, 1, 1, opt).image.pixels[0];
  expectNear(got, 0.62890625 + T * bgR, 0.31640625 + T * bgG, T * bgB, 1e-7, "adaptive k 4");
  // Underestimate property: never more visibility than the reference, and
  // the total transmittance (blue = T bg) is exact.
  EXPECT_LE(got.r, ref.r);
  EXPECT_LE(got.g, ref.g);
  EXPECT_EQ(got.b, ref.b);
  // With k >= 8 nothing is removed: the reference.
  expectNear(render("adaptive", layers(8), fs, 1, 1, opt).image.pixels[0], ref.r, ref.g, ref.b, 1e-7, "k 8");
}

// ---------------------------------------------------------------- slab
TEST(Slab, BackToFrontWithEnoughLayersIsExact) {
  // Every new fragment is in front of all layers: nothing occludes it, P = 1
  // (a b >= 1), so all are kept and the colour pass is exact.
  std::vector<Fragment> fs;
  for (uint16_t x = 0; x < 8; ++x)
    for (int i = 0; i < 6; ++i)
      fs.push_back(frag(x, 0, 0.9f - 0.1f * i, 0.1f * i, 0.5f, 1.0f - 0.1f * x, 0.2f + 0.1f * i));
  const Image ref = render("abuffer", {}, fs, 8, 1).image;
  AlgorithmParams p = layers(6);
  const RenderResult r = render("slab", p, fs, 8, 1);
  EXPECT_LT(maxDiff(r.image, ref), 1e-6);
  EXPECT_EQ(r.counts.stored, fs.size());
  // Three layers: the furthest are evicted and the result is biased.
  p.layers = 3;
  EXPECT_GT(maxDiff(render("slab", p, fs, 8, 1).image, ref), 1e-3);
}

TEST(Slab, InsertionProbabilityFollowsTheStratifiedTable) {
  // Per pixel: F1 (front, a .5) then F2 (behind, a .5). With b = 8: s = 4
  // occluded bits, t = 4 -> P_8(4, 4) = 1 - (4)_4 / (8)_4 = 1 - 24/1680.
  const uint32_t w = 100, h = 100;
  std::vector<Fragment> fs;
  for (uint16_t y = 0; y < h; ++y)
    for (uint16_t x = 0; x < w; ++x) {
      fs.push_back(frag(x, y, 0.2f, 1, 0, 0, 0.5f, kTranspDraw, 2 * (y * w + x)));
      fs.push_back(frag(x, y, 0.8f, 0, 1, 0, 0.5f, kTranspDraw, 2 * (y * w + x) + 1));
    }
  const double pDiscard = 24.0 / 1680.0;  // 0.0143
  for (bool mask : {false, true}) {
    AlgorithmParams p = layers(4);
    p.bits = 8;
    p.coverage_mask = mask;
    const RenderResult r = render("slab", p, fs, w, h);
    const double frac = double(r.counts.discarded) / (w * h);
    EXPECT_NEAR(frac, pDiscard, 0.006) << "mask " << mask;  // ~5 sigma
    EXPECT_GT(r.counts.discarded, 0u);
    EXPECT_TRUE(allFinite(r.image));
  }
}

TEST(Slab, ManyBitsTieRuleLaterInFront) {
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 1, 0, 0, 0.5f), frag(0, 0, 0.5f, 0, 0, 1, 0.5f),
                              frag(1, 0, 0.5f, 1, 0, 0, 0.5f), frag(1, 0, 0.25f, 0, 1, 0, 0.5f),
                              frag(1, 0, 0.5f, 0, 0, 1, 0.5f)};
  AlgorithmParams p = layers(3);
  p.bits = 1024;  // P_b -> 1: a k-buffer with Enderton's normalisation
  const Image img = render("slab", p, fs, 2, 1).image;
  expectNear(img.pixels[0], 0.25, 0.0, 0.5, 1e-6, "pixel 0");
  expectNear(img.pixels[1], 0.125, 0.5, 0.25, 1e-6, "pixel 1");
}

TEST(Slab, RejectsBadBits) {
  AlgorithmParams p;
  p.bits = 0;
  EXPECT_THROW(makeAlgorithm("slab", p), std::invalid_argument);
  p.bits = 33;
  p.coverage_mask = true;
  EXPECT_THROW(makeAlgorithm("slab", p), std::invalid_argument);
  p.samples = 65;
  EXPECT_THROW(makeAlgorithm("stochastic", p), std::invalid_argument);
}

// ---------------------------------------------------------------- stochastic
TEST(Stochastic, TwoLayersAreExactWithStratifiedCoverage) {
  // With exactly round(a S) = 4 of 8 samples per fragment, the back fragment
  // of two always sees exactly half the samples: vis = .5 in either order.
  std::vector<Fragment> fs;
  for (uint16_t x = 0; x < 64; ++x) {
    const bool frontFirst = x % 2;
    Fragment f1 = frag(x, 0, 0.3f, 1, 0.5f, 0, 0.5f, kTranspDraw, 2 * x);
    Fragment f2 = frag(x, 0, 0.6f, 0, 0.25f, 1, 0.5f, kTranspDraw, 2 * x + 1);
    if (frontFirst) {
      fs.push_back(f1);
      fs.push_back(f2);
    } else {
      fs.push_back(f2);
      fs.push_back(f1);
    }
  }
  const Image ref = render("abuffer", {}, fs, 64, 1).image;
  AlgorithmParams p;
  p.samples = 8;
  EXPECT_LT(maxDiff(render("stochastic", p, fs, 64, 1).image, ref), 1e-6);
}

TEST(Stochastic, SeedChangesNoiseNotDeterminism) {
  const auto fs = randomScene(16, 16, 10, 9, 6);
  AlgorithmParams a;
  a.samples = 8;
  AlgorithmParams b = a;
  b.seed = 2;
  for (const std::string name : {"stochastic", "slab"}) {
    const Image i1 = render(name, a, fs, 16, 16).image;
    EXPECT_EQ(i1.pixels, render(name, a, fs, 16, 16).image.pixels) << name;
    EXPECT_NE(i1.pixels, render(name, b, fs, 16, 16).image.pixels) << name;
  }
}

// hybrid fp16: 1000 fragments of a = 2e-4, sent back to front, so each older
// core row falls into the tail. fp16 rounds T = 1 - 2e-4 to 1 (the spacing
// below 1 is 2^-11) but keeps the premultiplied colour 2e-4; the tail used to
// drop such rows and the pixel came out (0.0002, ...), 900x too dark. Exact:
// 1 - 0.9998^1000 = 0.18129 times the colour (1, .5, .25).
TEST(Hybrid, Fp16TailKeepsRowsWhoseTRoundedToOne) {
  std::vector<Fragment> fs;
  for (int i = 0; i < 1000; ++i) fs.push_back(frag(0, 0, 1.0f - float(i) / 1000.0f, 1, 0.5f, 0.25f, 0.0002f, 1, uint32_t(i)));
  const float exact = 1.0f - float(std::pow(0.9998, 1000.0));
  for (StorageFormat f : {StorageFormat::Fp32, StorageFormat::Fp16}) {
    const Rgb got = render("hybrid", layers(2, f), fs, 1, 1).image.pixels[0];
    // fp16's packed tail (10-bit colour ratio, fp16 alpha_sum) costs ~1 %.
    const float tol = f == StorageFormat::Fp32 ? 1e-4f : 0.01f;
    EXPECT_NEAR(got.r, exact, tol) << int(f);
    EXPECT_NEAR(got.g, exact * 0.5f, tol) << int(f);
    EXPECT_NEAR(got.b, exact * 0.25f, tol) << int(f);
  }
}
