// Classifies a draw's blend state (attachment 0) into the modes the trace keeps
// apart: off (opaque), straight over and premultiplied over (transparent), additive,
// multiplicative, other. Pure function of GL enums, tested without GL.
#pragma once

#include <cstdint>

#include "traces/capture/interposer/CaptureStream.hpp"

namespace oit::capture::stream {

// Only the colour (RGB) equation and factors decide: the model keeps no destination
// alpha, so the alpha factors change nothing it draws.
inline BlendMode classifyBlend(bool enabled, uint32_t eq_rgb, uint32_t src_rgb, uint32_t dst_rgb) {
  constexpr uint32_t kAdd = 0x8006, kZero = 0, kOne = 1, kSrcColor = 0x0300, kSrcAlpha = 0x0302,
                     kOneMinusSrcAlpha = 0x0303, kDstColor = 0x0306;
  if (!enabled) return kBlendOff;
  if (eq_rgb != kAdd) return kBlendOther;
  if (src_rgb == kSrcAlpha && dst_rgb == kOneMinusSrcAlpha) return kBlendOver;
  if (src_rgb == kOne && dst_rgb == kOneMinusSrcAlpha) return kBlendPremulOver;
  if ((src_rgb == kSrcAlpha || src_rgb == kOne) && dst_rgb == kOne) return kBlendAdditive;
  if ((src_rgb == kDstColor && dst_rgb == kZero) || (src_rgb == kZero && dst_rgb == kSrcColor))
    return kBlendMultiply;
  // ONE, ZERO with blending on writes the source unchanged: opaque.
  if (src_rgb == kOne && dst_rgb == kZero) return kBlendOff;
  return kBlendOther;
}

inline const char* blendModeName(uint32_t m) {
  switch (m) {
    case kBlendOff: return "opaque";
    case kBlendOver: return "over";
    case kBlendPremulOver: return "premultiplied over";
    case kBlendAdditive: return "additive";
    case kBlendMultiply: return "multiplicative";
    default: return "other blend";
  }
}

}  // namespace oit::capture::stream
