// Bit-accurate per-pixel storage formats of the blending array (one row per
// layer) and of hybrid transparency's packed 8-byte tail. Bit layouts are
// documented in model/FORMATS.md; every codec here is exact and deterministic
// (no dependence on the FPU rounding mode or build flags).
#pragma once

#include <array>
#include <bit>
#include <cstdint>
#include <string_view>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace oit::model {

enum class StorageFormat : uint8_t {
  Fp32,        // r, g, b, t, z as IEEE binary32: lossless reference
  Rgba8T8Z32,  // MLAB paper's 8-byte row: premultiplied RGB unorm8, T unorm8, z fp32
  Fp16,        // r, g, b, t as IEEE binary16 (saturating), z fp32
};

// One blending-array row: premultiplied colour, transmittance, depth.
struct LayerRow {
  float r, g, b;  // premultiplied linear colour
  float t;        // transmittance (1 - alpha) of this row
  float z;        // window depth; an empty row holds +inf
};

// 32-bit words per row.
constexpr unsigned rowWords(StorageFormat f) {
  switch (f) {
    case StorageFormat::Fp32: return 5;
    case StorageFormat::Rgba8T8Z32: return 2;
    case StorageFormat::Fp16: return 3;
  }
  return 0;
}
constexpr unsigned rowBytes(StorageFormat f) { return 4u * rowWords(f); }

// words must hold rowWords(f) elements. Depth is always stored as its raw
// binary32 bits (bit-exact, including +inf, -0 and denormals). Inline,
// defined after the scalar codecs: the blending-array inserts call them with
// a constant format, so each call reduces to that format's fields.
inline void encodeRow(StorageFormat f, const LayerRow& row, uint32_t* words);
inline LayerRow decodeRow(StorageFormat f, const uint32_t* words);
// decodeRow(f, encodeRow(f, row)): what a row becomes after one store.
LayerRow quantizeRow(StorageFormat f, const LayerRow& row);

// "fp32", "rgba8t8z32", "fp16" (exact, lower case); otherwise throws
// std::invalid_argument listing the valid names.
StorageFormat parseStorageFormat(std::string_view name);
const char* toString(StorageFormat f);

