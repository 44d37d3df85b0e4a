#include "model/Image.hpp"

#include "traces/TempFiles.hpp"

#include <png.h>
#include <unistd.h>

#include <atomic>
#include <bit>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

namespace oit::model {

Image::Image(uint32_t w, uint32_t h, Rgb fill)
    : width(w), height(h), pixels(std::size_t(w) * h, fill) {}

Rgb& Image::at(uint32_t x, uint32_t y) {
  if (x >= width || y >= height)
    throw std::out_of_range(fmt::format("Image::at({}, {}) outside {}x{}", x, y, width, height));
  return pixels[index(x, y)];
}
const Rgb& Image::at(uint32_t x, uint32_t y) const {
  return const_cast<Image&>(*this).at(x, y);
}

namespace {

double srgbEncode(double l) {
  if (!(l > 0.0)) return 0.0;  // also NaN
  if (l >= 1.0) return 1.0;
  return l <= 0.0031308 ? 12.92 * l : 1.055 * std::pow(l, 1.0 / 2.4) - 0.055;
}

void checkShape(const Image& img, const std::string& what) {
  if (img.pixels.size() != std::size_t(img.width) * img.height)
    throw std::runtime_error(fmt::format("{}: image is {}x{} but holds {} pixels", what,
                                         img.width, img.height, img.pixels.size()));
}

// Non-finite pixels are a bug upstream; refuse to write them (and name the file).
void checkFinite(const Image& img, const std::string& path) {
  try {
    requireFinite(img, path.c_str());
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(fmt::format("{} (not written)", e.what()));
  }
}

// A unique temporary next to the destination, so the final rename is atomic
// (same filesystem) and readers never see a half-written file; removed unless
// committed (also if the process is interrupted).
void commitTemp(TempFile& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp.path(), path, ec);
  if (ec) throw std::runtime_error(fmt::format("{}: cannot rename temporary file: {}", path, ec.message()));
  tmp.keep();
}

struct FileCloser {
  void operator()(FILE* f) const {
    if (f) std::fclose(f);
  }
};

// libpng reports errors by longjmp: keep this frame free of objects with
// destructors and of locals modified after setjmp.
bool encodePng(FILE* file, uint32_t width, uint32_t height, const uint8_t* rgbTopFirst) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_init_io(png, file);
  png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
  png_write_info(png, info);
  for (uint32_t row = 0; row < height; ++row)
    png_write_row(png, rgbTopFirst + std::size_t(row) * width * 3);
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

// Reads any 8-bit or 16-bit PNG as RGB codes (libpng's transforms: palette
// and grey expanded, 16-bit cut to 8, alpha dropped). Same longjmp rule as
// encodePng: the message is copied out through `why`.
bool decodePng(FILE* file, Srgb8Image& img, std::string& why) {
  unsigned char sig[8];
  if (std::fread(sig, 1, 8, file) != 8 || png_sig_cmp(sig, 0, 8) != 0) {
    why = "no PNG signature";
    return false;
  }
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    return false;
  }
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    why = "corrupt or truncated data";
    return false;
  }
  png_init_io(png, file);
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  png_set_expand(png);
  png_set_strip_16(png);
  png_set_strip_alpha(png);
  png_set_gray_to_rgb(png);
  png_read_update_info(png, info);
  img.width = png_get_image_width(png, info);
  img.height = png_get_image_height(png, info);
  if (png_get_rowbytes(png, info) != std::size_t(img.width) * 3) {
    png_destroy_read_struct(&png, &info, nullptr);
    why = "unsupported pixel layout";
    return false;
  }
  img.rgb.resize(std::size_t(img.width) * img.height * 3);
  for (uint32_t row = 0; row < img.height; ++row) png_read_row(png, img.rgb.data() + std::size_t(row) * img.width * 3, nullptr);
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return true;
}

}  // namespace

float linearToSrgb(float linear) { return float(srgbEncode(linear)); }

uint8_t toSrgb8(float linear) {
  return static_cast<uint8_t>(std::floor(srgbEncode(linear) * 255.0 + 0.5));
}

void requireFinite(const Image& img, const char* what) {
  for (uint32_t y = 0; y < img.height; ++y)
    for (uint32_t x = 0; x < img.width; ++x) {
      const Rgb& p = img.pixels[img.index(x, y)];
      if (!std::isfinite(p.r) || !std::isfinite(p.g) || !std::isfinite(p.b))
        throw std::invalid_argument(fmt::format("{}: pixel ({}, {}) is not finite ({}, {}, {})",
                                                what, x, y, p.r, p.g, p.b));
    }
}

