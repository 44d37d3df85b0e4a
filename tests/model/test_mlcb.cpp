// mlcb (Wyman 2016, multi-layer coverage blending) against hand-computed
// values, an independent screen-door oracle, and the reference's statistics.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "AlgoTestUtil.hpp"
#include "model/AlgorithmDetail.hpp"

using namespace oit;
using namespace oit::model;
using namespace oit::model::testutil;

namespace {

AlgorithmParams mlcb(unsigned k, unsigned bits, StorageFormat f = StorageFormat::Fp32, uint64_t seed = 1) {
  AlgorithmParams p = layers(k, f);
  p.bits = bits;
  p.seed = seed;
  return p;
}

// What mlcb must equal when it never merges: b-sample screen door with the
// same masks. Per sample the nearest covering fragment (equal depth: the
// later one) gives the colour, else the background; pixel = sample mean.
// Transparent fragments only (no opaque draws in the scenes that use it).
Image screenDoor(const std::vector<Fragment>& fs, uint32_t w, uint32_t h, unsigned bits, Rgb bg,
                 uint64_t seed = 1) {
  std::vector<std::vector<Fragment>> px(size_t(w) * h);
  for (const Fragment& f : fs) px[size_t(f.y) * w + f.x].push_back(f);
  Image img;
  img.width = w;
  img.height = h;
  img.pixels.assign(px.size(), bg);
  for (size_t i = 0; i < px.size(); ++i) {
    double r = 0, g = 0, b = 0;
    for (unsigned s = 0; s < bits; ++s) {
      const Fragment* best = nullptr;
      for (const Fragment& f : px[i])  // submission order: `<=` lets a later tie win
        if (f.a > 0 && (detail::mlcbCoverageMask(f, bits, seed) >> s & 1) && (!best || f.z <= best->z))
          best = &f;
      r += best ? best->r : bg.r;
      g += best ? best->g : bg.g;
      b += best ? best->b : bg.b;
    }
    img.pixels[i] = {float(r / bits), float(g / bits), float(b / bits)};
  }
  return img;
}

RenderResult renderBg(const AlgorithmParams& p, const std::vector<Fragment>& fs, uint32_t w, uint32_t h,
                      Rgb bg) {
  RenderOptions opt;
  opt.clear_colour = bg;
  return render("mlcb", p, fs, w, h, opt);
}

void expectRgbNear(Rgb got, double r, double g, double b, double tol, const std::string& what = "") {
  EXPECT_NEAR(got.r, r, tol) << what;
  EXPECT_NEAR(got.g, g, tol) << what;
  EXPECT_NEAR(got.b, b, tol) << what;
}

}  // namespace

// ---------------------------------------------------------------- layout
TEST(MlcbLayout, BytesPerPixelPerFormatAndBits) {
  // fp32: rgb + z + one mask word (b <= 32) or two (b <= 64).
  EXPECT_EQ(makeAlgorithm("mlcb", mlcb(4, 32))->bytesPerPixel(), 4u * 4 * 5);
  EXPECT_EQ(makeAlgorithm("mlcb", mlcb(4, 64))->bytesPerPixel(), 4u * 4 * 6);
  // rgba8t8z32 with b <= 8: the mask sits in the T byte, MLAB's 8-byte row.
  EXPECT_EQ(makeAlgorithm("mlcb", mlcb(4, 8, StorageFormat::Rgba8T8Z32))->bytesPerPixel(), 32u);
  EXPECT_EQ(makeAlgorithm("mlcb", mlcb(4, 9, StorageFormat::Rgba8T8Z32))->bytesPerPixel(), 48u);
  // fp16 with b <= 16: the mask sits in the spare half of word 1.
  EXPECT_EQ(makeAlgorithm("mlcb", mlcb(4, 16, StorageFormat::Fp16))->bytesPerPixel(), 48u);
  EXPECT_EQ(makeAlgorithm("mlcb", mlcb(4, 64, StorageFormat::Fp16))->bytesPerPixel(), 80u);
  auto a = makeAlgorithm("mlcb", mlcb(4, 32));
  EXPECT_EQ(a->readBytes(0, InsertOutcome::Stored), 80u);
  EXPECT_EQ(a->writeBytes(0, InsertOutcome::Merged), 80u);
  EXPECT_EQ(a->writeBytes(0, InsertOutcome::Discarded), 0u);
}

