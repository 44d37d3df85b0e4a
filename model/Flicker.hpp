// Flicker across runs of one frame: how much the images of N runs that
// differ only in timing (shader-latency seeds) differ from each other, in the
// sRGB 8-bit codes a display shows. Definitions in model/METRICS.md.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "model/Image.hpp"
#include "model/Metrics.hpp"

namespace oit::model {

struct FlickerMetrics {
  unsigned images = 0;
  // Per pixel: the standard deviation across the images of each channel's
  // sRGB8 code (population, divided by N), the largest of the three channels.
  double mean_std = 0.0;  // its mean over the pixels, in sRGB8 levels
  double max_std = 0.0;   // its largest value
  uint64_t differing_pixels = 0;    // pixels whose sRGB8 codes are not the same in every image
  double differing_fraction = 0.0;  // of all pixels
  // Each image against the reference (in image order), and the mean and the
  // largest RMSE among them.
  std::vector<ImageMetrics> errors;
  double rmse_mean = 0.0, rmse_worst = 0.0;
  // With an image scale > 0: the per-pixel standard deviation as a grey image
  // whose 8-bit sRGB PNG code is min(255, round(scale x std)) (writePng
  // writes it so); empty otherwise.
  Image image;
};

// Spreads the work over up to `threads` threads (0: the machine's cores).
// Throws std::invalid_argument when there is no image, the sizes differ, a
// pixel is not finite or the scale is negative or not finite.
FlickerMetrics measureFlicker(std::span<const Image> images, const Image& reference, double image_scale = 0.0,
                              unsigned threads = 0);

// The linear value whose toSrgb8() is `code` (exact for every code 0..255).
float srgb8ToLinear(uint8_t code);

}  // namespace oit::model