// --- scalar codecs -------------------------------------------------------
// unorm8 and binary16 are inline: the row codecs call them per channel.
// unorm8: code = floor(v * 255 + 0.5) after saturating v to [0,1]; NaN -> 0.
// double makes v * 255 exact (24 + 8 bits); the saturated sum is >= 0.5, so
// the truncating conversion is the floor.
inline uint8_t encodeUnorm8(float v) {
  const float s = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f;  // NaN fails v > 0
  return static_cast<uint8_t>(double(s) * 255.0 + 0.5);
}
// Four channels at once, channel i in byte i: the codes of encodeUnorm8, by
// the same arithmetic (a row's store encodes four; one at a time was the
// costliest part of an rgba8 insert). SSE2 (every x86-64): max(v, 0) gives 0
// for NaN as v > 0 does (MAXPS returns its second operand when one is NaN),
// min(., 1) saturates, then double v * 255 + 0.5 and truncation, two lanes at
// a time. test_storage_format.cpp checks it against encodeUnorm8.
inline uint32_t encodeUnorm8x4(float c0, float c1, float c2, float c3) {
#if defined(__SSE2__)
  __m128 v = _mm_setr_ps(c0, c1, c2, c3);
  v = _mm_min_ps(_mm_max_ps(v, _mm_setzero_ps()), _mm_set1_ps(1.0f));
  const __m128d k255 = _mm_set1_pd(255.0), half = _mm_set1_pd(0.5);
  const __m128d lo = _mm_add_pd(_mm_mul_pd(_mm_cvtps_pd(v), k255), half);
  const __m128d hi = _mm_add_pd(_mm_mul_pd(_mm_cvtps_pd(_mm_movehl_ps(v, v)), k255), half);
  const __m128i codes = _mm_unpacklo_epi64(_mm_cvttpd_epi32(lo), _mm_cvttpd_epi32(hi));  // 0..255 each
  const __m128i bytes = _mm_packus_epi16(_mm_packs_epi32(codes, codes), _mm_setzero_si128());
  return uint32_t(_mm_cvtsi128_si32(bytes));
#else
  return uint32_t(encodeUnorm8(c0)) | uint32_t(encodeUnorm8(c1)) << 8 | uint32_t(encodeUnorm8(c2)) << 16 |
         uint32_t(encodeUnorm8(c3)) << 24;
#endif
}
// code / 255, correctly rounded: the 256 quotients, so a decode is one load.
inline constexpr std::array<float, 256> kUnorm8Values = [] {
  std::array<float, 256> t{};
  for (unsigned c = 0; c < 256; ++c) t[c] = float(c) / 255.0f;
  return t;
}();
inline float decodeUnorm8(uint8_t code) { return kUnorm8Values[code]; }
// IEEE binary16, round to nearest even. Overflow (|v| >= 65520, including
// +-inf) saturates to +-65504, never Inf; NaN -> +0. -0 stays -0.
inline uint16_t encodeHalf(float v) {
  const uint32_t bits = std::bit_cast<uint32_t>(v);
  const uint16_t sign = static_cast<uint16_t>((bits >> 16) & 0x8000u);
  const uint32_t abs = bits & 0x7FFFFFFFu;
  if (abs > 0x7F800000u) return 0;  // NaN
  // 65520 is the midpoint between 65504 and 2^16; ties-to-even would round it
  // (and everything above) to Inf, which we saturate instead.
  if (abs >= 0x477FF000u) return sign | 0x7BFFu;
  if (abs >= 0x38800000u) {  // >= 2^-14: normal half
    // Re-bias the exponent (127 -> 15) and drop 13 mantissa bits, rounding to
    // nearest even without a branch: adding 0xFFF plus the kept lowest bit
    // carries exactly when the dropped bits exceed 0x1000 or equal it with an
    // odd kept bit. A carry out of the mantissa correctly bumps the exponent.
    return sign | static_cast<uint16_t>((abs - ((127u - 15u) << 23) + 0xFFFu + ((abs >> 13) & 1u)) >> 13);
  }
  // 2^-25 is the midpoint between 0 and the smallest subnormal 2^-24; the tie
  // goes to the even code, 0.
  if (abs <= 0x33000000u) return sign;
  // Subnormal half: code = value / 2^-24 = mant24 >> (126 - exp).
  const uint32_t exp = abs >> 23;  // 102..112 here
  const uint32_t mant = (abs & 0x7FFFFFu) | 0x800000u;
  const uint32_t shift = 126 - exp;  // 14..24
  uint32_t h = mant >> shift;
  const uint32_t rest = mant & ((1u << shift) - 1u);
  const uint32_t halfway = 1u << (shift - 1);
  if (rest > halfway || (rest == halfway && (h & 1u))) ++h;  // may become 2^-14, a normal: fine
  return sign | static_cast<uint16_t>(h);
}
// Exact for finite codes; the Inf codes decode to +-65504 and NaN codes to 0,
// so foreign data can never inject a non-finite value.
inline float decodeHalf(uint16_t code) {
  const uint32_t sign = uint32_t(code & 0x8000u) << 16;
  const uint32_t exp = (code >> 10) & 0x1Fu;
  const uint32_t mant = code & 0x3FFu;
  if (exp == 0x1F) {
    if (mant != 0) return 0.0f;                                 // NaN code
    return std::bit_cast<float>(sign | 0x477FE000u);            // Inf code -> +-65504
  }
  if (exp == 0) {
    // Subnormal (or zero): mant * 2^-24, exact in binary32.
    const float mag = float(mant) * 0x1p-24f;
    return sign ? -mag : mag;
  }
  return std::bit_cast<float>(sign | ((exp - 15 + 127) << 23) | (mant << 13));
}
// unorm10 (used by the hybrid tail): floor(v * 1023 + 0.5) after saturating to [0,1]; NaN -> 0.
uint16_t encodeUnorm10(float v);
float decodeUnorm10(uint16_t code);  // code / 1023, correctly rounded; only the low 10 bits are read

