#include "model/Metrics.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

namespace oit::model {

namespace {

// Metrics describe the displayable image: linear values outside [0,1] (e.g.
// weighted-sum overshoot) count as the value the PNG shows.
double clamp01(float v) { return v < 0.0f ? 0.0 : (v > 1.0f ? 1.0 : double(v)); }

// Rec.709 / sRGB primaries luma of gamma-encoded 8-bit codes, in [0,1].
double luma8(const int code[3]) { return (0.2126 * code[0] + 0.7152 * code[1] + 0.0722 * code[2]) / 255.0; }

}  // namespace

double psnrFromMse8(double mse8) {
  if (!(mse8 > 0.0)) return kPsnrCapDb;  // identical: PSNR would be +inf
  return std::min(kPsnrCapDb, 10.0 * std::log10(255.0 * 255.0 / mse8));
}

double meanSsim(const double* x, const double* y, uint32_t width, uint32_t height) {
  if (width == 0 || height == 0) throw std::invalid_argument("meanSsim: empty image");
  // Window side: 11, or the largest odd size that fits a smaller image.
  uint32_t side = std::min({kSsimWindow, width, height});
  if (side % 2 == 0) --side;
  std::vector<double> g(side);
  double gsum = 0.0;
  const double c = (side - 1) / 2.0;
  for (uint32_t i = 0; i < side; ++i) {
    g[i] = std::exp(-((i - c) * (i - c)) / (2.0 * kSsimSigma * kSsimSigma));
    gsum += g[i];
  }
  for (double& v : g) v /= gsum;  // separable: the 2D window sums to 1

  const uint32_t ow = width - side + 1, oh = height - side + 1;  // 'valid' windows only
  // Horizontal pass of the five moment images, then vertical.
  constexpr int kPlanes = 5;  // x, y, x^2, y^2, xy
  std::vector<double> hp(std::size_t(kPlanes) * ow * height, 0.0);
  for (uint32_t r = 0; r < height; ++r)
    for (uint32_t col = 0; col < ow; ++col) {
      double s[kPlanes] = {};
      for (uint32_t k = 0; k < side; ++k) {
        const std::size_t i = std::size_t(r) * width + col + k;
        const double a = x[i], b = y[i], w = g[k];
        s[0] += w * a;
        s[1] += w * b;
        s[2] += w * a * a;
        s[3] += w * b * b;
        s[4] += w * a * b;
      }
      for (int p = 0; p < kPlanes; ++p) hp[(std::size_t(p) * height + r) * ow + col] = s[p];
    }
  const double c1 = (kSsimK1 * 1.0) * (kSsimK1 * 1.0);  // L = 1
  const double c2 = (kSsimK2 * 1.0) * (kSsimK2 * 1.0);
  double total = 0.0;
  for (uint32_t r = 0; r < oh; ++r)
    for (uint32_t col = 0; col < ow; ++col) {
      double m[kPlanes] = {};
      for (uint32_t k = 0; k < side; ++k)
        for (int p = 0; p < kPlanes; ++p)
          m[p] += g[k] * hp[(std::size_t(p) * height + r + k) * ow + col];
      const double mx = m[0], my = m[1];
      const double vx = m[2] - mx * mx, vy = m[3] - my * my, cxy = m[4] - mx * my;
      // Denominator >= c1 * (c2 - rounding) > 0: never 0/0.
      total += ((2.0 * mx * my + c1) * (2.0 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2));
    }
  return total / (double(ow) * oh);
}

ImageMetrics compareImages(const Image& img, const Image& ref) {
  if (!img.sameSize(ref))
    throw std::invalid_argument(fmt::format("compareImages: size mismatch {}x{} vs reference {}x{}",
                                            img.width, img.height, ref.width, ref.height));
  if (img.width == 0 || img.height == 0)
    throw std::invalid_argument("compareImages: empty images");
  const std::size_t n = std::size_t(img.width) * img.height;
  if (img.pixels.size() != n || ref.pixels.size() != n)
    throw std::invalid_argument("compareImages: pixel count does not match width x height");
  requireFinite(img, "compareImages image");
  requireFinite(ref, "compareImages reference");

  double sumSq = 0.0, sumAbs = 0.0, maxAbs = 0.0, sumSq8 = 0.0;
  uint64_t over = 0;
  std::vector<double> ly(n), lr(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Rgb& p = img.pixels[i];
    const Rgb& q = ref.pixels[i];
    const float pc[3] = {p.r, p.g, p.b};
    const float qc[3] = {q.r, q.g, q.b};
    double pixMax = 0.0;
    int pc8[3], qc8[3];
    for (int ch = 0; ch < 3; ++ch) {
      const double d = std::fabs(clamp01(pc[ch]) - clamp01(qc[ch]));
      sumSq += d * d;
      sumAbs += d;
      pixMax = std::max(pixMax, d);
      pc8[ch] = toSrgb8(pc[ch]);
      qc8[ch] = toSrgb8(qc[ch]);
      const double d8 = double(pc8[ch] - qc8[ch]);
      sumSq8 += d8 * d8;
    }
    maxAbs = std::max(maxAbs, pixMax);
    if (pixMax > 1.0 / 255.0) ++over;
    ly[i] = luma8(pc8);
    lr[i] = luma8(qc8);
  }
  const double samples = 3.0 * double(n);
  ImageMetrics m{};
  m.rmse = std::sqrt(sumSq / samples);
  m.psnr = psnrFromMse8(sumSq8 / samples);
  m.ssim = meanSsim(ly.data(), lr.data(), img.width, img.height);
  m.mean_abs = sumAbs / samples;
  m.max_abs = maxAbs;
  m.pixels_over_1_255 = over;
  return m;
}

}  // namespace oit::model
