// Bit-accurate storage formats: exhaustive scalar codecs checked against
// independent reference computations, row layouts, hybrid tail saturation.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cfenv>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "model/FloatSpecials.hpp"
#include "model/AlgorithmDetail.hpp"  // requantizedHalves
#include "model/StorageFormat.hpp"

using namespace oit::model;

namespace {

using oit::model::testutil::kInf;
using oit::model::testutil::kNaN;

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }
float fromBits(uint32_t u) { return std::bit_cast<float>(u); }

// Reference unorm8: the code is the number of thresholds (k + 1/2)/255 that v
// reaches, counted with exact integer-valued doubles (v * 510 is exact).
uint8_t refUnorm8(float v) {
  if (std::isnan(v)) return 0;
  const double v510 = double(std::clamp(v, 0.0f, 1.0f)) * 510.0;
  unsigned code = 0;
  for (unsigned k = 0; k < 255; ++k)
    if (v510 >= 2.0 * k + 1.0) ++code;
  return uint8_t(code);
}

// Value of a binary16 code from its definition.
double halfCodeValue(uint16_t h) {
  const int s = h >> 15, e = (h >> 10) & 31, m = h & 1023;
  const double mag = e == 0 ? std::ldexp(double(m), -24) : std::ldexp(1.0 + m / 1024.0, e - 15);
  return s ? -mag : mag;
}

// Reference float -> binary16 value: scale so one half ulp is 1, round to
// nearest even with nearbyint, saturate at 65504. Everything is exact in double.
double refHalfValue(float v) {
  if (std::isnan(v)) return 0.0;
  const double a = std::fabs(double(v));
  double r;
  if (std::isinf(v) || a >= 65536.0) {
    r = 65504.0;
  } else if (a == 0.0) {
    r = 0.0;
  } else {
    const int e = std::max(std::ilogb(a), -14);
    const double ulp = std::ldexp(1.0, e - 10);
    r = std::nearbyint(a / ulp) * ulp;
    if (r > 65504.0) r = 65504.0;
  }
  return std::signbit(v) ? -r : r;
}

void expectHalfMatchesReference(float v) {
  const uint16_t h = encodeHalf(v);
  ASSERT_NE((h >> 10) & 31, 31) << "Inf/NaN code for input bits 0x" << std::hex << bits(v);
  const double ref = refHalfValue(v);
  const double got = halfCodeValue(h);
  ASSERT_EQ(got, ref) << "input bits 0x" << std::hex << bits(v);
  if (ref == 0.0) {
    ASSERT_EQ(std::signbit(got), std::signbit(ref)) << "zero sign, bits 0x" << std::hex << bits(v);
  }
}

}  // namespace

TEST(StorageFormat, RowSizes) {
  static_assert(rowWords(StorageFormat::Fp32) == 5 && rowBytes(StorageFormat::Fp32) == 20);
  static_assert(rowWords(StorageFormat::Rgba8T8Z32) == 2 && rowBytes(StorageFormat::Rgba8T8Z32) == 8);
  static_assert(rowWords(StorageFormat::Fp16) == 3 && rowBytes(StorageFormat::Fp16) == 12);
  EXPECT_EQ(rowBytes(StorageFormat::Rgba8T8Z32), 8u);  // the MLAB paper's 8-byte row
}

TEST(StorageFormat, Unorm8AllCodesRoundTrip) {
  for (unsigned k = 0; k < 256; ++k) {
    const float v = decodeUnorm8(uint8_t(k));
    EXPECT_EQ(v, float(k) / 255.0f) << k;
    EXPECT_EQ(encodeUnorm8(v), k) << k;
  }
  EXPECT_EQ(decodeUnorm8(0), 0.0f);
  EXPECT_EQ(decodeUnorm8(255), 1.0f);
}

