#include "traces/gen/Rasterizer.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace oit::gen {

// A vertex during clipping: position in double so that the intersection points a
// plane makes on an edge are computed identically by both triangles sharing it.
struct Rasterizer::HVertex {
  double x, y, z, w;
  std::array<float, kMaxAttributes> attr;
};

struct Rasterizer::WinVertex {
  int64_t X, Y;  // snapped window position, 1/256 pixel units
  double z;      // window depth
  double invw;   // 1 / clip w, for perspective-correct attributes
  const std::array<float, kMaxAttributes>* attr;
};

namespace {

constexpr int kPlanes = 7;
constexpr double kMinW = 1e-6;  // clip w must stay positive for the divide

// Signed distance to clip plane p, >= 0 inside. Fixed order: near, far, the four
// guard-band planes, then w > 0 (which the guard band alone would not ensure for w = 0).
template <class V>
double planeDistance(int p, const V& v) {
  constexpr double g = Rasterizer::kGuardBand;
  switch (p) {
    case 0: return v.z + v.w;
    case 1: return v.w - v.z;
    case 2: return v.x + g * v.w;
    case 3: return g * v.w - v.x;
    case 4: return v.y + g * v.w;
    case 5: return g * v.w - v.y;
    default: return v.w - kMinW;
  }
}

// floor(a / b) and ceil(a / b) for b > 0.
int64_t floorDiv(int64_t a, int64_t b) {
  int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}
int64_t ceilDiv(int64_t a, int64_t b) { return -floorDiv(-a, b); }

}  // namespace

Rasterizer::Rasterizer(uint32_t width, uint32_t height, int attribute_count)
    : width_(width), height_(height) {
  if (width < 1 || height < 1 || width > kMaxViewport || height > kMaxViewport)
    throw std::invalid_argument("rasterizer viewport " + std::to_string(width) + "x" +
                                std::to_string(height) + " is outside 1..65536 per axis");
  setAttributeCount(attribute_count);
}

void Rasterizer::setAttributeCount(int n) {
  if (n < 0 || n > kMaxAttributes)
    throw std::invalid_argument("rasterizer attribute count " + std::to_string(n) +
                                " is outside 0.." + std::to_string(kMaxAttributes));
  nattr_ = n;
}

Rasterizer::Snapped Rasterizer::snap(const Vec4& clip) const {
  HVertex h{clip.x, clip.y, clip.z, clip.w, {}};
  WinVertex w = toWindow(h);
  return {w.X, w.Y};
}

Rasterizer::WinVertex Rasterizer::toWindow(const HVertex& v) const {
  const double inv = 1.0 / v.w;
  const double xw = (v.x * inv + 1.0) * (0.5 * width_);
  const double yw = (v.y * inv + 1.0) * (0.5 * height_);
  // Round to nearest 1/256 pixel; the guard band bounds |xw| by 2.5 * 65536.
  return {static_cast<int64_t>(std::floor(xw * kSubpixelOne + 0.5)),
          static_cast<int64_t>(std::floor(yw * kSubpixelOne + 0.5)), v.z * inv * 0.5 + 0.5, inv,
          &v.attr};
}

void Rasterizer::drawTriangleImpl(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c,
                                  EmitFn fn, void* ctx) {
  ++stats_.triangles;
  const ClipVertex* in[3] = {&a, &b, &c};
  HVertex poly[2][3 + kPlanes + 2];
  int n = 3;
  for (int i = 0; i < 3; ++i) poly[0][i] = {in[i]->pos.x, in[i]->pos.y, in[i]->pos.z, in[i]->pos.w,
                                            in[i]->attr};

  // Outcodes: reject when all three vertices are outside one plane, skip clipping
  // when all are inside every plane (the common case).
  unsigned outside_any = 0, outside_all = (1u << kPlanes) - 1;
  for (int i = 0; i < 3; ++i) {
    unsigned code = 0;
    for (int p = 0; p < kPlanes; ++p)
      if (!(planeDistance(p, poly[0][i]) >= 0)) code |= 1u << p;  // NaN counts as outside
    outside_any |= code;
    outside_all &= code;
  }
  if (outside_all) {
    ++stats_.rejected;
    return;
  }

  int cur = 0;
  if (outside_any) {
    ++stats_.clipped;
    // Sutherland-Hodgman, one plane at a time. An edge's intersection is always
    // computed from its inside end towards its outside end, so the two triangles
    // sharing that edge produce the very same new vertex.
    for (int p = 0; p < kPlanes; ++p) {
      if (!(outside_any & (1u << p))) continue;
      const HVertex* src = poly[cur];
      HVertex* dst = poly[cur ^ 1];
      int m = 0;
      for (int i = 0; i < n; ++i) {
        const HVertex& v0 = src[i];
        const HVertex& v1 = src[(i + 1) % n];
        const double d0 = planeDistance(p, v0), d1 = planeDistance(p, v1);
        const bool in0 = d0 >= 0, in1 = d1 >= 0;
        if (in0) dst[m++] = v0;
        if (in0 != in1) {
          const HVertex& I = in0 ? v0 : v1;
          const HVertex& O = in0 ? v1 : v0;
          const double dI = in0 ? d0 : d1, dO = in0 ? d1 : d0;
          const double t = dI / (dI - dO);
          HVertex& r = dst[m++];
          r.x = I.x + t * (O.x - I.x);
          r.y = I.y + t * (O.y - I.y);
          r.z = I.z + t * (O.z - I.z);
          r.w = I.w + t * (O.w - I.w);
          for (int k = 0; k < nattr_; ++k)
            r.attr[k] = static_cast<float>(I.attr[k] + t * (double(O.attr[k]) - I.attr[k]));
          for (int k = nattr_; k < kMaxAttributes; ++k) r.attr[k] = 0;
        }
      }
      n = m;
      cur ^= 1;
      if (n < 3) {
        ++stats_.rejected;
        return;
      }
    }
  }

  // Fan over the (convex) clipped polygon; its inner edges are shared exactly.
  const uint64_t culled_before = stats_.culled;
  for (int i = 1; i + 1 < n; ++i) rasterize(poly[cur][0], poly[cur][i], poly[cur][i + 1], fn, ctx);
  // All fan pieces have the same orientation: count a culled triangle once.
  if (stats_.culled > culled_before) stats_.culled = culled_before + 1;
}