TEST(MlcbLayout, RejectsBadBitsAndLayers) {
  EXPECT_THROW(makeAlgorithm("mlcb", mlcb(4, 0)), std::invalid_argument);
  EXPECT_THROW(makeAlgorithm("mlcb", mlcb(4, 65)), std::invalid_argument);
  EXPECT_THROW(makeAlgorithm("mlcb", mlcb(0, 8)), std::invalid_argument);
  EXPECT_THROW(makeAlgorithm("mlcb", mlcb(65, 8)), std::invalid_argument);
  EXPECT_NO_THROW(makeAlgorithm("mlcb", mlcb(64, 1)));
  EXPECT_NO_THROW(makeAlgorithm("mlcb", mlcb(1, 64)));
}

// ---------------------------------------------------------------- masks
TEST(MlcbMask, PinnedBitsForSeedOne) {
  // Regression pin of the hashed positions (any change to fragmentHash or the
  // shuffle changes every image): pixel (0,0), draw 1, a = .5, b = 8.
  const uint64_t want[] = {0xd1, 0xcc, 0x74, 0x4e};
  for (uint32_t prim = 0; prim < 4; ++prim)
    EXPECT_EQ(detail::mlcbCoverageMask(frag(0, 0, 0.5f, 1, 0, 0, 0.5f, kTranspDraw, prim), 8, 1), want[prim])
        << prim;
  // a = 1 covers everything, including all 64 bits.
  EXPECT_EQ(detail::mlcbCoverageMask(frag(0, 0, 0.5f, 1, 0, 0, 1.0f), 64, 1), ~uint64_t(0));
}

TEST(MlcbMask, StochasticRoundingAndUniformPositions) {
  // a b integral: exactly a b bits. a = .3, b = 8: 2.4 -> 3 bits with
  // probability .4, else 2 (E = a b: what makes mlcb unbiased).
  const unsigned n = 20000;
  unsigned three = 0, perBit[8] = {};
  for (uint32_t prim = 0; prim < n; ++prim) {
    const Fragment half = frag(uint16_t(prim % 100), 0, 0.5f, 1, 1, 1, 0.75f, kTranspDraw, prim);
    ASSERT_EQ(std::popcount(detail::mlcbCoverageMask(half, 8, 1)), 6);
    const uint64_t m = detail::mlcbCoverageMask(frag(0, 0, 0.5f, 1, 1, 1, 0.3f, kTranspDraw, prim), 8, 1);
    const int c = std::popcount(m);
    ASSERT_TRUE(c == 2 || c == 3) << c;
    three += c == 3;
    for (unsigned s = 0; s < 8; ++s) perBit[s] += m >> s & 1;
  }
  // sigma = sqrt(.24 / n) = .0035; 5 sigma.
  EXPECT_NEAR(double(three) / n, 0.4, 0.0175);
  // Each position is set with probability a = .3 (sigma .0032).
  for (unsigned s = 0; s < 8; ++s) EXPECT_NEAR(double(perBit[s]) / n, 0.3, 0.016) << "bit " << s;
}