void writePng(const Image& img, const std::string& path) {
  checkShape(img, path);
  checkFinite(img, path);
  if (img.width == 0 || img.height == 0)
    throw std::runtime_error(fmt::format("{}: cannot write an empty {}x{} PNG", path, img.width,
                                         img.height));
  // Encode everything before touching the file system.
  Srgb8Image codes;
  codes.width = img.width;
  codes.height = img.height;
  codes.rgb.resize(img.pixels.size() * 3);
  for (uint32_t y = 0; y < img.height; ++y) {
    uint8_t* out = codes.rgb.data() + std::size_t(img.height - 1 - y) * img.width * 3;  // top row first
    for (uint32_t x = 0; x < img.width; ++x) {
      const Rgb& p = img.pixels[img.index(x, y)];
      out[3 * x + 0] = toSrgb8(p.r);
      out[3 * x + 1] = toSrgb8(p.g);
      out[3 * x + 2] = toSrgb8(p.b);
    }
  }
  writePng(codes, path);
}

void writePng(const Srgb8Image& img, const std::string& path) {
  if (img.width == 0 || img.height == 0)
    throw std::runtime_error(fmt::format("{}: cannot write an empty {}x{} PNG", path, img.width,
                                         img.height));
  if (img.rgb.size() != std::size_t(img.width) * img.height * 3)
    throw std::runtime_error(fmt::format("{}: image is {}x{} but holds {} bytes", path, img.width, img.height,
                                         img.rgb.size()));
  TempFile tmp(tempPathNextTo(path));
  std::unique_ptr<FILE, FileCloser> file(std::fopen(tmp.path().c_str(), "wb"));
  if (!file)
    throw std::runtime_error(fmt::format("{}: cannot create {}: {}", path, tmp.path(), std::strerror(errno)));

  errno = 0;
  const bool ok = encodePng(file.get(), img.width, img.height, img.rgb.data());
  const int write_err = errno;
  const bool closed = std::fclose(file.release()) == 0;
  const int err = closed ? write_err : errno;
  if (!ok || !closed)
    throw std::runtime_error(
        fmt::format("{}: PNG write failed{}", path, err ? std::string(": ") + std::strerror(err) : std::string()));
  commitTemp(tmp, path);
}

Srgb8Image readPng(const std::string& path) {
  std::unique_ptr<FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw std::runtime_error(fmt::format("{}: cannot open: {}", path, std::strerror(errno)));
  Srgb8Image img;
  std::string why;
  if (!decodePng(file.get(), img, why)) throw std::runtime_error(fmt::format("{}: not a readable PNG: {}", path, why));
  return img;
}

void writePfm(const Image& img, const std::string& path) {
  checkShape(img, path);
  checkFinite(img, path);
  if (img.width == 0 || img.height == 0)  // readPfm rejects zero dimensions too
    throw std::runtime_error(fmt::format("{}: cannot write an empty {}x{} PFM", path, img.width,
                                         img.height));
  const std::string header = fmt::format("PF\n{} {}\n-1.0\n", img.width, img.height);
  TempFile tmp(tempPathNextTo(path));
  {
    std::ofstream out(tmp.path(), std::ios::binary | std::ios::trunc);
    if (!out)
      throw std::runtime_error(fmt::format("{}: cannot create {}: {}", path, tmp.path(), std::strerror(errno)));
    errno = 0;
    out.write(header.data(), std::streamsize(header.size()));
    // Rgb is three packed floats and the host is little-endian (see
    // traces/Fragment.hpp), so the pixel array is the PFM payload as is.
    static_assert(sizeof(Rgb) == 3 * sizeof(float));
    static_assert(std::endian::native == std::endian::little);
    out.write(reinterpret_cast<const char*>(img.pixels.data()),
              std::streamsize(img.pixels.size() * sizeof(Rgb)));
    out.close();
    if (!out) {
      const int err = errno;  // the failing write's or close's (ENOSPC, EIO ...)
      throw std::runtime_error(
          fmt::format("{}: PFM write failed{}", path, err ? std::string(": ") + std::strerror(err) : std::string()));
    }
  }
  commitTemp(tmp, path);
}