void Rasterizer::rasterize(const HVertex& a, const HVertex& b, const HVertex& c, EmitFn fn,
                           void* ctx) {
  WinVertex v[3] = {toWindow(a), toWindow(b), toWindow(c)};
  int64_t area2 = (v[1].X - v[0].X) * (v[2].Y - v[0].Y) - (v[2].X - v[0].X) * (v[1].Y - v[0].Y);
  if (area2 == 0) return;  // degenerate after snapping: covers nothing
  const bool front = area2 > 0;  // counter-clockwise in GL window coordinates
  if ((cull_ == CullMode::Back && !front) || (cull_ == CullMode::Front && front)) {
    ++stats_.culled;
    return;
  }
  if (area2 < 0) {  // make it counter-clockwise so the interior is where E > 0
    std::swap(v[1], v[2]);
    area2 = -area2;
  }

  // Edge k runs from v[k+1] to v[k+2] (opposite vertex k): E_k(P) = A Px + B Py + C,
  // positive inside, and E_k / area2 is vertex k's barycentric weight.
  int64_t A[3], B[3], C[3], bias[3];
  for (int k = 0; k < 3; ++k) {
    const WinVertex& p = v[(k + 1) % 3];
    const WinVertex& q = v[(k + 2) % 3];
    const int64_t dx = q.X - p.X, dy = q.Y - p.Y;
    A[k] = -dy;
    B[k] = dx;
    C[k] = dy * p.X - dx * p.Y;
    // Counter-clockwise with y up: a left edge runs downwards, a top edge runs
    // towards -x. Centres on them are in (E >= 0); on other edges out (E >= 1).
    const bool top_left = dy < 0 || (dy == 0 && dx < 0);
    bias[k] = top_left ? 0 : 1;
  }

  const int64_t minX = std::min({v[0].X, v[1].X, v[2].X}), maxX = std::max({v[0].X, v[1].X, v[2].X});
  const int64_t minY = std::min({v[0].Y, v[1].Y, v[2].Y}), maxY = std::max({v[0].Y, v[1].Y, v[2].Y});
  const int64_t half = kSubpixelOne / 2;
  // Pixels whose centre x * 256 + 128 lies in the bounding box, scissored to the viewport.
  const int64_t x0 = std::max<int64_t>(0, ceilDiv(minX - half, kSubpixelOne));
  const int64_t x1 = std::min<int64_t>(width_ - 1, floorDiv(maxX - half, kSubpixelOne));
  const int64_t y0 = std::max<int64_t>(0, ceilDiv(minY - half, kSubpixelOne));
  const int64_t y1 = std::min<int64_t>(height_ - 1, floorDiv(maxY - half, kSubpixelOne));
  if (x0 > x1 || y0 > y1) return;

  const double inv_area = 1.0 / static_cast<double>(area2);
  const int nattr = nattr_;
  int64_t step[3];
  for (int k = 0; k < 3; ++k) step[k] = A[k] * kSubpixelOne;

  RasterFragment f;
  for (int64_t y = y0; y <= y1; ++y) {
    const int64_t py = y * kSubpixelOne + half, px = x0 * kSubpixelOne + half;
    int64_t e0[3];
    // The covered pixels of a row form one interval: intersect each edge's
    // half-line exactly in integers instead of testing every pixel of the box.
    int64_t lo = 0, hi = x1 - x0;
    for (int k = 0; k < 3 && lo <= hi; ++k) {
      e0[k] = A[k] * px + B[k] * py + C[k];
      if (step[k] > 0)
        lo = std::max(lo, ceilDiv(bias[k] - e0[k], step[k]));
      else if (step[k] < 0)
        hi = std::min(hi, floorDiv(e0[k] - bias[k], -step[k]));
      else if (e0[k] < bias[k])
        hi = -1;
    }
    if (lo > hi) continue;
    f.y = static_cast<uint16_t>(y);
    for (int64_t i = lo; i <= hi; ++i) {
      const double b0 = static_cast<double>(e0[0] + i * step[0]) * inv_area;
      const double b1 = static_cast<double>(e0[1] + i * step[1]) * inv_area;
      const double b2 = static_cast<double>(e0[2] + i * step[2]) * inv_area;
      const double z = b0 * v[0].z + b1 * v[1].z + b2 * v[2].z;
      f.x = static_cast<uint16_t>(x0 + i);
      f.z = static_cast<float>(std::clamp(z, 0.0, 1.0));
      if (nattr > 0) {
        const double q0 = b0 * v[0].invw, q1 = b1 * v[1].invw, q2 = b2 * v[2].invw;
        const double s = 1.0 / (q0 + q1 + q2);
        const auto &a0 = *v[0].attr, &a1 = *v[1].attr, &a2 = *v[2].attr;
        for (int k = 0; k < nattr; ++k)
          f.attr[k] = static_cast<float>((q0 * a0[k] + q1 * a1[k] + q2 * a2[k]) * s);
      }
      ++stats_.fragments;
      fn(ctx, f);
    }
  }
}

}  // namespace oit::gen