// ---------------------------------------------------------------- exactness
TEST(MlcbExactness, OneFragmentWithIntegralCoverageEqualsReferenceBitwise) {
  // a b integral -> coverage a exactly; dyadic inputs make eq. 15 exact in
  // double, so the fp32 result equals the A-buffer's bit for bit.
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 0.25f, 0.5f, 1.0f, 0.5f), frag(1, 0, 0.25f, 1.0f, 0.75f, 0.0f, 0.25f),
                              frag(2, 0, 0.5f, 0.5f, 0.5f, 0.5f, 1.0f), frag(3, 0, 0.3f, 0.125f, 1.0f, 0.5f, 0.75f),
                              frag(3, 0, 0.9f, 0.5f, 0.25f, 1.0f, 1.0f, kOpaqueDraw)};
  RenderOptions opt;
  opt.clear_colour = {0.25f, 0.5f, 0.75f};
  const Image ref = render("abuffer", {}, fs, 5, 1, opt).image;
  for (unsigned bits : {4u, 8u, 32u, 64u})
    for (StorageFormat f : {StorageFormat::Fp32}) {
      const Image img = render("mlcb", mlcb(1, bits, f), fs, 5, 1, opt).image;
      EXPECT_EQ(img.pixels, ref.pixels) << "b=" << bits;
    }
}

TEST(MlcbExactness, OneRandomFragmentWithinQuantisationBound) {
  // One fragment gets n in {floor(a b), ceil(a b)} bits, so |n/b - a| < 1/b
  // and |C - ref| < |c - bg| / b per channel (the exact bound).
  const auto fs = randomScene(16, 16, 1, 7);
  const Rgb bg{0.2f, 0.4f, 0.6f};
  RenderOptions opt;
  opt.clear_colour = bg;
  const Image ref = render("abuffer", {}, fs, 16, 16, opt).image;
  for (unsigned bits : {8u, 32u}) {
    const Image img = render("mlcb", mlcb(1, bits), fs, 16, 16, opt).image;
    double worst = 0;  // largest |C - ref| / (|c - bg| / b): must stay below 1
    for (const Fragment& f : fs) {
      const size_t i = size_t(f.y) * 16 + f.x;
      const double d[3] = {img.pixels[i].r - ref.pixels[i].r, img.pixels[i].g - ref.pixels[i].g,
                           img.pixels[i].b - ref.pixels[i].b};
      const double span[3] = {std::abs(f.r - bg.r), std::abs(f.g - bg.g), std::abs(f.b - bg.b)};
      for (int c = 0; c < 3; ++c) {
        EXPECT_LE(std::abs(d[c]), span[c] / bits + 1e-6) << "b=" << bits << " pixel " << i;
        if (span[c] > 0.05) worst = std::max(worst, std::abs(d[c]) / (span[c] / bits));
      }
    }
    EXPECT_GT(worst, 0.5) << "b=" << bits;  // the quantisation is real, the bound nearly tight
  }
}

TEST(MlcbExactness, EnoughLayersEqualScreenDoorOracle) {
  // k >= depth complexity: no merge, so mlcb is exactly b-sample screen door
  // with its own masks (checked against the independent oracle above).
  const auto fs = randomScene(12, 12, 6, 11);
  const Rgb bg{0.25f, 0.5f, 0.75f};
  for (unsigned bits : {8u, 32u, 64u}) {
    const Image oracle = screenDoor(fs, 12, 12, bits, bg);
    for (unsigned k : {6u, 16u})
      EXPECT_LT(maxDiff(renderBg(mlcb(k, bits), fs, 12, 12, bg).image, oracle), 1e-6) << bits << " k=" << k;
    // Too few layers merges and departs from it (the comparison can fail).
    EXPECT_GT(maxDiff(renderBg(mlcb(2, bits), fs, 12, 12, bg).image, oracle), 1e-3) << bits;
  }
}

