// Image files: PNG row order and exact sRGB codes (read back with libpng),
// PFM bytes and bit-exact round trips, difference images.
#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <bit>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <string>
#include <vector>

#include "model/FloatSpecials.hpp"
#include "model/Image.hpp"

using namespace oit::model;
namespace fs = std::filesystem;

// A fresh directory per test, so leftover temporaries can be detected. Outside
// the anonymous namespace: the TEST_F classes derive from it, and in the unity
// build (this file included into a batch) g++ warns of a base with internal
// linkage (-Wsubobject-linkage).
class ImageFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / (std::string("oitsim_image_") + info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::vector<std::string> files() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir_)) out.push_back(e.path().filename().string());
    return out;
  }
  fs::path dir_;
};

namespace {

struct Png {
  uint32_t width = 0, height = 0;
  int bitDepth = 0, colourType = 0;
  bool hasSrgb = false;
  std::vector<std::vector<uint8_t>> rows;  // as stored: first row = top
};

Png readPngFile(const std::string& p) {
  Png out;
  FILE* f = std::fopen(p.c_str(), "rb");
  if (!f) throw std::runtime_error("cannot open " + p);
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    std::fclose(f);
    throw std::runtime_error("libpng failed on " + p);
  }
  png_init_io(png, f);
  png_read_png(png, info, PNG_TRANSFORM_IDENTITY, nullptr);
  out.width = png_get_image_width(png, info);
  out.height = png_get_image_height(png, info);
  out.bitDepth = png_get_bit_depth(png, info);
  out.colourType = png_get_color_type(png, info);
  int intent = 0;
  out.hasSrgb = png_get_sRGB(png, info, &intent) != 0;
  png_bytepp rows = png_get_rows(png, info);
  for (uint32_t y = 0; y < out.height; ++y) out.rows.emplace_back(rows[y], rows[y] + 3 * out.width);
  png_destroy_read_struct(&png, &info, nullptr);
  std::fclose(f);
  return out;
}

std::string slurp(const std::string& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void writeBytes(const std::string& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary) << bytes;
}

// Inverse sRGB transfer, written from IEC 61966-2-1 independently of the product code.
double srgbToLinear(double s) { return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4); }

uint32_t bits(float f) { return std::bit_cast<uint32_t>(f); }
using oit::model::testutil::kInf;
using oit::model::testutil::kNaN;

}  // namespace

TEST(Srgb, KnownCodes) {
  EXPECT_EQ(toSrgb8(0.5f), 188);  // 187.516
  EXPECT_EQ(toSrgb8(0.0f), 0);
  EXPECT_EQ(toSrgb8(1.0f), 255);
  EXPECT_EQ(toSrgb8(0.18f), 118);  // 117.98
  EXPECT_EQ(toSrgb8(0.0031308f), 10);  // 0.04045 * 255 = 10.31
  EXPECT_EQ(toSrgb8(-0.5f), 0);
  EXPECT_EQ(toSrgb8(7.0f), 255);
  EXPECT_EQ(toSrgb8(kNaN), 0);
  EXPECT_FLOAT_EQ(linearToSrgb(0.002f), 0.02584f);  // linear segment: 12.92 x
  EXPECT_FLOAT_EQ(linearToSrgb(0.5f), 0.7353569f);
  EXPECT_EQ(linearToSrgb(2.0f), 1.0f);
}

TEST(Srgb, EveryCodeRoundTripsThroughTheInverse) {
  // Linear value of each code, and of points just inside its rounding interval.
  for (int c = 0; c < 256; ++c) {
    EXPECT_EQ(toSrgb8(float(srgbToLinear(c / 255.0))), c) << c;
    if (c > 0) {
      EXPECT_EQ(toSrgb8(float(srgbToLinear((c - 0.49) / 255.0))), c) << c;
    }
    if (c < 255) {
      EXPECT_EQ(toSrgb8(float(srgbToLinear((c + 0.49) / 255.0))), c) << c;
    }
  }
}

TEST(ImageBasics, AtIsRowMajorBottomUpAndChecked) {
  Image img(3, 2, {0.1f, 0.2f, 0.3f});
  EXPECT_EQ(img.pixels.size(), 6u);
  img.at(2, 1) = {1.0f, 0.0f, 0.0f};
  EXPECT_EQ(img.pixels[5], (Rgb{1.0f, 0.0f, 0.0f}));
  EXPECT_EQ(img.index(1, 1), 4u);
  EXPECT_THROW(img.at(3, 0), std::out_of_range);
  EXPECT_THROW(img.at(0, 2), std::out_of_range);
}