// --- row codecs -----------------------------------------------------------
// Throws std::invalid_argument naming `where` (a format value outside the enum).
[[noreturn]] void unknownStorageFormat(const char* where);

inline void encodeRow(StorageFormat f, const LayerRow& row, uint32_t* w) {
  switch (f) {
    case StorageFormat::Fp32:
      w[0] = std::bit_cast<uint32_t>(row.r);
      w[1] = std::bit_cast<uint32_t>(row.g);
      w[2] = std::bit_cast<uint32_t>(row.b);
      w[3] = std::bit_cast<uint32_t>(row.t);
      w[4] = std::bit_cast<uint32_t>(row.z);
      return;
    case StorageFormat::Rgba8T8Z32:
      w[0] = encodeUnorm8x4(row.r, row.g, row.b, row.t);
      w[1] = std::bit_cast<uint32_t>(row.z);
      return;
    case StorageFormat::Fp16:
      w[0] = uint32_t(encodeHalf(row.r)) | uint32_t(encodeHalf(row.g)) << 16;
      w[1] = uint32_t(encodeHalf(row.b)) | uint32_t(encodeHalf(row.t)) << 16;
      w[2] = std::bit_cast<uint32_t>(row.z);
      return;
  }
  unknownStorageFormat("encodeRow");
}

inline LayerRow decodeRow(StorageFormat f, const uint32_t* w) {
  switch (f) {
    case StorageFormat::Fp32:
      return {std::bit_cast<float>(w[0]), std::bit_cast<float>(w[1]), std::bit_cast<float>(w[2]),
              std::bit_cast<float>(w[3]), std::bit_cast<float>(w[4])};
    case StorageFormat::Rgba8T8Z32:
      return {decodeUnorm8(uint8_t(w[0])), decodeUnorm8(uint8_t(w[0] >> 8)),
              decodeUnorm8(uint8_t(w[0] >> 16)), decodeUnorm8(uint8_t(w[0] >> 24)),
              std::bit_cast<float>(w[1])};
    case StorageFormat::Fp16:
      return {decodeHalf(uint16_t(w[0])), decodeHalf(uint16_t(w[0] >> 16)),
              decodeHalf(uint16_t(w[1])), decodeHalf(uint16_t(w[1] >> 16)),
              std::bit_cast<float>(w[2])};
  }
  unknownStorageFormat("decodeRow");
}

// --- hybrid transparency's packed 8-byte tail (MLAB paper, Sec. 4.2) ------
// Holds the running sums of the one-pass HT tail. The 30 colour bits store
// the *normalised* colour accColour / accAlpha (10:10:10 unorm in [0,1]),
// which is exactly the colour the HT resolve needs and stays in [0,1] for
// valid premultiplied input (each row's colour <= its alpha). The 16 alpha
// bits store accAlpha as IEEE binary16 (saturating at 65504), the 16 count
// bits the fragment count (saturating at 65535). Saturate, never wrap.
struct HybridTail {
  float r, g, b;      // accumulated premultiplied colour (sum of row colours)
  float alpha_sum;    // accumulated alpha, sum of (1 - t)
  uint32_t count;     // fragments accumulated
};
void encodeTail(const HybridTail& tail, uint32_t words[2]);
// Colour comes back as stored ratio x decoded alpha_sum (0 when alpha_sum is 0).
HybridTail decodeTail(const uint32_t words[2]);
HybridTail quantizeTail(const HybridTail& tail);  // decodeTail(encodeTail(tail))

}  // namespace oit::model
