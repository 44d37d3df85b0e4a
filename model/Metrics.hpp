// Image-error metrics against a reference image; exact definitions in
// model/METRICS.md. Every field is always finite.
#pragma once

#include <cstdint>

#include "model/Image.hpp"

namespace oit::model {

struct ImageMetrics {
  double rmse;      // over linear RGB channels, each clamped to [0,1]
  double psnr;      // dB on sRGB 8-bit codes, capped at kPsnrCapDb (identical -> cap)
  double ssim;      // mean windowed SSIM (Wang et al. 2004) on Rec.709 luma of sRGB8 codes
  double mean_abs;  // mean |img - ref| over clamped linear channels
  double max_abs;   // max  |img - ref| over clamped linear channels
  uint64_t pixels_over_1_255;  // pixels whose largest channel error exceeds 1/255
};

inline constexpr double kPsnrCapDb = 100.0;
inline constexpr unsigned kSsimWindow = 11;  // Gaussian window side
inline constexpr double kSsimSigma = 1.5;
inline constexpr double kSsimK1 = 0.01, kSsimK2 = 0.03;

// Throws std::invalid_argument on size mismatch, empty images or NaN/Inf pixels.
ImageMetrics compareImages(const Image& img, const Image& ref);

// Building blocks, exposed for tests and reports.
double psnrFromMse8(double mse8);  // 10 log10(255^2 / mse8), capped; mse8 = 0 -> cap
// Mean SSIM of two luma planes (row-major, values in [0,1]) with the window
// rule of METRICS.md (shrinks to the largest odd size that fits).
double meanSsim(const double* x, const double* y, uint32_t width, uint32_t height);

}  // namespace oit::model