TEST_F(ImageFiles, PngTopRowFirstWithExactSrgbCodes) {
  Image img(2, 2);
  img.at(0, 0) = {0.5f, 0.5f, 0.5f};     // bottom-left
  img.at(1, 0) = {1.0f, 0.0f, 0.0f};     // bottom-right
  img.at(0, 1) = {0.0f, 0.0f, 1.0f};     // top-left
  img.at(1, 1) = {0.18f, 2.0f, -1.0f};   // top-right, out-of-range values clamp
  const std::string p = path("out.png");
  writePng(img, p);
  const Png png = readPngFile(p);
  ASSERT_EQ(png.width, 2u);
  ASSERT_EQ(png.height, 2u);
  EXPECT_EQ(png.bitDepth, 8);
  EXPECT_EQ(png.colourType, PNG_COLOR_TYPE_RGB);
  EXPECT_TRUE(png.hasSrgb);
  EXPECT_EQ(png.rows[0], (std::vector<uint8_t>{0, 0, 255, 118, 255, 0}));      // top row
  EXPECT_EQ(png.rows[1], (std::vector<uint8_t>{188, 188, 188, 255, 0, 0}));    // bottom row
  EXPECT_EQ(files(), std::vector<std::string>{"out.png"});  // no temporary left behind
}

TEST_F(ImageFiles, PngRefusesNonFiniteAndNamesTheFile) {
  for (float bad : {kNaN, kInf, -kInf}) {
    Image img(2, 2, {0.5f, 0.5f, 0.5f});
    img.at(1, 0).g = bad;
    const std::string p = path("bad.png");
    try {
      writePng(img, p);
      FAIL() << "wrote a non-finite pixel";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("(1, 0)"), std::string::npos) << e.what();
    }
    EXPECT_TRUE(files().empty());
  }
}

TEST_F(ImageFiles, PngOverwritesAndReportsUnwritablePath) {
  const std::string p = path("x.png");
  writePng(Image(1, 1, {1.0f, 1.0f, 1.0f}), p);
  writePng(Image(1, 1, {0.0f, 0.0f, 0.0f}), p);
  EXPECT_EQ(readPngFile(p).rows[0], (std::vector<uint8_t>{0, 0, 0}));
  const std::string missing = path("no/such/dir/y.png");
  try {
    writePng(Image(1, 1), missing);
    FAIL();
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing), std::string::npos) << e.what();
  }
}

TEST_F(ImageFiles, PfmHeaderBytesAndBottomRowFirst) {
  Image img(2, 1);
  img.at(0, 0) = {1.0f, 0.5f, 0.25f};
  img.at(1, 0) = {-2.0f, 0.0f, 3.0f};
  Image tall(1, 2);
  tall.at(0, 0) = {0.125f, 0.125f, 0.125f};  // bottom
  tall.at(0, 1) = {0.75f, 0.75f, 0.75f};     // top
  writePfm(img, path("a.pfm"));
  writePfm(tall, path("b.pfm"));
  const std::string a = slurp(path("a.pfm"));
  ASSERT_EQ(a.size(), 12u + 24u);
  EXPECT_EQ(a.substr(0, 12), "PF\n2 1\n-1.0\n");
  float first;
  std::memcpy(&first, a.data() + 12, 4);
  EXPECT_EQ(first, 1.0f);
  EXPECT_EQ(static_cast<unsigned char>(a[12 + 15]), 0xC0);  // -2.0f = 0xC0000000, little-endian
  const std::string b = slurp(path("b.pfm"));
  EXPECT_EQ(b.substr(0, 12), "PF\n1 2\n-1.0\n");
  float v[6];
  std::memcpy(v, b.data() + 12, sizeof v);
  EXPECT_EQ(v[0], 0.125f);  // bottom row first, as PFM defines
  EXPECT_EQ(v[3], 0.75f);
}