TEST(MlcbExactness, FrontToBackOneLayerEqualsOracleBackToFrontDoesNot) {
  // Front to back, every fragment lands behind the merged layer and only
  // takes samples nobody in front covers: k = 1 is exact screen door.
  // Back to front differs from MLAB (exact there): the new front fragment
  // removes samples from a merged layer whose colour is an average, so the
  // samples it hides lose the average colour instead of their own.
  std::vector<Fragment> fs;
  for (uint32_t i = 0; i < 10; ++i) {
    const float c = 0.1f * i;
    fs.push_back(frag(0, 0, 0.05f + 0.09f * i, c, 1 - c, 0.5f, 0.2f + 0.07f * i, kTranspDraw, i));
    fs.push_back(frag(1, 0, 0.95f - 0.09f * i, 1 - c, 0.3f, c, 0.9f - 0.08f * i, kTranspDraw, 100 + i));
  }
  const Rgb bg{0.2f, 0.4f, 0.6f};
  const RenderResult r = renderBg(mlcb(1, 32), fs, 2, 1, bg);
  const Image oracle = screenDoor(fs, 2, 1, 32, bg);
  expectRgbNear(r.image.pixels[0], oracle.pixels[0].r, oracle.pixels[0].g, oracle.pixels[0].b, 1e-6,
                "front to back");
  EXPECT_GT(std::abs(r.image.pixels[1].r - oracle.pixels[1].r), 1e-3) << "back to front";
  // After the first of a pixel every fragment merges, or is hidden by the
  // accumulated coverage in front (front to back) and takes no layer.
  EXPECT_EQ(r.counts.stored, 2u);
  EXPECT_EQ(r.counts.merged + r.counts.discarded, 18u);
  EXPECT_GE(r.counts.merged, 9u);  // back to front: nothing is ever hidden
}

TEST(MlcbExactness, TwoHalfFragmentsFollowTheHypergeometricLaw) {
  // Front red and back green, a = .5, b = 8, blue background. The back
  // fragment keeps V = |m2 & ~m1| bits, V ~ Hypergeometric(8, 4, 4):
  // P(V = 0..4) = (1, 16, 36, 16, 1) / 70, E[V] = 2 -> E[C] = reference.
  // So C = (4 red + V green + (4 - V) blue) / 8 exactly, and the exact bound
  // is |C - ref| <= 2/8 |green - blue| per channel.
  const uint32_t w = 100, h = 70;
  std::vector<Fragment> fs;
  for (uint16_t y = 0; y < h; ++y)
    for (uint16_t x = 0; x < w; ++x) {
      fs.push_back(frag(x, y, 0.7f, 0, 1, 0, 0.5f, kTranspDraw, 1));  // back first: order is irrelevant
      fs.push_back(frag(x, y, 0.3f, 1, 0, 0, 0.5f, kTranspDraw, 2));
    }
  const Image img = renderBg(mlcb(4, 8), fs, w, h, {0, 0, 1}).image;
  unsigned hist[5] = {};
  double meanG = 0;
  for (const Rgb& p : img.pixels) {
    const int v = int(std::lround(p.g * 8));
    ASSERT_TRUE(v >= 0 && v <= 4) << p.g;
    ASSERT_EQ(p, (Rgb{0.5f, v / 8.0f, (4 - v) / 8.0f}));
    ++hist[v];
    meanG += p.g;
  }
  const double n = double(w) * h, want[5] = {1, 16, 36, 16, 1};
  for (int v = 0; v < 5; ++v) {
    const double pv = want[v] / 70, sigma = std::sqrt(pv * (1 - pv) / n);
    EXPECT_NEAR(hist[v] / n, pv, 5 * sigma + 1e-4) << "V=" << v;
  }
  EXPECT_NEAR(meanG / n, 0.25, 0.01);  // sigma of the mean: sqrt(4/7)/8/sqrt(7000) = .0011
}

