// Image metrics against hand-computed values and an independent brute-force SSIM.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <vector>

#include "model/Metrics.hpp"

using namespace oit::model;

namespace {

// Deterministic noise in [0,1).
struct Lcg {
  uint32_t s;
  double next() {
    s = s * 1664525u + 1013904223u;
    return (s >> 8) / 16777216.0;
  }
};

// sRGB 8-bit code from the IEC 61966-2-1 formula, written independently here.
int srgbCode(double l) {
  l = std::clamp(l, 0.0, 1.0);
  const double s = l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
  return int(std::lround(s * 255.0));
}

double lumaOf(const Rgb& p) {
  return 0.2126 * srgbCode(p.r) / 255.0 + 0.7152 * srgbCode(p.g) / 255.0 + 0.0722 * srgbCode(p.b) / 255.0;
}

// Straightforward SSIM: explicit 2D Gaussian window, two-pass moments, every
// valid window position, mean. Window side per METRICS.md.
double bruteSsim(const Image& a, const Image& b) {
  const int w = int(a.width), h = int(a.height);
  int side = std::min({11, w, h});
  if (side % 2 == 0) --side;
  const double c = (side - 1) / 2.0, sigma = 1.5;
  std::vector<double> win(side * side);
  double sum = 0;
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i) sum += win[j * side + i] = std::exp(-((i - c) * (i - c) + (j - c) * (j - c)) / (2 * sigma * sigma));
  for (double& v : win) v /= sum;
  const double C1 = 0.01 * 0.01, C2 = 0.03 * 0.03;
  double total = 0;
  int n = 0;
  for (int y0 = 0; y0 + side <= h; ++y0)
    for (int x0 = 0; x0 + side <= w; ++x0) {
      double mx = 0, my = 0;
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
          mx += win[j * side + i] * lumaOf(a.at(x0 + i, y0 + j));
          my += win[j * side + i] * lumaOf(b.at(x0 + i, y0 + j));
        }
      double vx = 0, vy = 0, cxy = 0;
      for (int j = 0; j < side; ++j)
        for (int i = 0; i < side; ++i) {
          const double dx = lumaOf(a.at(x0 + i, y0 + j)) - mx, dy = lumaOf(b.at(x0 + i, y0 + j)) - my;
          vx += win[j * side + i] * dx * dx;
          vy += win[j * side + i] * dy * dy;
          cxy += win[j * side + i] * dx * dy;
        }
      total += (2 * mx * my + C1) * (2 * cxy + C2) / ((mx * mx + my * my + C1) * (vx + vy + C2));
      ++n;
    }
  return total / n;
}

Image noise(uint32_t w, uint32_t h, uint32_t seed) {
  Image img(w, h);
  Lcg r{seed};
  for (Rgb& p : img.pixels) p = {float(r.next()), float(r.next()), float(r.next())};
  return img;
}

}  // namespace

TEST(Metrics, IdenticalImages) {
  const Image ref = noise(23, 17, 1);
  const ImageMetrics m = compareImages(ref, ref);
  EXPECT_EQ(m.rmse, 0.0);
  EXPECT_EQ(m.psnr, kPsnrCapDb);
  EXPECT_EQ(m.psnr, 100.0);
  EXPECT_EQ(m.ssim, 1.0);
  EXPECT_EQ(m.mean_abs, 0.0);
  EXPECT_EQ(m.max_abs, 0.0);
  EXPECT_EQ(m.pixels_over_1_255, 0u);
}

TEST(Metrics, ConstantOffsetGivesExactRmse) {
  const Image ref(8, 6, {0.5f, 0.25f, 0.125f});
  const Image img(8, 6, {0.75f, 0.5f, 0.375f});
  const ImageMetrics m = compareImages(img, ref);
  EXPECT_EQ(m.rmse, 0.25);
  EXPECT_EQ(m.mean_abs, 0.25);
  EXPECT_EQ(m.max_abs, 0.25);
  EXPECT_EQ(m.pixels_over_1_255, 48u);
}

TEST(Metrics, ValuesClampToDisplayRange) {
  const ImageMetrics m = compareImages(Image(4, 4, {1.5f, -0.5f, 1.0f}), Image(4, 4, {1.0f, 0.0f, 1.0f}));
  EXPECT_EQ(m.rmse, 0.0);
  EXPECT_EQ(m.psnr, 100.0);
  EXPECT_EQ(m.ssim, 1.0);
}

TEST(Metrics, PsnrOfKnownCodeDifference) {
  // 4x4 = 48 channel samples; one sample differs by 10 sRGB codes: MSE = 100/48.
  const Image ref(4, 4, {0.0f, 0.0f, 0.0f});
  Image img = ref;
  img.at(2, 3).g = 0.003035269835488375f;  // linear value of code 10 (10/255/12.92)
  const ImageMetrics m = compareImages(img, ref);
  EXPECT_NEAR(m.psnr, 44.94321598243498, 1e-12);  // 10 log10(255^2 * 48 / 100)
  EXPECT_NEAR(m.rmse, double(0.003035269835488375f) / std::sqrt(48.0), 1e-15);
  EXPECT_EQ(m.max_abs, double(0.003035269835488375f));
  EXPECT_EQ(m.pixels_over_1_255, 0u);  // 0.00304 < 1/255
  // Add four samples differing by 5 codes: MSE = 200/48.
  const float code5 = 5.0f / 255.0f / 12.92f;
  img.at(0, 0) = {code5, code5, 0.0f};
  img.at(1, 0).b = code5;
  img.at(3, 3).r = code5;
  EXPECT_NEAR(compareImages(img, ref).psnr, 41.932916025795166, 1e-12);
}

