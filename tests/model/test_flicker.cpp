// Flicker across runs (model/Flicker.hpp): per-pixel standard deviation of the
// sRGB8 codes, differing pixels, errors against the reference; values by hand.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "model/Flicker.hpp"

using namespace oit::model;

namespace {

// A 2x2 image whose pixels have the sRGB8 codes `codes` (grey).
Image grey(std::vector<uint8_t> codes) {
  Image img(2, 2);
  for (size_t i = 0; i < 4; ++i) {
    const float v = srgb8ToLinear(codes[i]);
    img.pixels[i] = {v, v, v};
  }
  return img;
}

TEST(Flicker, Srgb8ToLinearRoundTripsEveryCode) {
  for (unsigned c = 0; c < 256; ++c) EXPECT_EQ(toSrgb8(srgb8ToLinear(uint8_t(c))), c);
}

// Two images differing in one of four pixels by codes 100 and 110: that pixel's
// population standard deviation is 5 levels; mean over the pixels 5 / 4.
TEST(Flicker, StandardDeviationInSrgb8Levels) {
  const std::vector<Image> imgs{grey({10, 20, 100, 255}), grey({10, 20, 110, 255})};
  const FlickerMetrics m = measureFlicker(imgs, imgs[0]);
  EXPECT_EQ(m.images, 2u);
  EXPECT_DOUBLE_EQ(m.max_std, 5.0);
  EXPECT_DOUBLE_EQ(m.mean_std, 1.25);
  EXPECT_EQ(m.differing_pixels, 1u);
  EXPECT_DOUBLE_EQ(m.differing_fraction, 0.25);
  ASSERT_EQ(m.errors.size(), 2u);
  EXPECT_EQ(m.errors[0].rmse, 0.0);
  EXPECT_GT(m.errors[1].rmse, 0.0);
  EXPECT_DOUBLE_EQ(m.rmse_worst, m.errors[1].rmse);
  EXPECT_DOUBLE_EQ(m.rmse_mean, m.errors[1].rmse / 2);
}

// Three images, codes 0, 0, 3 in one channel only: variance (0 + 0 + 9) / 3 -
// 1 = 2, std sqrt(2); the largest channel counts (the others do not move).
TEST(Flicker, LargestChannelOfThreeImages) {
  std::vector<Image> imgs(3, Image(1, 1));
  for (int i = 0; i < 3; ++i) imgs[size_t(i)].pixels[0] = {srgb8ToLinear(i == 2 ? 3 : 0), 0.5f, 0.25f};
  const FlickerMetrics m = measureFlicker(imgs, imgs[0]);
  EXPECT_DOUBLE_EQ(m.max_std, std::sqrt(2.0));
  EXPECT_EQ(m.differing_pixels, 1u);
}

TEST(Flicker, IdenticalImagesDoNotFlicker) {
  const std::vector<Image> imgs(5, grey({1, 2, 3, 4}));
  const FlickerMetrics m = measureFlicker(imgs, grey({1, 2, 3, 5}));
  EXPECT_EQ(m.max_std, 0.0);
  EXPECT_EQ(m.mean_std, 0.0);
  EXPECT_EQ(m.differing_pixels, 0u);
  EXPECT_DOUBLE_EQ(m.rmse_mean, m.rmse_worst);
  EXPECT_GT(m.rmse_worst, 0.0);
}

// flicker.png: code = min(255, round(scale x std)); the same figures on one
// thread or several.
TEST(Flicker, ImageScalesTheStandardDeviation) {
  const std::vector<Image> imgs{grey({10, 0, 100, 0}), grey({10, 255, 110, 0})};
  const FlickerMetrics m = measureFlicker(imgs, imgs[0], 8.0, 1);
  const Image& f = m.image;
  ASSERT_EQ(f.width, 2u);
  EXPECT_EQ(toSrgb8(f.pixels[0].r), 0u);
  EXPECT_EQ(toSrgb8(f.pixels[1].g), 255u);  // std 127.5 x 8 clamps
  EXPECT_EQ(toSrgb8(f.pixels[2].b), 40u);   // std 5 x 8
  EXPECT_EQ(toSrgb8(f.pixels[3].r), 0u);
  const FlickerMetrics t = measureFlicker(imgs, imgs[1], 8.0, 2);
  EXPECT_EQ(t.image.pixels, f.pixels);
  EXPECT_EQ(t.mean_std, m.mean_std);
  EXPECT_EQ(t.errors[0].rmse, m.errors[1].rmse);  // the reference swapped
  EXPECT_TRUE(measureFlicker(imgs, imgs[0]).image.pixels.empty());  // no scale, no image
}

TEST(Flicker, BadInputIsRefused) {
  EXPECT_THROW(measureFlicker({}, Image(1, 1)), std::invalid_argument);
  const std::vector<Image> mixed{Image(1, 1), Image(2, 1)};
  EXPECT_THROW(measureFlicker(mixed, Image(1, 1)), std::invalid_argument);
  EXPECT_THROW(measureFlicker(std::vector<Image>{Image(1, 1)}, Image(1, 1), -1.0), std::invalid_argument);
}

}  // namespace
