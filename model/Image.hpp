// Linear-RGB float images and their file formats (sRGB PNG, linear PFM).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace oit::model {

struct Rgb {
  float r, g, b;  // linear RGB
  friend bool operator==(const Rgb&, const Rgb&) = default;
};

struct Image {
  uint32_t width = 0, height = 0;
  std::vector<Rgb> pixels;  // row-major, row 0 = bottom row (GL window y = 0)

  Image() = default;
  Image(uint32_t w, uint32_t h, Rgb fill = {0.0f, 0.0f, 0.0f});

  // Bounds-checked (throws std::out_of_range), like std::vector::at.
  Rgb& at(uint32_t x, uint32_t y);
  const Rgb& at(uint32_t x, uint32_t y) const;
  std::size_t index(uint32_t x, uint32_t y) const { return std::size_t(y) * width + x; }
  bool sameSize(const Image& o) const { return width == o.width && height == o.height; }
};

// Exact sRGB transfer function (IEC 61966-2-1) of a value clamped to [0,1].
// NaN -> 0.
float linearToSrgb(float linear);
// round(linearToSrgb(v) * 255) evaluated in double (e.g. 0.5 -> 188).
uint8_t toSrgb8(float linear);

// 8-bit sRGB RGB triples, top row first (as a PNG stores them).
struct Srgb8Image {
  uint32_t width = 0, height = 0;
  std::vector<uint8_t> rgb;  // 3 x width x height
};

// 8-bit sRGB PNG (with an sRGB chunk), top row first. Written to a temporary
// file in the same directory, then renamed. Throws std::runtime_error naming
// the file on I/O errors or any NaN/Inf pixel (nothing is written then).
void writePng(const Image& img, const std::string& path);
// The same PNG from 8-bit codes as they are (e.g. a colour-mapped error map).
void writePng(const Srgb8Image& img, const std::string& path);
// Reads an 8-bit PNG (grey, grey + alpha, RGB or RGBA; 16-bit channels are cut
// to their high byte, alpha dropped) as RGB codes. Throws std::runtime_error
// naming the file on anything else.
Srgb8Image readPng(const std::string& path);
// Linear float RGB PFM: "PF\n<w> <h>\n-1.0\n", little-endian, bottom row
// first (PFM's own order, identical to Image's). Same temp+rename and
// non-finite rules as writePng.
void writePfm(const Image& img, const std::string& path);
// Reads "PF" (RGB) and "Pf" (grey, expanded to RGB) in either byte order.
// Throws std::runtime_error naming the file on malformed input or non-finite data.
Image readPfm(const std::string& path);

// min(1, |a - ref| * gain) per channel: the MLAB paper's x4 enhanced
// difference image. Throws std::invalid_argument on size mismatch, non-finite
// pixels or a negative/non-finite gain.
Image differenceImage(const Image& a, const Image& ref, float gain = 4.0f);

// Throws std::invalid_argument("<what>: pixel (x, y) is not finite") on the
// first NaN/Inf channel.
void requireFinite(const Image& img, const char* what);

}  // namespace oit::model
