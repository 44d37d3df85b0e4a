#include "model/Flicker.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

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

// f(i) for i in [0, n) on up to `threads` threads (each takes every threads-th i).
template <class F>
void parallelFor(size_t n, unsigned threads, F&& f) {
  threads = unsigned(std::min<size_t>(std::max(1u, threads), n));
  if (threads <= 1) {
    for (size_t i = 0; i < n; ++i) f(i);
    return;
  }
  std::vector<std::thread> pool;
  for (unsigned t = 0; t < threads; ++t)
    pool.emplace_back([&, t] {
      for (size_t i = t; i < n; i += threads) f(i);
    });
  for (auto& th : pool) th.join();
}

}  // namespace

float srgb8ToLinear(uint8_t code) {
  const double c = code / 255.0;
  return float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
}

FlickerMetrics measureFlicker(std::span<const Image> images, const Image& reference, double image_scale,
                              unsigned threads) {
  checkImages(images);
  if (!(image_scale >= 0) || !std::isfinite(image_scale))
    throw std::invalid_argument("flicker: the image scale must be >= 0 and finite");
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  const size_t n = images.size(), pixels = images[0].pixels.size();
  FlickerMetrics m;
  m.images = unsigned(n);
  // Each image's sRGB8 codes once (the encoding is most of the work), and its
  // error against the reference, image by image in parallel.
  std::vector<uint8_t> codes(n * pixels * 3);
  m.errors.resize(n);
  parallelFor(n, threads, [&](size_t i) {
    uint8_t* c = codes.data() + i * pixels * 3;
    for (const Rgb& p : images[i].pixels) {
      *c++ = toSrgb8(p.r);
      *c++ = toSrgb8(p.g);
      *c++ = toSrgb8(p.b);
    }
    m.errors[i] = compareImages(images[i], reference);
  });
  if (image_scale > 0) m.image = Image(images[0].width, images[0].height);
  // Per pixel and channel: N^2 variance = N sum(c^2) - (sum c)^2, exact in integers.
  double sum = 0.0;
  const uint64_t nn = n;
  for (size_t p = 0; p < pixels; ++p) {
    uint64_t worst = 0;
    bool differs = false;
    for (size_t ch = 0; ch < 3; ++ch) {
      uint64_t s = 0, sq = 0;
      uint8_t lo = 255, hi = 0;
      for (size_t i = 0; i < n; ++i) {
        const uint8_t v = codes[(i * pixels + p) * 3 + ch];
        s += v;
        sq += uint64_t(v) * v;
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
      worst = std::max(worst, nn * sq - s * s);
      differs |= lo != hi;
    }
    const double std = std::sqrt(double(worst)) / double(n);
    sum += std;
    m.max_std = std::max(m.max_std, std);
    m.differing_pixels += differs;
    if (image_scale > 0) {
      const float v = srgb8ToLinear(uint8_t(std::min(255.0, std::round(image_scale * std))));
      m.image.pixels[p] = {v, v, v};
    }
  }
  m.mean_std = pixels ? sum / double(pixels) : 0.0;
  m.differing_fraction = pixels ? double(m.differing_pixels) / double(pixels) : 0.0;
  double rmse_sum = 0.0;
  for (const ImageMetrics& e : m.errors) {
    rmse_sum += e.rmse;
    m.rmse_worst = std::max(m.rmse_worst, e.rmse);
  }
  m.rmse_mean = std::min(m.rmse_worst, rmse_sum / double(n));  // (rounding never above the worst)
  return m;
}

}  // namespace oit::model
