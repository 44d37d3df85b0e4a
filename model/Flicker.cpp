#include "model/Flicker.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace oit::model {

namespace {

void checkImages(std::span<const Image> images) {
  if (images.empty()) throw std::invalid_argument("flicker: no images");
  for (size_t i = 0; i < images.size(); ++i) {
    if (!images[i].sameSize(images[0]))
      throw std::invalid_argument(fmt::format("flicker: image {} is {} x {}, image 0 {} x {}", i, images[i].width,
                                              images[i].height, images[0].width, images[0].height));
    requireFinite(images[i], "flicker image");
  }
}

// Calls f(pixel, std, differs) for every pixel: the largest channel's
// standard deviation of the sRGB8 codes across the images, exact (integer
// sums: N sum(c^2) - (sum c)^2 = N^2 variance).
template <class F>
void forEachPixel(std::span<const Image> images, F&& f) {
  const size_t pixels = images[0].pixels.size();
  const uint64_t n = images.size();
  for (size_t p = 0; p < pixels; ++p) {
    uint64_t worst = 0;  // the largest N^2 variance of the three channels
    bool differs = false;
    for (int ch = 0; ch < 3; ++ch) {
      uint64_t sum = 0, sq = 0;
      uint8_t lo = 255, hi = 0;
      for (const Image& img : images) {
        const Rgb& c = img.pixels[p];
        const uint8_t v = toSrgb8(ch == 0 ? c.r : ch == 1 ? c.g : c.b);
        sum += v;
        sq += uint64_t(v) * v;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      worst = std::max(worst, n * sq - sum * sum);
      differs |= lo != hi;
    }
    f(p, std::sqrt(double(worst)) / double(n), differs);
  }
}

}  // namespace

float srgb8ToLinear(uint8_t code) {
  const double c = code / 255.0;
  return float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

FlickerMetrics measureFlicker(std::span<const Image> images, const Image& reference) {
  checkImages(images);
  FlickerMetrics m;
  m.images = unsigned(images.size());
  double sum = 0.0;
  forEachPixel(images, [&](size_t, double std, bool differs) {
    sum += std;
    m.max_std = std::max(m.max_std, std);
    m.differing_pixels += differs;
  });
  const size_t pixels = images[0].pixels.size();
  m.mean_std = pixels ? sum / double(pixels) : 0.0;
  m.differing_fraction = pixels ? double(m.differing_pixels) / double(pixels) : 0.0;
  double rmse_sum = 0.0;
  for (const Image& img : images) {
    m.errors.push_back(compareImages(img, reference));
    rmse_sum += m.errors.back().rmse;
    m.rmse_worst = std::max(m.rmse_worst, m.errors.back().rmse);
  }
  m.rmse_mean = std::min(m.rmse_worst, rmse_sum / double(images.size()));  // (rounding never above the worst)
  return m;
}

Image flickerImage(std::span<const Image> images, double scale) {
  checkImages(images);
  if (!(scale > 0) || !std::isfinite(scale)) throw std::invalid_argument("flicker: the scale must be > 0 and finite");
  Image out(images[0].width, images[0].height);
  forEachPixel(images, [&](size_t p, double std, bool) {
    const float v = srgb8ToLinear(uint8_t(std::min(255.0, std::round(scale * std))));
    out.pixels[p] = {v, v, v};
  });
  return out;
}

}  // namespace oit::model
