// Checks a captured trace against GL's own images of the same frame: the trace
// replayed by the functional `alpha` algorithm (over-blending in submission order)
// against GL's blended RGBA32F framebuffer, and per-pixel record counts against
// GL's counting pass.
#pragma once

#include <cstdint>
#include <string>

#include "traces/capture/ApitraceCapture.hpp"
#include "traces/capture/GlCapture.hpp"

namespace oit::capture {

struct VerifyResult {
  uint64_t pixels = 0;
  uint64_t channels_compared = 0;  // 3 per pixel (rgb; the model keeps no alpha)
  uint64_t channels_differing = 0;
  uint32_t max_ulps = 0;           // largest difference, in units in the last place
  double max_abs = 0;
  uint64_t count_pixels_differing = 0;  // pixels whose record count differs from GL's
  uint64_t fragments = 0;
  std::string first_difference;    // "" when none; else the first pixel and both values
  bool opaque_draws = false;       // the trace has opaque draws (a non-black background)
  bool exact() const { return channels_differing == 0 && count_pixels_differing == 0; }
  // Without opaque draws the replay must be bit-exact. Over an opaque background the
  // model resolves A + T * bg once where GL blends into bg at every step: the same
  // value rounded differently, within kOpaqueUlpBound (measured: at most 3 ulp).
  static constexpr uint32_t kOpaqueUlpBound = 8;
  bool passes() const {
    if (count_pixels_differing != 0) return false;
    return opaque_draws ? max_ulps <= kOpaqueUlpBound && max_abs <= 1e-6 : channels_differing == 0;
  }
};

// Reads the trace at path (its size must be the reference's) and compares.
VerifyResult verifyTrace(const std::string& path, const GlReference& ref);

// An apitrace frame (--apitrace --verify): its transparent draws (over and
// premultiplied over) replayed alone, in order, by the functional `alpha` algorithm
// over black, against GL's blend of the same draws into the interposer's RGBA32F
// target (GlTransparentReference); per-pixel record counts against that drawing's
// counts. Straight over is exact; premultiplied colours are divided by alpha for the
// trace and multiplied again by the model: within kPremultipliedUlpBound. GL draws
// the reference with its fragment colours clamped into [0, 1] (as the trace holds
// them, and as a fixed-point target blends them). A premultiplied colour above its
// alpha (or over alpha 0) has no straight colour in [0, 1]: with any such
// fragment the colours are not compared (reported, `clamped`).
struct TransparentVerifyResult : VerifyResult {
  bool premultiplied = false;  // the frame has premultiplied-over draws
  uint64_t clamped = 0;        // premultiplied fragments whose straight colour the trace clamped
  static constexpr uint32_t kPremultipliedUlpBound = 8;
  bool passes() const {
    if (count_pixels_differing != 0) return false;
    if (clamped != 0) return true;  // colour not comparable (reported)
    return premultiplied ? max_ulps <= kPremultipliedUlpBound && max_abs <= 1e-6 : channels_differing == 0;
  }
};
TransparentVerifyResult verifyTransparentDraws(const FrameCapture& frame);

// Distance between two finite floats in representable steps.
uint32_t ulpDistance(float a, float b);

}  // namespace oit::capture