TEST(Metrics, PsnrFromMse8) {
  EXPECT_NEAR(psnrFromMse8(1.0), 48.1308036086791, 1e-12);
  EXPECT_EQ(psnrFromMse8(0.0), 100.0);
  EXPECT_EQ(psnrFromMse8(1e-20), 100.0);  // finite cap, never +inf
  EXPECT_NEAR(psnrFromMse8(65025.0), 0.0, 1e-12);
}

TEST(Metrics, PixelsOverOneCode) {
  Image ref(3, 2, {0.5f, 0.5f, 0.5f});
  Image img = ref;
  img.at(0, 0).r = 0.5f + 0.003f;  // under 1/255
  img.at(1, 0).g = 0.5f + 0.005f;  // over
  img.at(2, 1) = {0.4f, 0.6f, 0.5f};  // over
  const ImageMetrics m = compareImages(img, ref);
  EXPECT_EQ(m.pixels_over_1_255, 2u);
  EXPECT_NEAR(m.max_abs, 0.1, 1e-7);
  EXPECT_NEAR(m.mean_abs, (0.003 + 0.005 + 0.1 + 0.1) / 18.0, 1e-7);
}

TEST(Metrics, SsimOfConstantImagesIsTheLuminanceTerm) {
  // Zero variance: SSIM = (2xy + C1) / (x^2 + y^2 + C1).
  const double c1 = 1e-4;
  // Tolerance: the window moments E[x^2] - E[x]^2 cancel to ~1e-16, not 0.
  EXPECT_NEAR(compareImages(Image(16, 16, {1, 1, 1}), Image(16, 16, {0, 0, 0})).ssim, c1 / (1 + c1), 1e-11);
  const ImageMetrics m = compareImages(Image(12, 20, {0.5f, 0.5f, 0.5f}), Image(12, 20, {0.18f, 0.18f, 0.18f}));
  const double x = 188 / 255.0, y = 118 / 255.0;  // sRGB codes of 0.5 and 0.18
  EXPECT_NEAR(m.ssim, (2 * x * y + c1) / (x * x + y * y + c1), 1e-11);
}

TEST(Metrics, SsimMatchesBruteForceOnNoise) {
  const Image ref = noise(29, 21, 7);
  Image noisy = ref;
  Lcg r{99};
  for (Rgb& p : noisy.pixels) {
    p.r = std::clamp(float(p.r + 0.2 * (r.next() - 0.5)), 0.0f, 1.0f);
    p.g = std::clamp(float(p.g + 0.2 * (r.next() - 0.5)), 0.0f, 1.0f);
    p.b = std::clamp(float(p.b + 0.2 * (r.next() - 0.5)), 0.0f, 1.0f);
  }
  const double ssim = compareImages(noisy, ref).ssim;
  EXPECT_NEAR(ssim, bruteSsim(noisy, ref), 1e-12);
  EXPECT_LT(ssim, 0.99);
  EXPECT_GT(ssim, 0.3);
}

TEST(Metrics, SsimMatchesBruteForceOnMeanShift) {
  const Image ref = noise(15, 13, 3);
  Image shifted = ref;
  for (Rgb& p : shifted.pixels) p = {p.r * 0.5f + 0.3f, p.g * 0.5f + 0.3f, p.b * 0.5f + 0.3f};
  const double ssim = compareImages(shifted, ref).ssim;
  EXPECT_NEAR(ssim, bruteSsim(shifted, ref), 1e-12);
  EXPECT_LT(ssim, 0.999);
}

TEST(Metrics, SsimOnImagesSmallerThanTheWindow) {
  for (auto [w, h] : {std::pair{7u, 5u}, {12u, 4u}, {2u, 9u}, {1u, 1u}, {10u, 10u}}) {
    const Image a = noise(w, h, w * 31 + h);
    const Image b = noise(w, h, w * 17 + h + 5);
    EXPECT_NEAR(compareImages(a, b).ssim, bruteSsim(a, b), 1e-12) << w << "x" << h;
    EXPECT_EQ(compareImages(a, a).ssim, 1.0) << w << "x" << h;
  }
  // 1x1: window of one pixel, zero variance: pure luminance term.
  const double y = 188 / 255.0;
  EXPECT_DOUBLE_EQ(compareImages(Image(1, 1, {0.5f, 0.5f, 0.5f}), Image(1, 1)).ssim, 1e-4 / (y * y + 1e-4));
}

TEST(Metrics, RejectsMismatchedEmptyAndNonFinite) {
  EXPECT_THROW(compareImages(Image(4, 3), Image(3, 4)), std::invalid_argument);
  EXPECT_THROW(compareImages(Image(), Image()), std::invalid_argument);
  Image bad(4, 4);
  bad.at(3, 3).b = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(compareImages(bad, Image(4, 4)), std::invalid_argument);
  EXPECT_THROW(compareImages(Image(4, 4), bad), std::invalid_argument);
}