TEST(MlcbExactness, UnbiasedWithStochasticRounding) {
  // Three fragments a = .3 (b = 8: 2.4 bits), red in front of green of blue,
  // black background. Without merges E[C] equals the reference
  // (.3, .21, .147); round(a b) = 2 bits would give (.25, .1875, .1406),
  // .05 off in red, far outside the tolerance.
  const uint32_t w = 200, h = 200;
  std::vector<Fragment> fs;
  for (uint16_t y = 0; y < h; ++y)
    for (uint16_t x = 0; x < w; ++x) {
      fs.push_back(frag(x, y, 0.5f, 0, 1, 0, 0.3f, kTranspDraw, 0));
      fs.push_back(frag(x, y, 0.2f, 1, 0, 0, 0.3f, kTranspDraw, 1));
      fs.push_back(frag(x, y, 0.8f, 0, 0, 1, 0.3f, kTranspDraw, 2));
    }
  const Image img = renderBg(mlcb(3, 8), fs, w, h, {0, 0, 0}).image;
  double m[3] = {};
  for (const Rgb& p : img.pixels) {
    m[0] += p.r;
    m[1] += p.g;
    m[2] += p.b;
  }
  const double n = double(w) * h;
  // Per-pixel channel sd < .25, sd of the mean < .0013: tolerance ~ 4 sigma.
  EXPECT_NEAR(m[0] / n, 0.3, 0.005);
  EXPECT_NEAR(m[1] / n, 0.21, 0.005);
  EXPECT_NEAR(m[2] / n, 0.147, 0.005);
}

// ---------------------------------------------------------------- merge
// Pinned masks (MlcbMask.PinnedBitsForSeedOne), pixel (0,0), b = 8:
//   prim 0: 0xd1 = 11010001, prim 1: 0xcc = 11001100, prim 2: 0x74 = 01110100.
TEST(MlcbMerge, TwoFragmentsMergeByVisibleBitCounts) {
  auto algo = makeAlgorithm("mlcb", mlcb(1, 8));
  std::vector<uint32_t> w(algo->stateWords());
  ASSERT_EQ(w.size(), 5u);  // r, g, b, z, mask
  algo->clear(w.data());
  const InsertContext ctx;
  EXPECT_EQ(algo->insert(w.data(), frag(0, 0, 0.2f, 1, 0, 0, 0.5f, kTranspDraw, 0), 0, ctx),
            InsertOutcome::Stored);
  // Green behind: m' = 0xcc & ~0xd1 = 0x0c (2 bits); merge weights 4/6, 2/6.
  EXPECT_EQ(algo->insert(w.data(), frag(0, 0, 0.8f, 0, 1, 0, 0.5f, kTranspDraw, 1), 0, ctx),
            InsertOutcome::Merged);
  EXPECT_FLOAT_EQ(detail::asFloat(w[0]), 2.0f / 3);
  EXPECT_FLOAT_EQ(detail::asFloat(w[1]), 1.0f / 3);
  EXPECT_EQ(detail::asFloat(w[2]), 0.0f);
  EXPECT_EQ(detail::asFloat(w[3]), 0.2f);  // the nearer depth
  EXPECT_EQ(w[4], 0xddu);                  // 0xd1 | 0x0c
  // Eq. 15 over blue: (6 (2/3, 1/3, 0) + 2 blue) / 8 = (.5, .25, .25), the
  // same as unmerged (and, by luck of V = E[V], the reference).
  expectRgbNear(algo->resolve(w.data(), {0, 0, 1}), 0.5, 0.25, 0.25, 1e-7);
}

