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

// An apitrace frame (--apitrace --verify). The interposer draws each captured
// transparent draw (over and premultiplied over) a second time, the check drawing,
// into its own RGBA32F target cleared to 0, and records that drawing too
// (GlTransparentReference). Three comparisons, each of like with like:
//  1. blend: the check drawing's records replayed alone, in order, by the
//     functional `alpha` algorithm over black, against GL's blend of them. Straight
//     over is exact; premultiplied colours are divided by alpha for the trace and
//     multiplied again by the model: within kPremultipliedUlpBound. GL draws with
//     its fragment colours clamped into [0, 1] (as the trace holds them, and as a
//     fixed-point target blends them). A premultiplied colour above its alpha (or
//     over alpha 0) has no straight colour in [0, 1]: with any such fragment the
//     colours are not compared (reported, `clamped`).
//  2. counts: the trace's fragments per pixel against GL's count of the check
//     drawing: equal.
//  3. drawings: the trace's transparent fragments (the application's drawing)
//     against the check drawing's records, paired per draw and pixel: the same
//     draw, primitive, pixel and depth, bit for bit, except for a draw into the
//     window: llvmpipe keeps window buffers upside down, so its fill rule gives a
//     pixel on a horizontal shared edge to the other triangle (allowed and
//     counted), and it interpolates depth from the other edge, a rounding that
//     grows with the triangle's depth slope: within kWindowDepthBound (measured:
//     at most 2 ulp on the test cube, 5.1e-6 on the glmark2 jellyfish; the depth
//     test's outcome is checked exactly by the counts). Colours within
//     kDrawingColourBound: llvmpipe compiles a shader variant per render-target
//     format, so the application's drawing (usually into an 8-bit target) and the
//     check drawing (RGBA32F) need not shade alike: its 8-bit texture filtering
//     (the "AoS" path) runs only for 8-bit targets; measured on the glmark2
//     jellyfish at most 0.0103 (traces/CAPTURE.md), 0 on untextured programs.
struct TransparentVerifyResult : VerifyResult {
  bool premultiplied = false;  // the frame has premultiplied-over draws
  uint64_t clamped = 0;        // premultiplied fragments whose straight colour the trace clamped
  uint64_t check_fragments = 0;     // records of the check drawing
  uint64_t drawing_mismatches = 0;  // trace fragments not at the check drawing's draw, primitive, pixel, depth
  uint64_t primitive_differing = 0; // window-draw fragments the two drawings give to another primitive
  uint64_t depth_differing = 0;     // trace fragments drawn into the window with another depth
  double max_depth_diff = 0;        // largest |trace - check drawing| depth of those fragments
  uint64_t colour_differing = 0;    // trace fragments whose rgba differs from the check drawing's
  double max_colour_diff = 0;       // largest |trace - check drawing| of a channel
  std::string first_drawing_difference;
  static constexpr uint32_t kPremultipliedUlpBound = 8;
  static constexpr double kDrawingColourBound = 4.0 / 255.0;
  static constexpr double kWindowDepthBound = 1e-5;
  bool drawingsAgree() const { return drawing_mismatches == 0 && max_colour_diff <= kDrawingColourBound; }
  bool passes() const {
    if (count_pixels_differing != 0 || !drawingsAgree()) return false;
    if (clamped != 0) return true;  // colour not comparable (reported)
    return premultiplied ? max_ulps <= kPremultipliedUlpBound && max_abs <= 1e-6 : channels_differing == 0;
  }
};
TransparentVerifyResult verifyTransparentDraws(const FrameCapture& frame);

// Distance between two finite floats in representable steps.
uint32_t ulpDistance(float a, float b);

}  // namespace oit::capture