Image readPfm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open", path));
  const std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto fail = [&path](const std::string& why) {
    return std::runtime_error(fmt::format("{}: not a valid PFM: {}", path, why));
  };

  // Header: three whitespace-separated tokens after the magic, then exactly
  // one whitespace byte before the binary payload.
  std::size_t pos = 0;
  auto isSpace = [](char c) { return c == ' ' || c == '\n' || c == '\r' || c == '\t'; };
  auto token = [&]() {
    while (pos < data.size() && isSpace(data[pos])) ++pos;
    const std::size_t start = pos;
    while (pos < data.size() && !isSpace(data[pos])) ++pos;
    if (start == pos || pos >= data.size()) throw fail("truncated header");
    return data.substr(start, pos - start);
  };
  const std::string magic = token();
  if (magic != "PF" && magic != "Pf") throw fail("magic is not PF or Pf");
  const unsigned channels = magic == "PF" ? 3 : 1;
  auto parseDim = [&](const std::string& s) {
    if (s.empty() || s.size() > 9 || s.find_first_not_of("0123456789") != std::string::npos)
      throw fail(fmt::format("bad dimension '{}'", s));
    const unsigned long v = std::stoul(s);
    if (v == 0) throw fail("zero dimension");
    return uint32_t(v);
  };
  const uint32_t w = parseDim(token());
  const uint32_t h = parseDim(token());
  const std::string scaleText = token();
  double scale = 0.0;
  try {
    std::size_t used = 0;
    scale = std::stod(scaleText, &used);
    if (used != scaleText.size()) throw std::invalid_argument("trailing");
  } catch (const std::exception&) {
    throw fail(fmt::format("bad scale '{}'", scaleText));
  }
  if (scale == 0.0 || !std::isfinite(scale)) throw fail("scale must be finite and non-zero");
  const bool bigEndian = scale > 0.0;
  ++pos;  // the single whitespace byte ending the header

  const std::size_t values = std::size_t(w) * h * channels;
  if (data.size() - pos != values * 4)
    throw fail(fmt::format("payload is {} bytes, {}x{}x{} floats need {}", data.size() - pos, w, h,
                           channels, values * 4));
  Image img(w, h);
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data() + pos);
  auto value = [&](std::size_t i) {
    const unsigned char* b = bytes + 4 * i;
    const uint32_t u = bigEndian ? (uint32_t(b[0]) << 24 | uint32_t(b[1]) << 16 | uint32_t(b[2]) << 8 | b[3])
                                 : (uint32_t(b[3]) << 24 | uint32_t(b[2]) << 16 | uint32_t(b[1]) << 8 | b[0]);
    return std::bit_cast<float>(u);
  };
  for (std::size_t i = 0; i < img.pixels.size(); ++i) {
    if (channels == 3) {
      img.pixels[i] = {value(3 * i), value(3 * i + 1), value(3 * i + 2)};
    } else {
      const float v = value(i);
      img.pixels[i] = {v, v, v};
    }
  }
  try {
    requireFinite(img, path.c_str());
  } catch (const std::invalid_argument& e) {
    throw std::runtime_error(e.what());
  }
  return img;
}

Image differenceImage(const Image& a, const Image& ref, float gain) {
  if (!a.sameSize(ref))
    throw std::invalid_argument(fmt::format("differenceImage: size mismatch {}x{} vs reference {}x{}",
                                            a.width, a.height, ref.width, ref.height));
  if (!(gain >= 0.0f) || !std::isfinite(gain))
    throw std::invalid_argument(fmt::format("differenceImage: gain {} must be finite and >= 0", gain));
  requireFinite(a, "differenceImage image");
  requireFinite(ref, "differenceImage reference");
  Image d(a.width, a.height);
  // Computed in double: |a - ref| of two floats can overflow float, and the
  // result must not depend on rounding order.
  auto diff = [gain](float x, float y) {
    const double v = std::fabs(double(x) - double(y)) * gain;
    return float(v < 1.0 ? v : 1.0);
  };
  for (std::size_t i = 0; i < d.pixels.size(); ++i) {
    const Rgb& p = a.pixels[i];
    const Rgb& q = ref.pixels[i];
    d.pixels[i] = {diff(p.r, q.r), diff(p.g, q.g), diff(p.b, q.b)};
  }
  return d;
}

}  // namespace oit::model
