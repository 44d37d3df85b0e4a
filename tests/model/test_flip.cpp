// LDR-FLIP (model/Flip.hpp) against the published reference implementation's
// values for eight image pairs (tests/data/flip/README.md): the mean within
// 1e-4 and the per-pixel map within 1/255 on at least 99 % of the pixels; and
// properties derived by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "model/Flip.hpp"
#include "model/Image.hpp"

using namespace oit::model;

namespace {

const std::string kData = std::string(OITSIM_SOURCE_DIR) + "/tests/data/flip/";

struct Published {
  const char* scene;
  const char* test;
  double mean, median, q1, q3, max;
};

// tests/data/flip/README.md, as the reference implementation printed them.
const Published kPublished[] = {
    {"hair", "mlab1", 0.008898, 0.044217, 0.031478, 0.058346, 0.111348},
    {"hair", "alpha", 0.015947, 0.081185, 0.055840, 0.108932, 0.203619},
    {"hair", "wboit", 0.011731, 0.061687, 0.041808, 0.083529, 0.155966},
    {"hair", "adaptive2", 0.106857, 0.519096, 0.422584, 0.564771, 0.736648},
    {"glass", "mlab1", 0.016456, 0.137275, 0.032489, 0.231982, 0.311275},
    {"glass", "alpha", 0.068452, 0.423584, 0.378815, 0.467444, 0.687786},
    {"glass", "wboit", 0.032715, 0.201127, 0.152682, 0.246548, 0.415406},
    {"glass", "adaptive2", 0.029623, 0.311572, 0.215629, 0.356178, 0.477051},
};

class FlipPublished : public ::testing::TestWithParam<Published> {};

TEST_P(FlipPublished, MeanAndMapMatchTheReferenceImplementation) {
  const Published& p = GetParam();
  const std::string base = kData + p.scene;
  const Srgb8Image ref = readPng(base + "-reference.png");
  const Srgb8Image test = readPng(base + "-" + p.test + ".png");
  const Srgb8Image published = readPng(base + "-" + p.test + "-flip.png");  // grey: error x 255, rounded
  const FlipMap map = ldrFlip(ref, test);
  ASSERT_EQ(map.width, published.width);
  ASSERT_EQ(map.height, published.height);
  EXPECT_NEAR(map.stats.mean, p.mean, 1e-4);
  // The pooled quantiles too (measured: within 1e-5 of the published ones).
  EXPECT_NEAR(map.stats.weighted_median, p.median, 1e-4);
  EXPECT_NEAR(map.stats.weighted_q1, p.q1, 1e-4);
  EXPECT_NEAR(map.stats.weighted_q3, p.q3, 1e-4);
  EXPECT_NEAR(map.stats.max, p.max, 1e-4);
  size_t within = 0, exact = 0, worst = 0;
  for (size_t i = 0; i < map.error.size(); ++i) {
    const long ours = std::lround(double(map.error[i]) * 255.0);
    const long theirs = published.rgb[3 * i];
    const size_t d = size_t(std::labs(ours - theirs));
    within += d <= 1;
    exact += d == 0;
    worst = std::max(worst, d);
  }
  const double share = double(within) / double(map.error.size());
  EXPECT_GE(share, 0.99) << "pixels within 1/255 of the published map";
  std::printf("%s-%s: mean %.6f (published %.6f), weighted median %.6f (%.6f), q1 %.6f (%.6f), q3 %.6f (%.6f), "
              "max %.6f (%.6f); map within 1/255 on %.4f %% of pixels (equal on %.4f %%), worst %zu/255\n",
              p.scene, p.test, map.stats.mean, p.mean, map.stats.weighted_median, p.median, map.stats.weighted_q1,
              p.q1, map.stats.weighted_q3, p.q3, map.stats.max, p.max, 100.0 * share,
              100.0 * double(exact) / double(map.error.size()), worst);
}

INSTANTIATE_TEST_SUITE_P(Pairs, FlipPublished, ::testing::ValuesIn(kPublished),
                         [](const auto& pair) { return std::string(pair.param.scene) + "_" + pair.param.test; });

Srgb8Image uniform(uint32_t w, uint32_t h, uint8_t r, uint8_t g, uint8_t b) {
  Srgb8Image img;
  img.width = w;
  img.height = h;
  for (size_t i = 0; i < size_t(w) * h; ++i) img.rgb.insert(img.rgb.end(), {r, g, b});
  return img;
}

TEST(Flip, IdenticalImagesHaveNoError) {
  const Srgb8Image ref = readPng(kData + "hair-reference.png");
  const FlipMap map = ldrFlip(ref, ref);
  for (float e : map.error) ASSERT_EQ(e, 0.0f);
  EXPECT_EQ(map.stats.mean, 0.0);
  EXPECT_EQ(map.stats.weighted_median, 0.0);
  EXPECT_EQ(map.stats.max, 0.0);
}

// Black against white, both uniform: the CSF filters (each summing to 1) leave
// them as they are and the feature detectors (weights summing to 0) see
// nothing, so the error is the colour term alone, by hand:
//   Hunt-adjusted Lab: black (0, 0, 0), white (100, 0, 0): HyAB 100, ^0.7 = 25.119.
//   cmax: green Lab (87.737, -86.185, 83.181) -> Hunt (87.737, -75.617, 72.980);
//   blue (32.303, 79.197, -107.864) -> (32.303, 25.583, -34.844); HyAB = 55.434 +
//   hypot(101.200, 107.824) = 203.31; cmax = 203.31^0.7 = 41.27, pc cmax = 16.51.
//   25.119 > 16.51: 0.95 + (25.119 - 16.51) / (41.27 - 16.51) x 0.05 = 0.9674.
TEST(Flip, BlackAgainstWhiteIsTheColourTermDerivedByHand) {
  const FlipMap map = ldrFlip(uniform(40, 30, 0, 0, 0), uniform(40, 30, 255, 255, 255));
  for (float e : map.error) ASSERT_NEAR(e, 0.9674, 1e-3);
  EXPECT_NEAR(map.stats.mean, 0.9674, 1e-3);
  EXPECT_NEAR(map.stats.weighted_median, 0.9674, 1e-3);
}

// Every step compares the two images symmetrically (HyAB and |feature
// differences|), so swapping reference and test gives the same map.
TEST(Flip, SwappingReferenceAndTestGivesTheSameMap) {
  const Srgb8Image ref = readPng(kData + "glass-reference.png");
  const Srgb8Image test = readPng(kData + "glass-alpha.png");
  const FlipMap a = ldrFlip(ref, test), b = ldrFlip(test, ref);
  ASSERT_EQ(a.error.size(), b.error.size());
  for (size_t i = 0; i < a.error.size(); ++i) ASSERT_FLOAT_EQ(a.error[i], b.error[i]) << i;
}

// The weighted quantiles by hand: errors {0, 0.1, 0.2, 0.3, 0.4} sum to 1.0;
// running sums 0, 0.1, 0.3, 0.6, 1.0: the first above 0.25 is at 0.2 (q1),
// above 0.5 at 0.3 (median), above 0.75 at 0.4 (q3). Mean 0.2, max 0.4.
TEST(Flip, WeightedQuantilesWeighEachPixelByItsError) {
  const FlipStats s = flipStats({0.3f, 0.0f, 0.4f, 0.1f, 0.2f});
  EXPECT_NEAR(s.mean, 0.2, 1e-7);
  EXPECT_NEAR(s.weighted_q1, 0.2, 1e-7);
  EXPECT_NEAR(s.weighted_median, 0.3, 1e-7);
  EXPECT_NEAR(s.weighted_q3, 0.4, 1e-7);
  EXPECT_NEAR(s.max, 0.4, 1e-7);
}

TEST(Flip, BadInputIsRefusedNamingTheProblem) {
  const Srgb8Image a = uniform(8, 8, 1, 2, 3), b = uniform(8, 9, 1, 2, 3);
  EXPECT_THROW(ldrFlip(a, b), std::invalid_argument);
  EXPECT_THROW(ldrFlip(a, a, 0.0), std::invalid_argument);
  EXPECT_THROW(ldrFlip(a, a, std::nan("")), std::invalid_argument);
  EXPECT_THROW(ldrFlip(uniform(0, 0, 0, 0, 0), uniform(0, 0, 0, 0, 0)), std::invalid_argument);
}

// flip.png: the map in magma (0 -> (0, 0, 4)), then the scale: a gradient bar
// from magma(0) at the left to magma(1) = (252, 253, 191) at the right.
TEST(Flip, PngHoldsTheMapAndItsScale) {
  FlipMap map;
  map.width = 64;
  map.height = 10;
  map.error.assign(64 * 10, 0.0f);
  map.error[0] = 1.0f;
  const std::string path = std::string(::testing::TempDir()) + "flip_scale_test.png";
  writeFlipPng(map, path);
  const Srgb8Image png = readPng(path);
  std::remove(path.c_str());
  ASSERT_EQ(png.width, 64u);
  ASSERT_EQ(png.height, 10u + kFlipScaleRows);
  auto px = [&](uint32_t x, uint32_t y) {
    const uint8_t* p = &png.rgb[(size_t(y) * png.width + x) * 3];
    return std::vector<int>{p[0], p[1], p[2]};
  };
  EXPECT_EQ(px(0, 0), (std::vector<int>{252, 253, 191}));
  EXPECT_EQ(px(1, 0), (std::vector<int>{0, 0, 4}));
  EXPECT_EQ(px(5, 11), (std::vector<int>{255, 255, 255}));  // blank rows under the map
  EXPECT_EQ(px(0, 14), (std::vector<int>{0, 0, 4}));        // the bar's left end: 0
  EXPECT_EQ(px(63, 14), (std::vector<int>{252, 253, 191})); // its right end: 1
  uint8_t mid[3];
  magmaSrgb8(0.5, mid);
  // t = 0.5 is code 127.5, between the samples at 112 (red 156) and 128 (red
  // 183): 156 + 15.5 / 16 x 27 = 182.2 -> 182.
  EXPECT_EQ(mid[0], 182);
}

}  // namespace
