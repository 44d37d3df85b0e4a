// LDR-FLIP (Andersson, Nilsson, Akenine-Moller, Oskarsson, Astrom, Fairchild,
// "FLIP: A Difference Evaluator for Alternating Images", HPG 2020): a per-pixel
// perceptual error in [0,1] between a reference and a test image as a viewer
// flipping between them would see it, at a given number of pixels per degree of
// visual angle. Written from the paper; the steps and constants are in
// model/METRICS.md. Inputs are 8-bit sRGB (what the PNGs hold), so FLIP, like
// PSNR and SSIM, is a function of the images a user looks at.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/Image.hpp"

namespace oit::model {

// 0.7 m from a 0.7 m wide display of 3840 pixels: 3840 pi / 180 = 67.02 pixels
// per degree, the paper's (and its reference implementation's) default.
inline constexpr double kFlipDefaultPpd = 3840.0 * 3.14159265358979323846 / 180.0;

// Pooled statistics of a FLIP map. The weighted quantiles weight each pixel by
// its own error (so large errors count more; the paper's weighted histogram):
// the smallest error e such that the errors <= e, summed, exceed q times the sum
// of all errors. All 0 for identical images.
struct FlipStats {
  double mean = 0, weighted_median = 0, weighted_q1 = 0, weighted_q3 = 0, max = 0;
};

struct FlipMap {
  uint32_t width = 0, height = 0;
  std::vector<float> error;  // row-major, top row first, each in [0,1]
  FlipStats stats;
};

// The sRGB 8-bit codes of a linear image (toSrgb8 per channel, the PNG writer's
// encoding), top row first.
Srgb8Image toSrgb8Image(const Image& img);

// LDR-FLIP of `test` against `reference` at `ppd` pixels per degree (> 0,
// finite). Throws std::invalid_argument on a size mismatch, an empty image or a
// bad ppd.
FlipMap ldrFlip(const Srgb8Image& reference, const Srgb8Image& test, double ppd = kFlipDefaultPpd);

// The pooled statistics of any error map (values in [0,1]).
FlipStats flipStats(const std::vector<float>& error);

// The FLIP map as an 8-bit PNG in the magma colour map (0 black, 1 pale
// yellow; METRICS.md), with its colour scale beneath: a gradient bar from 0 at
// the left to 1 at the right, ticks at 0, 0.25, 0.5, 0.75, 1 and the labels 0,
// 0.5 and 1. The map's rows are the PNG's first `height` rows. Written to a
// temporary file and renamed; throws std::runtime_error naming the file.
void writeFlipPng(const FlipMap& map, const std::string& path);

// Height in pixels of the scale strip writeFlipPng adds below the map.
inline constexpr uint32_t kFlipScaleRows = 20;

// magma(t) as 8-bit sRGB, t clamped to [0,1].
void magmaSrgb8(double t, uint8_t out[3]);

}  // namespace oit::model
