// Bit-accurate per-pixel storage formats of the blending array (one row per
// layer) and of hybrid transparency's packed 8-byte tail. Bit layouts are
// documented in model/FORMATS.md; every codec here is exact and deterministic
// (no dependence on the FPU rounding mode or build flags).
#pragma once

#include <cstdint>
#include <string_view>

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
// binary32 bits (bit-exact, including +inf, -0 and denormals).
void encodeRow(StorageFormat f, const LayerRow& row, uint32_t* words);
LayerRow decodeRow(StorageFormat f, const uint32_t* words);
// decodeRow(f, encodeRow(f, row)): what a row becomes after one store.
LayerRow quantizeRow(StorageFormat f, const LayerRow& row);

// "fp32", "rgba8t8z32", "fp16" (exact, lower case); otherwise throws
// std::invalid_argument listing the valid names.
StorageFormat parseStorageFormat(std::string_view name);
const char* toString(StorageFormat f);

// --- scalar codecs -------------------------------------------------------
// unorm8: code = floor(v * 255 + 0.5) after saturating v to [0,1]; NaN -> 0.
uint8_t encodeUnorm8(float v);
float decodeUnorm8(uint8_t code);  // code / 255, correctly rounded
// IEEE binary16, round to nearest even. Overflow (|v| >= 65520, including
// +-inf) saturates to +-65504, never Inf; NaN -> +0. -0 stays -0.
uint16_t encodeHalf(float v);
// Exact for finite codes; the Inf codes decode to +-65504 and NaN codes to 0,
// so foreign data can never inject a non-finite value.
float decodeHalf(uint16_t code);
// unorm10 (used by the hybrid tail): floor(v * 1023 + 0.5) after saturating to [0,1]; NaN -> 0.
uint16_t encodeUnorm10(float v);
float decodeUnorm10(uint16_t code);  // code / 1023, correctly rounded; only the low 10 bits are read

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
