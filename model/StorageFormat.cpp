#include "model/StorageFormat.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

namespace oit::model {

namespace {

// v saturated to [0,1] and rounded to an n-bit unorm code. double makes
// v * maxCode exact (24 + 10 bits < 53), so the +0.5/floor rounding is exact;
// the sum is positive there, so the truncating conversion is the floor.
uint32_t encodeUnorm(double v, uint32_t maxCode) {
  if (!(v > 0.0)) return 0;  // negative, zero and NaN
  if (v >= 1.0) return maxCode;
  return static_cast<uint32_t>(v * maxCode + 0.5);
}

}  // namespace

uint16_t encodeUnorm10(float v) { return static_cast<uint16_t>(encodeUnorm(v, 1023)); }
float decodeUnorm10(uint16_t code) { return float(code & 0x3FFu) / 1023.0f; }

void unknownStorageFormat(const char* where) {
  throw std::invalid_argument(std::string(where) + ": unknown storage format");
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
