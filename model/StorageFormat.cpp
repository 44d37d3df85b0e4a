#include "model/StorageFormat.hpp"

#include <bit>
#include <cmath>
#include <stdexcept>
#include <string>

namespace oit::model {

namespace {

// v saturated to [0,1] and rounded to an n-bit unorm code. double makes
// v * maxCode exact (24 + 10 bits < 53), so the +0.5/floor rounding is exact.
uint32_t encodeUnorm(double v, uint32_t maxCode) {
  if (!(v > 0.0)) return 0;  // negative, zero and NaN
  if (v >= 1.0) return maxCode;
  return static_cast<uint32_t>(std::floor(v * maxCode + 0.5));
}

}  // namespace

uint8_t encodeUnorm8(float v) { return static_cast<uint8_t>(encodeUnorm(v, 255)); }
float decodeUnorm8(uint8_t code) { return float(code) / 255.0f; }

uint16_t encodeUnorm10(float v) { return static_cast<uint16_t>(encodeUnorm(v, 1023)); }
float decodeUnorm10(uint16_t code) { return float(code & 0x3FFu) / 1023.0f; }

uint16_t encodeHalf(float v) {
  const uint32_t bits = std::bit_cast<uint32_t>(v);
  const uint16_t sign = static_cast<uint16_t>((bits >> 16) & 0x8000u);
  const uint32_t abs = bits & 0x7FFFFFFFu;
  if (abs > 0x7F800000u) return 0;  // NaN
  // 65520 is the midpoint between 65504 and 2^16; ties-to-even would round it
  // (and everything above) to Inf, which we saturate instead.
  if (abs >= 0x477FF000u) return sign | 0x7BFFu;
  if (abs >= 0x38800000u) {  // >= 2^-14: normal half
    const uint32_t exp = (abs >> 23) - 127 + 15;
    const uint32_t mant = abs & 0x7FFFFFu;
    uint32_t h = (exp << 10) | (mant >> 13);
    const uint32_t rest = mant & 0x1FFFu;
    // A carry out of the mantissa correctly bumps the exponent.
    if (rest > 0x1000u || (rest == 0x1000u && (h & 1u))) ++h;
    return sign | static_cast<uint16_t>(h);
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

float decodeHalf(uint16_t code) {
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

void encodeRow(StorageFormat f, const LayerRow& row, uint32_t* w) {
  switch (f) {
    case StorageFormat::Fp32:
      w[0] = std::bit_cast<uint32_t>(row.r);
      w[1] = std::bit_cast<uint32_t>(row.g);
      w[2] = std::bit_cast<uint32_t>(row.b);
      w[3] = std::bit_cast<uint32_t>(row.t);
      w[4] = std::bit_cast<uint32_t>(row.z);
      return;
    case StorageFormat::Rgba8T8Z32:
      w[0] = uint32_t(encodeUnorm8(row.r)) | uint32_t(encodeUnorm8(row.g)) << 8 |
             uint32_t(encodeUnorm8(row.b)) << 16 | uint32_t(encodeUnorm8(row.t)) << 24;
      w[1] = std::bit_cast<uint32_t>(row.z);
      return;
    case StorageFormat::Fp16:
      w[0] = uint32_t(encodeHalf(row.r)) | uint32_t(encodeHalf(row.g)) << 16;
      w[1] = uint32_t(encodeHalf(row.b)) | uint32_t(encodeHalf(row.t)) << 16;
      w[2] = std::bit_cast<uint32_t>(row.z);
      return;
  }
  throw std::invalid_argument("encodeRow: unknown storage format");
}

LayerRow decodeRow(StorageFormat f, const uint32_t* w) {
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
  throw std::invalid_argument("decodeRow: unknown storage format");
}

LayerRow quantizeRow(StorageFormat f, const LayerRow& row) {
  uint32_t w[5];
  encodeRow(f, row, w);
  return decodeRow(f, w);
}

StorageFormat parseStorageFormat(std::string_view name) {
  if (name == "fp32") return StorageFormat::Fp32;
  if (name == "rgba8t8z32") return StorageFormat::Rgba8T8Z32;
  if (name == "fp16") return StorageFormat::Fp16;
  throw std::invalid_argument("unknown storage format '" + std::string(name) +
                              "' (valid: fp32, rgba8t8z32, fp16)");
}

const char* toString(StorageFormat f) {
  switch (f) {
    case StorageFormat::Fp32: return "fp32";
    case StorageFormat::Rgba8T8Z32: return "rgba8t8z32";
    case StorageFormat::Fp16: return "fp16";
  }
  return "unknown";
}

// Tail words: w0 = r10 | g10 << 10 | b10 << 20 (bits 30-31 zero, ignored on
// decode); w1 = half(alpha_sum) | count16 << 16. See FORMATS.md.
void encodeTail(const HybridTail& t, uint32_t words[2]) {
  // alpha_sum is a sum of (1 - t) >= 0: negative or NaN input stores 0.
  const float alpha = (t.alpha_sum > 0.0f) ? t.alpha_sum : 0.0f;
  const uint16_t alphaCode = encodeHalf(alpha);
  uint32_t rgb = 0;
  if (alpha > 0.0f) {
    // Ratio of the unquantised sums, so the stored colour is the resolve
    // colour accColour / accAlpha rounded once. An infinite alpha only keeps
    // infinite colour channels (ratio 1); inf/inf would be NaN.
    auto ratio = [alpha](float c) {
      if (std::isinf(alpha)) return encodeUnorm(std::isinf(c) && c > 0 ? 1.0 : 0.0, 1023);
      return encodeUnorm(double(c) / double(alpha), 1023);
    };
    rgb = ratio(t.r) | ratio(t.g) << 10 | ratio(t.b) << 20;
  }
  const uint32_t count = t.count > 0xFFFFu ? 0xFFFFu : t.count;
  words[0] = rgb;
  words[1] = uint32_t(alphaCode) | count << 16;
}

HybridTail decodeTail(const uint32_t words[2]) {
  const float alpha = decodeHalf(uint16_t(words[1]));
  const float a = alpha > 0.0f ? alpha : 0.0f;  // a foreign negative code reads as 0
  auto colour = [a](uint32_t code) { return decodeUnorm10(uint16_t(code & 0x3FFu)) * a; };
  return {colour(words[0]), colour(words[0] >> 10), colour(words[0] >> 20), a, words[1] >> 16};
}

HybridTail quantizeTail(const HybridTail& t) {
  uint32_t w[2];
  encodeTail(t, w);
  return decodeTail(w);
}

}  // namespace oit::model
