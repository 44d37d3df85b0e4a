// Internal helpers shared by the algorithm implementations (not a public API).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "model/OitAlgorithm.hpp"

namespace oit::model::detail {

inline constexpr float kInf = std::numeric_limits<float>::infinity();
inline constexpr unsigned kMaxLayers = 64;  // bounds the on-stack row arrays

// Row access. fp32 rows are the raw r, g, b, t, z binary32 words (FORMATS.md),
// i.e. LayerRow's own layout, so the hot path copies instead of calling the
// codec; test_algorithms checks this equals encodeRow/decodeRow.
inline LayerRow loadRow(StorageFormat f, const uint32_t* w) {
  if (f == StorageFormat::Fp32) {
    LayerRow r;
    static_assert(sizeof(LayerRow) == 5 * sizeof(uint32_t));
    std::memcpy(&r, w, sizeof r);
    return r;
  }
  return decodeRow(f, w);
}
inline void storeRow(StorageFormat f, const LayerRow& r, uint32_t* w) {
  if (f == StorageFormat::Fp32) {
    std::memcpy(w, &r, sizeof r);
    return;
  }
  encodeRow(f, r, w);
}

inline constexpr LayerRow kEmptyRow{0.0f, 0.0f, 0.0f, 1.0f, kInf};

// A fragment with a = 0 (or NaN alpha) changes no pixel in the reference;
// letting it take a layer would only push real fragments out (notes, pitfall
// 3). Every algorithm therefore discards it without touching the state.
inline bool noContribution(const Fragment& f) { return !(f.a > 0.0f); }

// encodeHalf(decodeHalf(h)) for both halves of a word, without the float
// round trip: every finite half code comes back unchanged; an Inf code decodes
// to +-65504 (re-encoded 0x7BFF / 0xFBFF), a NaN code to 0 (0x0000). encodeHalf
// never writes Inf / NaN codes, so real states take the early return.
// test_storage_format checks all 2^16 codes against the codecs.
inline uint32_t requantizedHalves(uint32_t w) {
  if ((w & 0x7C00u) != 0x7C00u && (w & 0x7C000000u) != 0x7C000000u) return w;
  auto one = [](uint32_t h) -> uint32_t {
    if ((h & 0x7C00u) != 0x7C00u) return h;
    return (h & 0x3FFu) ? 0u : (h & 0x8000u) | 0x7BFFu;
  };
  return one(w & 0xFFFFu) | one(w >> 16) << 16;
}

// The fragment as a blending-array row: premultiplied colour, T = 1 - a.
inline LayerRow fragmentRow(const Fragment& f) {
  return {f.a * f.r, f.a * f.g, f.a * f.b, 1.0f - f.a, f.z};
}

// An RGBA accumulator (render-target-like) in the storage format's precision:
// fp32 -> 4 words, fp16 -> 4 halves in 2 words, rgba8t8z32 -> 4 unorm8 in 1 word.
struct Rgba {
  float r, g, b, a;
};
inline unsigned accWords(StorageFormat f) {
  switch (f) {
    case StorageFormat::Fp32: return 4;
    case StorageFormat::Fp16: return 2;
    case StorageFormat::Rgba8T8Z32: return 1;
  }
  return 4;
}
inline Rgba loadAcc(StorageFormat f, const uint32_t* w) {
  switch (f) {
    case StorageFormat::Fp16:
      return {decodeHalf(uint16_t(w[0])), decodeHalf(uint16_t(w[0] >> 16)),
              decodeHalf(uint16_t(w[1])), decodeHalf(uint16_t(w[1] >> 16))};
    case StorageFormat::Rgba8T8Z32:
      return {decodeUnorm8(uint8_t(w[0])), decodeUnorm8(uint8_t(w[0] >> 8)),
              decodeUnorm8(uint8_t(w[0] >> 16)), decodeUnorm8(uint8_t(w[0] >> 24))};
    case StorageFormat::Fp32: break;
  }
  Rgba v;
  std::memcpy(&v, w, sizeof v);
  return v;
}
inline void storeAcc(StorageFormat f, const Rgba& v, uint32_t* w) {
  switch (f) {
    case StorageFormat::Fp16:
      w[0] = uint32_t(encodeHalf(v.r)) | uint32_t(encodeHalf(v.g)) << 16;
      w[1] = uint32_t(encodeHalf(v.b)) | uint32_t(encodeHalf(v.a)) << 16;
      return;
    case StorageFormat::Rgba8T8Z32:
      w[0] = encodeUnorm8x4(v.r, v.g, v.b, v.a);
      return;
    case StorageFormat::Fp32: break;
  }
  std::memcpy(w, &v, sizeof v);
}

inline float asFloat(uint32_t w) {
  float f;
  std::memcpy(&f, &w, 4);
  return f;
}
inline uint32_t asWord(float f) {
  uint32_t w;
  std::memcpy(&w, &f, 4);
  return w;
}

// Last line of defence of every resolve: NaN -> 0, +-Inf -> +-FLT_MAX.
inline float finiteOr0(float v) {
  if (std::isnan(v)) return 0.0f;
  return std::clamp(v, -std::numeric_limits<float>::max(), std::numeric_limits<float>::max());
}
// The final colour write saturates to [0,1], as a ROP writing a UNORM target
// does: quantised rows can round colour + transmittance just above 1 (8-bit:
// 128/255 + 128/255), and wboit's published clamp(A.a, 1e-4, 5e4) scales
// colour above 1 once the weight sum passes 5e4. The error stays measured
// against the reference; only the range is enforced here.
inline float saturate01(float v) { return std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f); }
inline Rgb finiteRgb(float r, float g, float b) { return {saturate01(r), saturate01(g), saturate01(b)}; }

[[noreturn]] void badParam(std::string_view algo, const std::string& what);
void requireLayers(std::string_view algo, const AlgorithmParams& p);
void requireFormat(std::string_view algo, const AlgorithmParams& p,
                   std::initializer_list<StorageFormat> allowed);

std::unique_ptr<OitAlgorithm> makeABuffer(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeAlpha(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeMlab(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeHybrid(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeAdaptive(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeKBuffer(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeWsum(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeWavg(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeWboit(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeSlab(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeStochastic(const AlgorithmParams&);
std::unique_ptr<OitAlgorithm> makeMlcb(const AlgorithmParams&);

// mlcb's alpha-to-coverage mask of a fragment: floor(a b) or ceil(a b) bits
// (stochastic rounding) at hashed positions, bits in 1..64. Exposed so tests
// can build an independent screen-door oracle from the same masks.
uint64_t mlcbCoverageMask(const Fragment& f, unsigned bits, uint64_t seed);

}  // namespace oit::model::detail