TEST_F(ImageFiles, PfmRoundTripIsBitExact) {
  Image img(5, 3);
  uint32_t seed = 12345;
  for (Rgb& p : img.pixels) {
    auto next = [&seed] {
      seed = seed * 1664525u + 1013904223u;
      return std::bit_cast<float>((seed >> 9) | 0x3F000000u) - 0.75f;  // [-0.25, 0.25) with low bits
    };
    p = {next(), next(), next()};
  }
  img.at(0, 0) = {std::numeric_limits<float>::denorm_min(), -0.0f, std::numeric_limits<float>::max()};
  img.at(4, 2) = {1e-38f, -1e30f, 0.1f};
  writePfm(img, path("r.pfm"));
  const Image back = readPfm(path("r.pfm"));
  ASSERT_EQ(back.width, 5u);
  ASSERT_EQ(back.height, 3u);
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    EXPECT_EQ(bits(back.pixels[i].r), bits(img.pixels[i].r)) << i;
    EXPECT_EQ(bits(back.pixels[i].g), bits(img.pixels[i].g)) << i;
    EXPECT_EQ(bits(back.pixels[i].b), bits(img.pixels[i].b)) << i;
  }
  EXPECT_EQ(files(), std::vector<std::string>{"r.pfm"});
}

TEST_F(ImageFiles, PfmReadsBigEndianAndGrey) {
  // Big-endian (positive scale) greyscale 2x1: 0.5 = 3F000000, 2.0 = 40000000.
  writeBytes(path("g.pfm"), std::string("Pf\n2 1\n1.0\n") + std::string("\x3F\x00\x00\x00\x40\x00\x00\x00", 8));
  const Image g = readPfm(path("g.pfm"));
  ASSERT_EQ(g.width, 2u);
  EXPECT_EQ(g.at(0, 0), (Rgb{0.5f, 0.5f, 0.5f}));
  EXPECT_EQ(g.at(1, 0), (Rgb{2.0f, 2.0f, 2.0f}));
}

TEST_F(ImageFiles, PfmRejectsMalformedAndNonFinite) {
  const std::string ok = std::string("PF\n1 1\n-1.0\n");
  const std::string one(4, '\0');
  const std::string nan("\x00\x00\xC0\x7F", 4);
  const std::pair<const char*, std::string> cases[] = {
      {"truncated.pfm", ok + one + one},
      {"long.pfm", ok + one + one + one + one},
      {"magic.pfm", "P6\n1 1\n-1.0\n" + one + one + one},
      {"dims.pfm", "PF\n1 x\n-1.0\n" + one + one + one},
      {"zero.pfm", "PF\n0 1\n-1.0\n"},
      {"scale.pfm", "PF\n1 1\n0\n" + one + one + one},
      {"nan.pfm", ok + one + nan + one},
      {"empty.pfm", ""},
  };
  for (const auto& [name, bytes] : cases) {
    writeBytes(path(name), bytes);
    try {
      readPfm(path(name));
      ADD_FAILURE() << name << " accepted";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(path(name)), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(readPfm(path("missing.pfm")), std::runtime_error);
  Image bad(1, 1, {0.0f, kInf, 0.0f});
  EXPECT_THROW(writePfm(bad, path("inf.pfm")), std::runtime_error);
  EXPECT_FALSE(fs::exists(path("inf.pfm")));
}

TEST(DifferenceImage, ScaledAbsoluteErrorClampedToOne) {
  Image a(2, 1), ref(2, 1);
  a.at(0, 0) = {0.5f, 0.25f, 1.0f};
  ref.at(0, 0) = {0.375f, 0.3125f, 0.0f};
  a.at(1, 0) = {0.0f, 3.0f, 0.5f};
  ref.at(1, 0) = {0.0f, -3.0f, 0.5f};
  const Image d = differenceImage(a, ref);
  EXPECT_EQ(d.at(0, 0), (Rgb{0.5f, 0.25f, 1.0f}));  // 0.125 x 4, 0.0625 x 4, clamped
  EXPECT_EQ(d.at(1, 0), (Rgb{0.0f, 1.0f, 0.0f}));
  const Image d8 = differenceImage(a, ref, 8.0f);
  EXPECT_EQ(d8.at(0, 0), (Rgb{1.0f, 0.5f, 1.0f}));
  const Image d1 = differenceImage(a, ref, 1.0f);
  EXPECT_EQ(d1.at(0, 0), (Rgb{0.125f, 0.0625f, 1.0f}));
  EXPECT_THROW(differenceImage(a, Image(1, 2)), std::invalid_argument);
  EXPECT_THROW(differenceImage(a, ref, -1.0f), std::invalid_argument);
  EXPECT_THROW(differenceImage(a, ref, kNaN), std::invalid_argument);
  a.at(1, 0).b = kNaN;
  EXPECT_THROW(differenceImage(a, ref), std::invalid_argument);
}
