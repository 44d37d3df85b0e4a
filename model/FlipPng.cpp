// flip.png: the FLIP map in the magma colour map with its colour scale beneath.
#include <algorithm>
#include <array>
#include <cmath>
#include <string_view>

#include "model/Flip.hpp"

namespace oit::model {

namespace {

// magma at t = 0, 16/255, 32/255, ..., 240/255, 1, as 8-bit sRGB: sampled from
// Debian's python3-matplotlib 3.6 (matplotlib.colormaps["magma"]), the map the
// FLIP paper shows its errors in; linear interpolation between the samples.
constexpr std::array<std::array<uint8_t, 3>, 17> kMagma = {{
    {0, 0, 4},       {10, 8, 34},     {29, 17, 71},    {54, 16, 107},   {81, 18, 124},   {106, 28, 129},
    {131, 38, 129},  {156, 46, 127},  {183, 55, 121},  {208, 65, 111},  {231, 82, 99},   {245, 107, 92},
    {252, 137, 97},  {254, 167, 114}, {254, 196, 136}, {253, 226, 163}, {252, 253, 191},
}};

// 5 x 7 glyphs of the scale's labels ('#' is ink).
struct Glyph {
  char c;
  std::array<std::string_view, 7> rows;
};
constexpr Glyph kGlyphs[] = {
    {'0', {".###.", "#...#", "#..##", "#.#.#", "##..#", "#...#", ".###."}},
    {'1', {"..#..", ".##..", "..#..", "..#..", "..#..", "..#..", ".###."}},
    {'5', {"#####", "#....", "####.", "....#", "....#", "#...#", ".###."}},
    {'.', {"..", "..", "..", "..", "..", "##", "##"}},
};

const Glyph* glyph(char c) {
  for (const Glyph& g : kGlyphs)
    if (g.c == c) return &g;
  return nullptr;
}

int textWidth(std::string_view s) {
  int w = 0;
  for (char c : s) w += int(glyph(c)->rows[0].size()) + 1;
  return w > 0 ? w - 1 : 0;
}

void put(Srgb8Image& img, int x, int y, const uint8_t c[3]) {
  if (x < 0 || y < 0 || x >= int(img.width) || y >= int(img.height)) return;
  std::copy(c, c + 3, img.rgb.begin() + (size_t(y) * img.width + size_t(x)) * 3);
}

void drawText(Srgb8Image& img, int x, int y, std::string_view s, const uint8_t ink[3]) {
  for (char c : s) {
    const Glyph* g = glyph(c);
    for (int r = 0; r < 7; ++r)
      for (int col = 0; col < int(g->rows[size_t(r)].size()); ++col)
        if (g->rows[size_t(r)][size_t(col)] == '#') put(img, x + col, y + r, ink);
    x += int(g->rows[0].size()) + 1;
  }
}

}  // namespace

void magmaSrgb8(double t, uint8_t out[3]) {
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0);
  // Sample i sits at t = min(16 i, 255) / 255.
  const double code = t * 255.0;
  size_t i = std::min<size_t>(size_t(code / 16.0), kMagma.size() - 2);
  const double t0 = double(16 * i), t1 = std::min(16.0 * double(i + 1), 255.0);
  const double f = std::clamp((code - t0) / (t1 - t0), 0.0, 1.0);
  for (int c = 0; c < 3; ++c)
    out[c] = uint8_t(std::lround(kMagma[i][size_t(c)] + f * (kMagma[i + 1][size_t(c)] - kMagma[i][size_t(c)])));
}

void writeFlipPng(const FlipMap& map, const std::string& path) {
  Srgb8Image img;
  img.width = map.width;
  img.height = map.height + kFlipScaleRows;
  img.rgb.assign(size_t(img.width) * img.height * 3, 255);  // white strip
  for (size_t i = 0; i < map.error.size(); ++i) magmaSrgb8(map.error[i], &img.rgb[3 * i]);
  // Rows below the map: 2 blank, 8 of gradient, 2 of ticks, 1 blank, 7 of labels.
  const int w = int(map.width), top = int(map.height);
  for (int x = 0; x < w; ++x) {
    uint8_t c[3];
    magmaSrgb8(w > 1 ? double(x) / double(w - 1) : 0.0, c);
    for (int r = 2; r < 10; ++r) put(img, x, top + r, c);
  }
  const uint8_t ink[3] = {40, 40, 40};
  for (double t : {0.0, 0.25, 0.5, 0.75, 1.0}) {
    const int x = int(std::lround(t * (w - 1)));
    for (int r = 10; r < 12; ++r) put(img, x, top + r, ink);
  }
  if (w >= textWidth("0") + textWidth("0.5") + textWidth("1") + 4) {
    drawText(img, 0, top + 13, "0", ink);
    drawText(img, (w - textWidth("0.5")) / 2, top + 13, "0.5", ink);
    drawText(img, w - textWidth("1"), top + 13, "1", ink);
  }
  writePng(img, path);
}

}  // namespace oit::model
