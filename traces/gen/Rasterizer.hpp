// A software triangle rasterizer following GL's rasterization rules, used to turn
// scene geometry into fragment traces.
//
// Rules (GL 4.6 core, 14.6.1, with the choices GL leaves open made explicit):
// - Window coordinates: origin bottom-left, +y up, x_w = (x_ndc + 1) W / 2,
//   z_w = z_ndc / 2 + 1/2 (glDepthRange(0, 1)). Pixel (x, y) is sampled at its
//   centre (x + 0.5, y + 0.5).
// - Vertices are snapped to 1/256 pixel (kSubpixelBits = 8) and coverage is decided
//   by exact int64 edge functions, so triangles sharing an edge never both cover a
//   pixel centre on it and never both miss it.
// - Top-left fill rule, in GL window coordinates (y up, as the image is shown):
//   a centre exactly on an edge is covered only if that edge is a "left" edge
//   (the triangle's interior lies on its +x side) or a "top" edge (horizontal, the
//   interior lies below it, towards -y). Right and bottom edges exclude.
// - Either winding is rasterized unless culling is asked for; front faces are
//   counter-clockwise in window coordinates (glFrontFace(GL_CCW)).
// - Clipping happens in homogeneous clip space against the near (z >= -w) and far
//   (z <= w) planes, against w > 0, and against a guard band |x|,|y| <= 4w that
//   keeps the fixed-point arithmetic far from overflow; the viewport then scissors.
// - Window depth is interpolated linearly in window space (that is the perspective-
//   correct depth) and clamped to [0, 1]; every other attribute is interpolated
//   perspective-correctly with 1/w.
// - Fragments leave in a fixed order: triangles in call order, and within one
//   triangle rows bottom to top, pixels left to right.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <type_traits>

#include "traces/gen/Math.hpp"

namespace oit::gen {

inline constexpr int kMaxAttributes = 8;

struct ClipVertex {
  Vec4 pos;  // clip-space position
  std::array<float, kMaxAttributes> attr{};
};

struct RasterFragment {
  uint16_t x = 0, y = 0;  // pixel, GL window coordinates
  float z = 0;            // window depth in [0, 1]
  std::array<float, kMaxAttributes> attr{};
};

enum class CullMode { None, Back, Front };

struct RasterStats {
  uint64_t triangles = 0;  // submitted
  uint64_t culled = 0;     // dropped by the cull mode
  uint64_t clipped = 0;    // needed a clipping plane
  uint64_t rejected = 0;   // entirely outside the clip volume
  uint64_t fragments = 0;  // covered pixel centres handed out
};

class Rasterizer {
 public:
  static constexpr int kSubpixelBits = 8;
  static constexpr int64_t kSubpixelOne = int64_t{1} << kSubpixelBits;
  static constexpr double kGuardBand = 4.0;  // clip |x|,|y| <= kGuardBand * w
  static constexpr uint32_t kMaxViewport = 65536;

  // Throws std::invalid_argument for a viewport outside 1..65536 or too many attributes.
  Rasterizer(uint32_t width, uint32_t height, int attribute_count = 0);

  uint32_t width() const { return width_; }
  uint32_t height() const { return height_; }

  // How many of ClipVertex::attr are interpolated (the rest of the fragment's
  // attributes are zero); fewer is faster.
  void setAttributeCount(int n);
  int attributeCount() const { return nattr_; }
  void setCullMode(CullMode m) { cull_ = m; }
  CullMode cullMode() const { return cull_; }

  const RasterStats& stats() const { return stats_; }
  void resetStats() { stats_ = {}; }

  // Calls emit(const RasterFragment&) for every covered pixel centre.
  template <class F>
  void drawTriangle(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c, F&& emit) {
    using Fn = std::remove_reference_t<F>;
    void* ctx = const_cast<void*>(static_cast<const void*>(std::addressof(emit)));
    drawTriangleImpl(a, b, c, [](void* p, const RasterFragment& f) { (*static_cast<Fn*>(p))(f); },
                     ctx);
  }

  // Window-space position of a clip-space point, as the rasterizer snaps it
  // (units of 1/256 pixel); for tests and tools.
  struct Snapped {
    int64_t x, y;
  };
  Snapped snap(const Vec4& clip) const;

 private:
  using EmitFn = void (*)(void*, const RasterFragment&);
  struct WinVertex;
  struct HVertex;

  void drawTriangleImpl(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c, EmitFn fn,
                        void* ctx);
  void rasterize(const HVertex& a, const HVertex& b, const HVertex& c, EmitFn fn, void* ctx);
  WinVertex toWindow(const HVertex& v) const;

  uint32_t width_, height_;
  int nattr_ = 0;
  CullMode cull_ = CullMode::None;
  RasterStats stats_;
};

}  // namespace oit::gen