TEST(MlcbMerge, ThirdFragmentBetweenMergedLayersGoesBehind) {
  // red z .2 (prim 0), green z .8 (prim 1), blue z .5 (prim 2), black bg.
  const std::vector<Fragment> fs = {frag(0, 0, 0.2f, 1, 0, 0, 0.5f, kTranspDraw, 0),
                                    frag(0, 0, 0.8f, 0, 1, 0, 0.5f, kTranspDraw, 1),
                                    frag(0, 0, 0.5f, 0, 0, 1, 0.5f, kTranspDraw, 2)};
  // k = 3, no merge: blue gets 0x74 & ~0xd1 = 0x24 (2 bits) and takes them
  // from green (0x0c & ~0x24 = 0x08, 1 bit): C = (4 red + 1 green + 2 blue) / 8,
  // here equal to the reference (red, blue, green) = (.5, .125, .25).
  const RenderResult r3 = renderBg(mlcb(3, 8), fs, 1, 1, {0, 0, 0});
  expectRgbNear(r3.image.pixels[0], 0.5, 0.125, 0.25, 1e-7, "k=3");
  EXPECT_EQ(r3.counts.stored, 3u);
  // k = 1: red+green merged at z .2 (mask 0xdd); blue lands behind it and
  // keeps 0x74 & ~0xdd = 0x20 (1 bit): C = (4 red + 2 green + 1 blue) / 8.
  const RenderResult r1 = renderBg(mlcb(1, 8), fs, 1, 1, {0, 0, 0});
  expectRgbNear(r1.image.pixels[0], 0.5, 0.25, 0.125, 1e-6, "k=1");
  EXPECT_EQ(r1.counts.merged, 2u);
  // The reference (red, blue, green): (.5, .125, .25).
  expectRgbNear(render("abuffer", {}, fs, 1, 1).image.pixels[0], 0.5, 0.125, 0.25, 1e-7, "abuffer");
}

// ---------------------------------------------------------------- ties
TEST(MlcbTieRule, LaterSubmittedIsInFront) {
  // Opaque-like (a = 1): the later one covers every sample.
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 1, 0, 0, 1.0f, kTranspDraw, 0),
                              frag(0, 0, 0.5f, 0, 0, 1, 1.0f, kTranspDraw, 1),
                              // a = .5: the later blue keeps all 4 bits, the
                              // earlier red only those blue leaves.
                              frag(1, 0, 0.5f, 1, 0, 0, 0.5f, kTranspDraw, 0),
                              frag(1, 0, 0.5f, 0, 0, 1, 0.5f, kTranspDraw, 1)};
  // Masks depend on x: pixel 1 uses its own; compute the expectation from them.
  const uint64_t mr = detail::mlcbCoverageMask(fs[2], 8, 1), mb = detail::mlcbCoverageMask(fs[3], 8, 1);
  const int red = std::popcount(mr & ~mb), blue = std::popcount(mb);
  ASSERT_EQ(blue, 4);
  for (unsigned k : {1u, 2u}) {
    const Image img = renderBg(mlcb(k, 8), fs, 2, 1, {0, 0, 0}).image;
    EXPECT_EQ(img.pixels[0], (Rgb{0, 0, 1})) << k;
    expectRgbNear(img.pixels[1], red / 8.0, 0.0, 0.5, 1e-7, "k=" + std::to_string(k));
  }
  // At (0,0) the pinned masks give red 0xd1 & ~0xcc = 0x11: (.25, 0, .5), not
  // (.5, 0, .25) as with the earlier one in front.
  fs = {frag(0, 0, 0.5f, 1, 0, 0, 0.5f, kTranspDraw, 0), frag(0, 0, 0.5f, 0, 0, 1, 0.5f, kTranspDraw, 1)};
  expectRgbNear(renderBg(mlcb(2, 8), fs, 1, 1, {0, 0, 0}).image.pixels[0], 0.25, 0.0, 0.5, 1e-7, "(0,0)");
}

// ---------------------------------------------------------------- outcomes
TEST(MlcbOutcomes, HiddenAndZeroCoverageFragmentsTakeNoLayer) {
  std::vector<Fragment> fs = {
      frag(0, 0, 0.2f, 1, 0, 0, 1.0f, kTranspDraw, 0),    // covers all 8 samples
      frag(0, 0, 0.6f, 0, 1, 0, 0.5f, kTranspDraw, 1),    // behind it: hidden -> Discarded
      frag(0, 0, 0.1f, 0, 0, 1, 1e-3f, kTranspDraw, 0),   // a b = .008 -> 0 bits here -> Discarded
      frag(1, 0, 0.6f, 0, 1, 0, 0.5f, kTranspDraw, 1),    // pixel 1: green, then
      frag(1, 0, 0.2f, 1, 0, 0, 1.0f, kTranspDraw, 2),    // a full red in front removes its layer
  };
  ASSERT_EQ(detail::mlcbCoverageMask(fs[2], 8, 1), 0u);
  const RenderResult r = renderBg(mlcb(1, 8), fs, 2, 1, {0, 0, 0});
  EXPECT_EQ(r.counts.discarded, 2u);
  EXPECT_EQ(r.counts.stored, 3u);  // the emptied green layer is dropped, no merge
  EXPECT_EQ(r.counts.merged, 0u);
  EXPECT_EQ(r.image.pixels[0], (Rgb{1, 0, 0}));
  EXPECT_EQ(r.image.pixels[1], (Rgb{1, 0, 0}));
  EXPECT_EQ(r.counts.bytes_written, 3u * 20);  // discarded inserts write nothing
}