TEST(StorageFormat, Unorm8RoundingAgainstReference) {
  // Every float just around each rounding threshold, plus a dense sweep of [0,1].
  for (unsigned k = 0; k < 255; ++k) {
    const float mid = float((k + 0.5) / 255.0);
    float v = mid;
    for (int i = 0; i < 4; ++i) v = std::nextafter(v, 0.0f);
    for (int i = 0; i < 9; ++i, v = std::nextafter(v, 2.0f)) ASSERT_EQ(encodeUnorm8(v), refUnorm8(v)) << v;
  }
  for (uint32_t u = 0; u <= bits(1.0f); u += 997) ASSERT_EQ(encodeUnorm8(fromBits(u)), refUnorm8(fromBits(u)));
  EXPECT_EQ(encodeUnorm8(0.5f), 128);  // 127.5 rounds up
  EXPECT_EQ(encodeUnorm8(0.25f), 64);  // 63.75
}

// The four-channel encoder every rgba8 row store uses: byte i is
// encodeUnorm8 of channel i, for special values in every lane and a sweep of
// all floats (every 251st bit pattern, each value in each lane). The whole
// 2^32 in every lane was checked once (session 12: 0 mismatches, ~1 minute).
TEST(StorageFormat, Unorm8FourChannelsEqualsOneByOne) {
  const auto check = [](float a, float b, float c, float d) {
    const uint32_t got = encodeUnorm8x4(a, b, c, d);
    const float v[4] = {a, b, c, d};
    for (unsigned k = 0; k < 4; ++k)
      if (uint8_t(got >> (8 * k)) != encodeUnorm8(v[k])) return ::testing::AssertionFailure() << "lane " << k << " value " << v[k];
    return ::testing::AssertionSuccess();
  };
  const float special[] = {kNaN, -kNaN, kInf, -kInf, 0.0f, -0.0f, 1.0f, -1.0f, 0.5f, 1e-45f, -1e-45f,
                           std::nextafter(1.0f, 0.0f), std::nextafter(1.0f, 2.0f), float(0.5 / 255.0),
                           std::nextafter(float(0.5 / 255.0), 0.0f), float(254.5 / 255.0), 1e30f};
  for (float a : special)
    for (float b : special) ASSERT_TRUE(check(a, b, b, a)) << a << " " << b;
  for (uint64_t u = 0; u < (uint64_t(1) << 32); u += 251 * 4) {
    const uint32_t b = uint32_t(u);
    ASSERT_TRUE(check(fromBits(b), fromBits(b + 251), fromBits(b + 502), fromBits(b + 753))) << b;
    ASSERT_TRUE(check(fromBits(b + 753), fromBits(b), fromBits(b + 251), fromBits(b + 502))) << b;
  }
  EXPECT_EQ(encodeUnorm8x4(0.0f, 1.0f, 0.5f, kNaN), 0x00'80'FF'00u);
}

TEST(StorageFormat, Unorm8Saturation) {
  EXPECT_EQ(encodeUnorm8(-0.0f), 0);
  EXPECT_EQ(encodeUnorm8(-1.0f), 0);
  EXPECT_EQ(encodeUnorm8(-kInf), 0);
  EXPECT_EQ(encodeUnorm8(1.0001f), 255);
  EXPECT_EQ(encodeUnorm8(1e30f), 255);
  EXPECT_EQ(encodeUnorm8(kInf), 255);
  EXPECT_EQ(encodeUnorm8(kNaN), 0);
  EXPECT_EQ(encodeUnorm8(-kNaN), 0);
  EXPECT_EQ(encodeUnorm8(std::numeric_limits<float>::denorm_min()), 0);
}

TEST(StorageFormat, Unorm8DecodeTableIsTheQuotient) {
  volatile float d255 = 255.0f;  // a run-time division, not the compiler's constant folding
  for (unsigned c = 0; c < 256; ++c)
    ASSERT_EQ(bits(decodeUnorm8(uint8_t(c))), bits(float(c) / d255)) << c;
}

TEST(StorageFormat, UnormEncodeEqualsFloorFormulaSampled) {
  // The codecs truncate instead of calling floor (the saturated sum is >= 0.5).
  // This was checked over all 2^32 float bit patterns once; here a strided
  // sample of every exponent and sign plus the neighbours of each threshold.
  auto floor8 = [](float v) -> unsigned {
    if (!(v > 0.0f)) return 0;
    if (v >= 1.0f) return 255;
    return unsigned(std::floor(double(v) * 255.0 + 0.5));
  };
  auto floor10 = [](float v) -> unsigned {
    if (!(v > 0.0f)) return 0;
    if (v >= 1.0f) return 1023;
    return unsigned(std::floor(double(v) * 1023.0 + 0.5));
  };
  for (uint64_t u = 0; u < (uint64_t(1) << 32); u += 4099) {
    const float v = fromBits(uint32_t(u));
    ASSERT_EQ(encodeUnorm8(v), floor8(v)) << std::hex << u;
    ASSERT_EQ(encodeUnorm10(v), floor10(v)) << std::hex << u;
  }
  for (unsigned k = 0; k < 1023; ++k) {
    float v = float((k + 0.5) / 1023.0);
    for (int i = 0; i < 4; ++i) v = std::nextafter(v, 0.0f);
    for (int i = 0; i < 9; ++i, v = std::nextafter(v, 2.0f)) ASSERT_EQ(encodeUnorm10(v), floor10(v)) << v;
  }
  for (unsigned k = 0; k < 255; ++k) {
    float v = float((k + 0.5) / 255.0);
    for (int i = 0; i < 4; ++i) v = std::nextafter(v, 0.0f);
    for (int i = 0; i < 9; ++i, v = std::nextafter(v, 2.0f)) ASSERT_EQ(encodeUnorm8(v), floor8(v)) << v;
  }
  for (float v : {1.0f, std::nextafter(1.0f, 0.0f), fromBits(1), 0.5f / 255.0f, kInf, -kInf, kNaN, -0.0f})
    EXPECT_EQ(encodeUnorm8(v), floor8(v)) << v;
}

TEST(StorageFormat, StoredRowWordsReencodeToThemselves) {
  // mlab / kbuffer / hybrid shift stored rows as raw words instead of
  // decode + encode; that is exact because every code round-trips: all 2^32
  // rgba8t8z32 colour words (one byte per channel, so each byte's 256 codes
  // are enough) and every fp16 word without an Inf / NaN half.
  for (unsigned c = 0; c < 256; ++c) {
    for (unsigned lane = 0; lane < 4; ++lane) {
      const uint32_t w[2] = {c << (8 * lane) | (0x5Au << (8 * ((lane + 1) % 4))), 0x3F000000u};
      uint32_t back[2];
      encodeRow(StorageFormat::Rgba8T8Z32, decodeRow(StorageFormat::Rgba8T8Z32, w), back);
      ASSERT_EQ(back[0], w[0]) << c << " lane " << lane;
      ASSERT_EQ(back[1], w[1]);
    }
  }
  for (uint32_t h = 0; h < 65536; ++h) {
    for (uint32_t other : {0x0000u, 0x8000u, 0x3C00u, 0x7BFFu}) {
      const uint32_t w[3] = {h | other << 16, other | h << 16, 0x80000001u};
      uint32_t back[3];
      encodeRow(StorageFormat::Fp16, decodeRow(StorageFormat::Fp16, w), back);
      // The in-place shift's rewrite equals the codec round trip for every code.
      ASSERT_EQ(oit::model::detail::requantizedHalves(w[0]), back[0]) << std::hex << h;
      ASSERT_EQ(oit::model::detail::requantizedHalves(w[1]), back[1]) << std::hex << h;
      ASSERT_EQ(back[2], w[2]);
      if ((h & 0x7C00u) != 0x7C00u) {
        ASSERT_EQ(back[0], w[0]) << std::hex << h;
        ASSERT_EQ(back[1], w[1]) << std::hex << h;
      }
    }
  }
  // -0, the smallest and largest subnormals and the saturated codes by name.
  for (uint16_t h : {0x8000, 0x0001, 0x8001, 0x03FF, 0x83FF, 0x0400, 0x7BFF, 0xFBFF})
    EXPECT_EQ(encodeHalf(decodeHalf(h)), h) << std::hex << h;
}

TEST(StorageFormat, HalfAllCodesRoundTrip) {
  int finite = 0;
  for (uint32_t c = 0; c < 65536; ++c) {
    const uint16_t h = uint16_t(c);
    const float v = decodeHalf(h);
    ASSERT_TRUE(std::isfinite(v)) << c;
    if (((h >> 10) & 31) == 31) {
      // Inf codes read as +-65504, NaN codes as 0: never non-finite.
      if (h & 1023) {
        EXPECT_EQ(bits(v), 0u) << c;
      } else {
        EXPECT_EQ(v, (h & 0x8000) ? -65504.0f : 65504.0f) << c;
      }
      continue;
    }
    ++finite;
    ASSERT_EQ(double(v), halfCodeValue(h)) << c;
    ASSERT_EQ(std::signbit(v), bool(h & 0x8000)) << c;
    ASSERT_EQ(encodeHalf(v), h) << c;
  }
  EXPECT_EQ(finite, 63488);  // 2 x 31 exponents x 1024
}

TEST(StorageFormat, HalfEncodeMatchesReferenceSweep) {
  ASSERT_EQ(std::fegetround(), FE_TONEAREST);
  // A strided sweep over all 2^32 bit patterns (every exponent, both signs, NaNs).
  for (uint64_t u = 0; u < (uint64_t(1) << 32); u += 251) expectHalfMatchesReference(fromBits(uint32_t(u)));
  // Every half value and every midpoint between neighbours (exact ties), +-3 float ulps.
  for (uint32_t c = 0; c < 0x7C00; ++c) {
    const double lo = halfCodeValue(uint16_t(c));
    const double hi = c + 1 < 0x7C00 ? halfCodeValue(uint16_t(c + 1)) : 65536.0;
    for (double centre : {lo, (lo + hi) / 2.0}) {
      const float f = float(centre);  // exact: halves and their midpoints fit in 24 bits
      ASSERT_EQ(double(f), centre);
      float v = f;
      for (int i = 0; i < 3; ++i) v = std::nextafter(v, 0.0f);
      for (int i = 0; i < 7; ++i, v = std::nextafter(v, kInf)) {
        expectHalfMatchesReference(v);
        expectHalfMatchesReference(-v);
      }
    }
  }
#ifdef __FLT16_MAX__
  // Second, unrelated reference: the compiler's own conversion (IEEE RNE, overflow to Inf).
  for (uint64_t u = 0; u < (uint64_t(1) << 32); u += 4093) {
    const float v = fromBits(uint32_t(u));
    if (std::isnan(v)) continue;
    const _Float16 h = static_cast<_Float16>(v);
    float expect = static_cast<float>(h);
    if (std::isinf(expect)) expect = std::copysign(65504.0f, expect);
    ASSERT_EQ(bits(decodeHalf(encodeHalf(v))), bits(expect)) << std::hex << u;
  }
#endif
}

TEST(StorageFormat, HalfSaturationAndSpecials) {
  EXPECT_EQ(encodeHalf(65504.0f), 0x7BFF);
  EXPECT_EQ(encodeHalf(65519.996f), 0x7BFF);
  EXPECT_EQ(encodeHalf(65520.0f), 0x7BFF);  // IEEE would round this tie to Inf
  EXPECT_EQ(encodeHalf(1e10f), 0x7BFF);
  EXPECT_EQ(encodeHalf(kInf), 0x7BFF);
  EXPECT_EQ(encodeHalf(-kInf), 0xFBFF);
  EXPECT_EQ(encodeHalf(-1e30f), 0xFBFF);
  EXPECT_EQ(encodeHalf(kNaN), 0x0000);
  EXPECT_EQ(encodeHalf(-kNaN), 0x0000);
  EXPECT_EQ(encodeHalf(0.0f), 0x0000);
  EXPECT_EQ(encodeHalf(-0.0f), 0x8000);
  EXPECT_EQ(encodeHalf(1.0f), 0x3C00);
  EXPECT_EQ(encodeHalf(0x1p-24f), 0x0001);                          // smallest subnormal
  EXPECT_EQ(encodeHalf(0x1p-25f), 0x0000);                          // tie -> even (0)
  EXPECT_EQ(encodeHalf(std::nextafter(0x1p-25f, 1.0f)), 0x0001);
  EXPECT_EQ(encodeHalf(3 * 0x1p-25f), 0x0002);                      // 1.5 ulp tie -> even (2)
  EXPECT_EQ(encodeHalf(0x1p-14f - 0x1p-25f), 0x0400);               // rounds up into the normals
  EXPECT_EQ(encodeHalf(1.0f + 0x1p-11f), 0x3C00);                   // tie -> even
  EXPECT_EQ(encodeHalf(1.0f + 3 * 0x1p-11f), 0x3C02);               // tie -> even (up)
  EXPECT_EQ(decodeHalf(0x7C00), 65504.0f);
  EXPECT_EQ(decodeHalf(0xFC00), -65504.0f);
  EXPECT_EQ(decodeHalf(0x7E00), 0.0f);
}

TEST(StorageFormat, Rgba8T8Z32Layout) {
  uint32_t w[2];
  encodeRow(StorageFormat::Rgba8T8Z32, {1.0f, 0.5f, 0.0f, 0.25f, 0.75f}, w);
  EXPECT_EQ(w[0], 0x400080FFu);  // R=255, G=128, B=0, T=64 from the low byte up
  EXPECT_EQ(w[1], 0x3F400000u);  // 0.75f
  const LayerRow r = decodeRow(StorageFormat::Rgba8T8Z32, w);
  EXPECT_EQ(r.r, 1.0f);
  EXPECT_EQ(r.g, 128.0f / 255.0f);
  EXPECT_EQ(r.b, 0.0f);
  EXPECT_EQ(r.t, 64.0f / 255.0f);
  EXPECT_EQ(r.z, 0.75f);
}

TEST(StorageFormat, Fp16Layout) {
  uint32_t w[3];
  encodeRow(StorageFormat::Fp16, {1.0f, 0.5f, -2.0f, 0.25f, 0.75f}, w);
  EXPECT_EQ(w[0], 0x38003C00u);  // r in the low half, g in the high half
  EXPECT_EQ(w[1], 0x3400C000u);  // b = -2 low, t = 0.25 high
  EXPECT_EQ(w[2], 0x3F400000u);
  const LayerRow r = quantizeRow(StorageFormat::Fp16, {0.1f, 70000.0f, kNaN, 0.3f, 0.5f});
  EXPECT_EQ(r.r, 0.0999755859375f);  // nearest half to 0.1
  EXPECT_EQ(r.g, 65504.0f);
  EXPECT_EQ(r.b, 0.0f);
  EXPECT_EQ(r.t, 0.300048828125f);
}

TEST(StorageFormat, Fp32IsLossless) {
  uint32_t w[5];
  const LayerRow in{0.1f, 1e-40f, -3.5f, 0.999f, 0.123456f};
  encodeRow(StorageFormat::Fp32, in, w);
  EXPECT_EQ(w[0], bits(0.1f));
  EXPECT_EQ(w[4], bits(0.123456f));
  const LayerRow out = decodeRow(StorageFormat::Fp32, w);
  EXPECT_EQ(bits(out.r), bits(in.r));
  EXPECT_EQ(bits(out.g), bits(in.g));
  EXPECT_EQ(bits(out.b), bits(in.b));
  EXPECT_EQ(bits(out.t), bits(in.t));
  EXPECT_EQ(bits(out.z), bits(in.z));
}

TEST(StorageFormat, DepthPreservedBitExactly) {
  const std::vector<uint32_t> depths = {
      bits(kInf), 0x00000000u, 0x80000000u, 0x00000001u, 0x007FFFFFu, 0x00400000u,
      bits(1.0f), bits(std::nextafter(1.0f, 0.0f)), bits(0.5f), 0x7F7FFFFFu, bits(-kInf), 0x3EAAAAABu};
  for (StorageFormat f : {StorageFormat::Fp32, StorageFormat::Rgba8T8Z32, StorageFormat::Fp16})
    for (uint32_t z : depths) {
      uint32_t w[5] = {};
      encodeRow(f, {0.3f, 0.2f, 0.1f, 0.6f, fromBits(z)}, w);
      EXPECT_EQ(w[rowWords(f) - 1], z) << toString(f);
      EXPECT_EQ(bits(decodeRow(f, w).z), z) << toString(f) << " z=0x" << std::hex << z;
    }
}

TEST(StorageFormat, EmptyRowSurvivesEveryFormat) {
  for (StorageFormat f : {StorageFormat::Fp32, StorageFormat::Rgba8T8Z32, StorageFormat::Fp16}) {
    const LayerRow r = quantizeRow(f, {0.0f, 0.0f, 0.0f, 1.0f, kInf});
    EXPECT_EQ(r.r, 0.0f);
    EXPECT_EQ(r.g, 0.0f);
    EXPECT_EQ(r.b, 0.0f);
    EXPECT_EQ(r.t, 1.0f);
    EXPECT_EQ(r.z, kInf);
  }
}

TEST(StorageFormat, QuantizedColourAndTransmittanceAlwaysFinite) {
  const float nasty[] = {kNaN, -kNaN, kInf, -kInf, 1e30f, -1e30f, 65520.0f, -0.0f, 1e-45f};
  for (StorageFormat f : {StorageFormat::Rgba8T8Z32, StorageFormat::Fp16})
    for (float v : nasty) {
      const LayerRow r = quantizeRow(f, {v, v, v, v, 0.5f});
      EXPECT_TRUE(std::isfinite(r.r) && std::isfinite(r.g) && std::isfinite(r.b) && std::isfinite(r.t))
          << toString(f) << " " << v;
    }
  const LayerRow r = quantizeRow(StorageFormat::Rgba8T8Z32, {kNaN, 2.0f, -1.0f, kInf, 0.5f});
  EXPECT_EQ(r.r, 0.0f);
  EXPECT_EQ(r.g, 1.0f);
  EXPECT_EQ(r.b, 0.0f);
  EXPECT_EQ(r.t, 1.0f);
}

TEST(StorageFormat, ParseAndNames) {
  for (StorageFormat f : {StorageFormat::Fp32, StorageFormat::Rgba8T8Z32, StorageFormat::Fp16})
    EXPECT_EQ(parseStorageFormat(toString(f)), f);
  EXPECT_STREQ(toString(StorageFormat::Rgba8T8Z32), "rgba8t8z32");
  try {
    parseStorageFormat("FP32");
    FAIL() << "accepted FP32";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("fp32, rgba8t8z32, fp16"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("'FP32'"), std::string::npos) << e.what();
  }
  EXPECT_THROW(parseStorageFormat(""), std::invalid_argument);
}

TEST(StorageFormat, Unorm10) {
  for (unsigned k = 0; k < 1024; ++k) ASSERT_EQ(encodeUnorm10(decodeUnorm10(uint16_t(k))), k);
  EXPECT_EQ(encodeUnorm10(0.5f), 512);  // 511.5 rounds up
  EXPECT_EQ(encodeUnorm10(2.0f), 1023);
  EXPECT_EQ(encodeUnorm10(kNaN), 0);
  EXPECT_EQ(decodeUnorm10(0xFC00 | 1023), 1.0f);  // high bits ignored
}

TEST(HybridTailFormat, Layout) {
  uint32_t w[2];
  encodeTail({0.25f, 0.5f, 0.0f, 1.0f, 3}, w);
  EXPECT_EQ(w[0], 256u | 512u << 10);  // ratios 255.75 -> 256, 511.5 -> 512, 0
  EXPECT_EQ(w[1], 0x3C00u | 3u << 16);  // alpha 1.0 as binary16, count 3
  const HybridTail t = decodeTail(w);
  EXPECT_EQ(t.r, 256.0f / 1023.0f);
  EXPECT_EQ(t.g, 512.0f / 1023.0f);
  EXPECT_EQ(t.b, 0.0f);
  EXPECT_EQ(t.alpha_sum, 1.0f);
  EXPECT_EQ(t.count, 3u);
  // Colour is stored normalised, so it keeps 10 bits at any alpha magnitude.
  const HybridTail big = quantizeTail({300.0f, 150.0f, 0.6f, 600.0f, 900});
  EXPECT_EQ(big.alpha_sum, 600.0f);
  EXPECT_EQ(big.r, 512.0f / 1023.0f * 600.0f);
  EXPECT_EQ(big.g, 256.0f / 1023.0f * 600.0f);  // 0.25 * 1023 = 255.75 -> 256
  EXPECT_EQ(big.b, 1.0f / 1023.0f * 600.0f);    // 0.001 * 1023 = 1.023 -> 1
}

TEST(HybridTailFormat, SpareBitsZeroAndIgnored) {
  uint32_t w[2];
  encodeTail({5.0f, 5.0f, 5.0f, 5.0f, 7}, w);
  EXPECT_EQ(w[0] >> 30, 0u);
  const HybridTail a = decodeTail(w);
  w[0] |= 0xC0000000u;
  const HybridTail b = decodeTail(w);
  EXPECT_EQ(a.r, b.r);
  EXPECT_EQ(a.b, b.b);
  EXPECT_EQ(a.b, 5.0f);
}

TEST(HybridTailFormat, CountSaturatesNeverWraps) {
  EXPECT_EQ(quantizeTail({0, 0, 0, 1.0f, 65534}).count, 65534u);
  EXPECT_EQ(quantizeTail({0, 0, 0, 1.0f, 65535}).count, 65535u);
  EXPECT_EQ(quantizeTail({0, 0, 0, 1.0f, 65536}).count, 65535u);  // would wrap to 0
  EXPECT_EQ(quantizeTail({0, 0, 0, 1.0f, 0xFFFFFFFFu}).count, 65535u);
  // Incrementing a saturated tail stays saturated.
  HybridTail t{0, 0, 0, 0, 65535};
  t.count += 1;
  EXPECT_EQ(quantizeTail(t).count, 65535u);
}

TEST(HybridTailFormat, ColourAndAlphaSaturate) {
  uint32_t w[2];
  encodeTail({2.0f, 1.0f, 1.5f, 1.0f, 1}, w);  // colour above alpha: invalid input, clamps
  EXPECT_EQ(w[0], 1023u | 1023u << 10 | 1023u << 20);  // 2046 would wrap to 1022 with & 0x3FF
  const HybridTail big = quantizeTail({5e5f, 1e6f, 0.0f, 1e6f, 65535});
  EXPECT_EQ(big.alpha_sum, 65504.0f);
  EXPECT_EQ(big.r, 512.0f / 1023.0f * 65504.0f);  // ratio 0.5 kept
  EXPECT_EQ(big.g, 65504.0f);
  EXPECT_EQ(big.b, 0.0f);
  const HybridTail inf = quantizeTail({kInf, 1.0f, kNaN, kInf, 1});
  EXPECT_EQ(inf.alpha_sum, 65504.0f);
  EXPECT_EQ(inf.r, 65504.0f);
  EXPECT_EQ(inf.g, 0.0f);
  EXPECT_EQ(inf.b, 0.0f);
}

TEST(HybridTailFormat, DegenerateInputsGiveZeroNeverNaN) {
  for (const HybridTail& in : {HybridTail{0.5f, 0.5f, 0.5f, 0.0f, 4}, HybridTail{kNaN, kNaN, kNaN, kNaN, 0},
                               HybridTail{1.0f, 1.0f, 1.0f, -1.0f, 2}, HybridTail{0.1f, 0.1f, 0.1f, -0.0f, 1}}) {
    const HybridTail t = quantizeTail(in);
    EXPECT_EQ(t.r, 0.0f);
    EXPECT_EQ(t.g, 0.0f);
    EXPECT_EQ(t.b, 0.0f);
    EXPECT_EQ(t.alpha_sum, 0.0f);
    EXPECT_FALSE(std::signbit(t.alpha_sum));
  }
}

TEST(HybridTailFormat, RepeatedAccumulationThroughStorage) {
  // One-pass HT: decode, add a row, encode, 100 times (alpha 0.5, colour (0.2, 0.4, 0.6)).
  uint32_t w[2] = {0, 0};
  for (int i = 0; i < 100; ++i) {
    HybridTail t = decodeTail(w);
    t.r += 0.5f * 0.2f;
    t.g += 0.5f * 0.4f;
    t.b += 0.5f * 0.6f;
    t.alpha_sum += 0.5f;
    t.count += 1;
    encodeTail(t, w);
  }
  const HybridTail t = decodeTail(w);
  EXPECT_EQ(t.alpha_sum, 50.0f);  // multiples of 0.5 up to 1024 are exact in binary16
  EXPECT_EQ(t.count, 100u);
  EXPECT_EQ(w[0] & 0x3FFu, 205u);         // round(0.2 * 1023) = round(204.6)
  EXPECT_EQ((w[0] >> 10) & 0x3FFu, 409u);  // round(409.2)
  EXPECT_EQ((w[0] >> 20) & 0x3FFu, 614u);  // round(613.8)
}