// ---------------------------------------------------------------- formats
TEST(MlcbFormats, MaskLogicIdenticalAcrossFormatsAndPackings) {
  // Colours 0 / 1 survive every format exactly and k >= depth never merges,
  // so only the mask storage (inline spare bits or separate words) differs.
  auto fs = randomScene(10, 10, 5, 21);
  for (Fragment& f : fs) {
    f.r = std::round(f.r);
    f.g = std::round(f.g);
    f.b = std::round(f.b);
  }
  const Rgb bg{0, 1, 0};
  for (unsigned bits : {8u, 16u, 32u, 64u}) {
    const Image ref = renderBg(mlcb(5, bits), fs, 10, 10, bg).image;
    for (StorageFormat f : {StorageFormat::Rgba8T8Z32, StorageFormat::Fp16})
      EXPECT_EQ(renderBg(mlcb(5, bits, f), fs, 10, 10, bg).image.pixels, ref.pixels)
          << toString(f) << " b=" << bits;
  }
}

TEST(MlcbFormats, ColourIsQuantisedOnStore) {
  // a = .5, b = 8: C = (4 q(c) + 4 bg) / 8 with q the format's round trip.
  const std::vector<Fragment> fs = {frag(0, 0, 0.5f, 0.3f, 0.7f, 0.1f, 0.5f)};
  const Rgb bg{0.5f, 0.5f, 0.5f};
  auto q8 = [](float v) { return double(decodeUnorm8(encodeUnorm8(v))); };
  auto q16 = [](float v) { return double(decodeHalf(encodeHalf(v))); };
  Rgb got = renderBg(mlcb(2, 8, StorageFormat::Rgba8T8Z32), fs, 1, 1, bg).image.pixels[0];
  expectRgbNear(got, (q8(0.3f) + 0.5) / 2, (q8(0.7f) + 0.5) / 2, (q8(0.1f) + 0.5) / 2, 1e-7, "rgba8");
  EXPECT_NE(got.r, (0.3f + 0.5f) / 2);  // 77/255 != .3: the quantisation is visible
  got = renderBg(mlcb(2, 8, StorageFormat::Fp16), fs, 1, 1, bg).image.pixels[0];
  expectRgbNear(got, (q16(0.3f) + 0.5) / 2, (q16(0.7f) + 0.5) / 2, (q16(0.1f) + 0.5) / 2, 1e-7, "fp16");
}

// ---------------------------------------------------------------- determinism
TEST(MlcbDeterminism, SameSeedSameImageOtherSeedDiffers) {
  const auto fs = randomScene(16, 16, 10, 9, 6);
  const Image a = render("mlcb", mlcb(3, 32), fs, 16, 16).image;
  MemorySource src(header(16, 16), fs, 1u << 16);  // other batch size, reused object
  auto algo = makeAlgorithm("mlcb", mlcb(3, 32));
  EXPECT_EQ(FunctionalRenderer().render(src, *algo).image.pixels, a.pixels);
  EXPECT_EQ(FunctionalRenderer().render(src, *algo).image.pixels, a.pixels);
  EXPECT_NE(render("mlcb", mlcb(3, 32, StorageFormat::Fp32, 2), fs, 16, 16).image.pixels, a.pixels);
}
