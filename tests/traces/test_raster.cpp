// The software rasterizer against hand-counted coverage, GL's fill rules,
// watertightness on shared edges, clipping and interpolation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

#include "traces/gen/Math.hpp"
#include "traces/gen/Random.hpp"
#include "traces/gen/Rasterizer.hpp"

namespace oit::gen {
namespace {

using Pixel = std::pair<int, int>;  // (x, y)

// A clip-space vertex at window position (x, y) of a w x h viewport, clip w = 1.
ClipVertex win(double x, double y, uint32_t w, uint32_t h, float z_ndc = 0) {
  ClipVertex v;
  v.pos = {static_cast<float>(2.0 * x / w - 1.0), static_cast<float>(2.0 * y / h - 1.0), z_ndc, 1.0f};
  return v;
}

std::vector<RasterFragment> draw(Rasterizer& r, const ClipVertex& a, const ClipVertex& b,
                                 const ClipVertex& c) {
  std::vector<RasterFragment> out;
  r.drawTriangle(a, b, c, [&](const RasterFragment& f) { out.push_back(f); });
  return out;
}

std::set<Pixel> pixels(const std::vector<RasterFragment>& fs) {
  std::set<Pixel> s;
  for (const RasterFragment& f : fs) s.insert({f.x, f.y});
  return s;
}

// Per-pixel coverage counts of a viewport.
struct Coverage {
  uint32_t w, h;
  std::vector<int> count;
  Coverage(uint32_t w_, uint32_t h_) : w(w_), h(h_), count(size_t{w_} * h_) {}
  void add(const RasterFragment& f) { ++count[size_t{f.y} * w + f.x]; }
  int at(int x, int y) const { return count[size_t(y) * w + x]; }
};

TEST(RasterCoverage, RightTriangleOnPixelCornersCoversHandCountedCentres) {
  // Legs of 8 pixels on pixel corners: centres (x+.5, y+.5) with x + y <= 6 are
  // inside; those with x + y = 7 lie on the hypotenuse, a right edge, so are out.
  Rasterizer r(16, 16);
  std::set<Pixel> expected;
  for (int y = 0; y < 8; ++y)
    for (int x = 0; x + y <= 6; ++x) expected.insert({x, y});
  ASSERT_EQ(expected.size(), 28u);

  auto ccw = draw(r, win(0, 0, 16, 16), win(8, 0, 16, 16), win(0, 8, 16, 16));
  auto cw = draw(r, win(0, 0, 16, 16), win(0, 8, 16, 16), win(8, 0, 16, 16));
  EXPECT_EQ(ccw.size(), 28u);
  EXPECT_EQ(pixels(ccw), expected);
  EXPECT_EQ(pixels(cw), expected) << "either winding covers the same centres";
}

TEST(RasterCoverage, SquareSplitOnItsDiagonalCoversEachCentreOnce) {
  // Centres on the diagonal x = y belong to the lower-right triangle, for which the
  // diagonal is a left edge; the upper-left one has it as a right edge.
  Rasterizer r(16, 16);
  auto lower = draw(r, win(0, 0, 16, 16), win(8, 0, 16, 16), win(8, 8, 16, 16));
  auto upper = draw(r, win(0, 0, 16, 16), win(8, 8, 16, 16), win(0, 8, 16, 16));
  EXPECT_EQ(lower.size(), 36u);  // y <= x: 8 * 9 / 2
  EXPECT_EQ(upper.size(), 28u);  // y > x
  for (const auto& f : lower) EXPECT_LE(f.y, f.x);
  for (const auto& f : upper) EXPECT_GT(f.y, f.x);
  Coverage cov(16, 16);
  for (const auto& f : lower) cov.add(f);
  for (const auto& f : upper) cov.add(f);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) EXPECT_EQ(cov.at(x, y), (x < 8 && y < 8) ? 1 : 0) << x << "," << y;
}

TEST(RasterCoverage, TopLeftRuleInGlWindowCoordinates) {
  // The square (2.5..5.5) x (1.5..4.5) has pixel centres exactly on all four sides.
  // Left (x = 2.5) and top (y = 4.5, the larger y) are in; right and bottom are out.
  const uint32_t n = 8;
  Rasterizer r(n, n);
  // Lower-left half: left edge x = 2.5, bottom edge y = 1.5, diagonal as a right edge.
  auto t1 = draw(r, win(2.5, 1.5, n, n), win(5.5, 1.5, n, n), win(2.5, 4.5, n, n));
  EXPECT_EQ(pixels(t1), (std::set<Pixel>{{2, 2}, {2, 3}, {3, 2}}));
  // Upper-right half: right edge x = 5.5, top edge y = 4.5, diagonal as a left edge.
  auto t2 = draw(r, win(5.5, 1.5, n, n), win(5.5, 4.5, n, n), win(2.5, 4.5, n, n));
  EXPECT_EQ(pixels(t2), (std::set<Pixel>{{2, 4}, {3, 3}, {3, 4}, {4, 2}, {4, 3}, {4, 4}}));
  // Reversed winding changes nothing.
  auto t2cw = draw(r, win(2.5, 4.5, n, n), win(5.5, 4.5, n, n), win(5.5, 1.5, n, n));
  EXPECT_EQ(pixels(t2cw), pixels(t2));
  // Together: the 3 x 3 block x, y in 2..4, each once.
  std::set<Pixel> all = pixels(t1);
  for (const auto& p : pixels(t2)) EXPECT_TRUE(all.insert(p).second) << "covered twice";
  std::set<Pixel> block;
  for (int y = 2; y <= 4; ++y)
    for (int x = 2; x <= 4; ++x) block.insert({x, y});
  EXPECT_EQ(all, block);
}

TEST(RasterCoverage, FullScreenPairCoversEveryPixelExactlyOnce) {
  const uint32_t w = 37, h = 23;  // odd sizes: the diagonal crosses centres unevenly
  Rasterizer r(w, h);
  const ClipVertex a{{-1, -1, 0, 1}}, b{{1, -1, 0, 1}}, c{{1, 1, 0, 1}}, d{{-1, 1, 0, 1}};
  Coverage cov(w, h);
  for (const auto& f : draw(r, a, b, c)) cov.add(f);
  for (const auto& f : draw(r, a, c, d)) cov.add(f);
  EXPECT_EQ(r.stats().fragments, uint64_t{w} * h);
  for (int v : cov.count) EXPECT_EQ(v, 1);
}

TEST(RasterCoverage, HugeTriangleIsGuardBandClippedAndCoversTheViewportOnce) {
  const uint32_t w = 40, h = 30;
  Rasterizer r(w, h);
  // Far beyond the guard band on two sides; its left and bottom edges lie on the
  // viewport's borders, where no pixel centre lies.
  const ClipVertex a{{-1, -1, 0, 1}}, b{{3001, -1, 0, 1}}, c{{-1, 3001, 0, 1}};
  Coverage cov(w, h);
  for (const auto& f : draw(r, a, b, c)) cov.add(f);
  EXPECT_EQ(r.stats().clipped, 1u);
  for (int v : cov.count) EXPECT_EQ(v, 1);
}

TEST(RasterCoverage, RandomFansInRectanglesCoverEveryCentreExactlyOnce) {
  // Fans around an interior point whose outer vertices lie on a rectangle with
  // integer corners: the union is that rectangle, and no pixel centre lies on its
  // border, so every centre inside must be covered exactly once, whatever the
  // sub-pixel positions and windings.
  const uint32_t n = 48;
  Rasterizer r(n, n);
  Rng rng(7, "fans");
  auto sub = [&](int lo, int hi) { return lo + static_cast<double>(rng.below((hi - lo) * 256 + 1)) / 256; };
  for (int trial = 0; trial < 150; ++trial) {
    const int x0 = static_cast<int>(rng.below(20)), y0 = static_cast<int>(rng.below(20));
    const int x1 = x0 + 2 + static_cast<int>(rng.below(26)), y1 = y0 + 2 + static_cast<int>(rng.below(26));
    // Points along the perimeter, counter-clockwise from the bottom-left corner.
    std::vector<std::pair<double, double>> ring;
    auto side = [&](double ax, double ay, double bx, double by, bool vertical) {
      ring.push_back({ax, ay});
      std::vector<double> ts;
      for (int k = static_cast<int>(rng.below(4)); k > 0; --k)
        ts.push_back(vertical ? sub(std::min<int>(ay, by), std::max<int>(ay, by))
                              : sub(std::min<int>(ax, bx), std::max<int>(ax, bx)));
      std::sort(ts.begin(), ts.end());
      if (vertical ? by < ay : bx < ax) std::reverse(ts.begin(), ts.end());
      for (double t : ts)
        if (vertical ? (t != ay && t != by) : (t != ax && t != bx))
          ring.push_back(vertical ? std::pair{ax, t} : std::pair{t, ay});
    };
    side(x0, y0, x1, y0, false);
    side(x1, y0, x1, y1, true);
    side(x1, y1, x0, y1, false);
    side(x0, y1, x0, y0, true);
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    const double cx = x0 + 0.1 + rng.uniform() * (x1 - x0 - 0.2);
    const double cy = y0 + 0.1 + rng.uniform() * (y1 - y0 - 0.2);
    Coverage cov(n, n);
    for (size_t i = 0; i < ring.size(); ++i) {
      auto [ax, ay] = ring[i];
      auto [bx, by] = ring[(i + 1) % ring.size()];
      ClipVertex p = win(cx, cy, n, n), q = win(ax, ay, n, n), s = win(bx, by, n, n);
      if (rng.below(2)) std::swap(q, s);  // random winding
      for (const auto& f : draw(r, p, q, s)) cov.add(f);
    }
    for (int y = 0; y < static_cast<int>(n); ++y)
      for (int x = 0; x < static_cast<int>(n); ++x) {
        const int want = (x >= x0 && x < x1 && y >= y0 && y < y1) ? 1 : 0;
        ASSERT_EQ(cov.at(x, y), want) << "trial " << trial << " pixel " << x << "," << y;
      }
  }
}

TEST(RasterCoverage, JitteredPerspectiveMeshCoversTheViewportExactlyOnce) {
  // A grid spanning the viewport, inner vertices jittered, each vertex at its own
  // clip w (the divide must give shared vertices the same window position), cells
  // split on random diagonals with random windings.
  const uint32_t w = 61, h = 47;
  const int cells = 9;
  Rasterizer r(w, h);
  Rng rng(11, "mesh");
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<ClipVertex> v((cells + 1) * (cells + 1));
    for (int j = 0; j <= cells; ++j)
      for (int i = 0; i <= cells; ++i) {
        double x = static_cast<double>(i) / cells, y = static_cast<double>(j) / cells;
        // +-0.15 cell keeps every cell convex, so either diagonal splits it cleanly.
        if (i > 0 && i < cells) x += rng.uniform(-0.15, 0.15) / cells;
        if (j > 0 && j < cells) y += rng.uniform(-0.15, 0.15) / cells;
        const float cw = rng.uniformf(0.5, 2.0);
        ClipVertex& cv = v[j * (cells + 1) + i];
        cv.pos = {static_cast<float>(2 * x - 1) * cw, static_cast<float>(2 * y - 1) * cw, 0, cw};
      }
    Coverage cov(w, h);
    auto tri = [&](int a, int b, int c) {
      if (rng.below(2)) std::swap(b, c);
      for (const auto& f : draw(r, v[a], v[b], v[c])) cov.add(f);
    };
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i) {
        const int p00 = j * (cells + 1) + i, p10 = p00 + 1, p01 = p00 + cells + 1, p11 = p01 + 1;
        if (rng.below(2)) {
          tri(p00, p10, p11);
          tri(p00, p11, p01);
        } else {
          tri(p00, p10, p01);
          tri(p10, p11, p01);
        }
      }
    for (size_t k = 0; k < cov.count.size(); ++k)
      ASSERT_EQ(cov.count[k], 1) << "trial " << trial << " pixel " << k % w << "," << k / w;
  }
}

TEST(RasterCoverage, FloorCrossingTheNearPlaneIsWatertight) {
  // A gridded floor from behind the camera to far ahead and far to the sides: near
  // plane and guard-band clipping cut shared edges, which must still match. Every
  // pixel below the floor's far edge is covered exactly once, none above it.
  const uint32_t w = 96, h = 64;
  Camera cam;
  cam.eye = {0, 1, 0};
  cam.target = {0, 0.7f, -3};
  cam.fovy_deg = 60;
  cam.aspect = double(w) / h;
  cam.near_plane = 0.1;
  cam.far_plane = 100;
  const Mat4 vp = cam.viewProjection();
  Rasterizer r(w, h);
  const int cells = 16;
  const float x0 = -50, x1 = 50, z0 = 10, z1 = -40;
  Coverage cov(w, h);
  auto at = [&](int i, int j) {
    ClipVertex v;
    v.pos = vp.transformPoint({x0 + (x1 - x0) * i / cells, 0, z0 + (z1 - z0) * j / cells});
    return v;
  };
  for (int j = 0; j < cells; ++j)
    for (int i = 0; i < cells; ++i) {
      for (const auto& f : draw(r, at(i, j), at(i + 1, j), at(i + 1, j + 1))) cov.add(f);
      for (const auto& f : draw(r, at(i, j), at(i + 1, j + 1), at(i, j + 1))) cov.add(f);
    }
  EXPECT_GT(r.stats().clipped, 0u);
  const Vec4 far_edge = vp.transformPoint({0, 0, z1});
  const double far_y = (far_edge.y / far_edge.w + 1) * 0.5 * h;
  ASSERT_GT(far_y, 10);
  ASSERT_LT(far_y, h - 10);
  for (int y = 0; y < static_cast<int>(h); ++y)
    for (int x = 0; x < static_cast<int>(w); ++x) {
      const double cy = y + 0.5;
      if (cy < far_y - 0.05) {
        ASSERT_EQ(cov.at(x, y), 1) << x << "," << y;
      } else if (cy > far_y + 0.05) {
        ASSERT_EQ(cov.at(x, y), 0) << x << "," << y;
      }
    }
}

TEST(RasterInterpolation, AttributesArePerspectiveCorrectAndDepthIsLinearInScreen) {
  // A at w = 1, B at w = 3, C at w = 1; B's barycentric weight in screen space is
  // s = x_w / 63 everywhere (A and C share x = 0). Perspective-correct u (0 at A and C,
  // 1 at B) is (s/3) / ((1 - s) + s/3), so 0.25 at the middle where linear would give
  // 0.5. Window depth is linear in screen space: z_ndc is -1, 1, -1, so z_w = s.
  const uint32_t n = 63;
  Rasterizer r(n, n, 1);
  ClipVertex a{{-1, -1, -1, 1}}, b{{3, -3, 3, 3}}, c{{-1, 1, -1, 1}};
  a.attr[0] = 0, b.attr[0] = 1, c.attr[0] = 0;
  auto fs = draw(r, a, b, c);
  ASSERT_GT(fs.size(), 1500u);
  bool saw_middle = false;
  for (const auto& f : fs) {
    const double s = (f.x + 0.5) / n;
    EXPECT_NEAR(f.attr[0], (s / 3) / ((1 - s) + s / 3), 2e-6) << f.x << "," << f.y;
    EXPECT_NEAR(f.z, s, 2e-6);
    if (f.x == 31) {
      EXPECT_NEAR(f.attr[0], 0.25, 2e-6);
      saw_middle = true;
    }
  }
  EXPECT_TRUE(saw_middle);
}

TEST(RasterInterpolation, ConstantAttributesStayExact) {
  Rasterizer r(32, 32, 4);
  ClipVertex a{{-1, -1, 0, 1}}, b{{2, -2, 0, 2}}, c{{-0.5f, 0.5f, 0, 0.5f}};
  for (ClipVertex* v : {&a, &b, &c}) v->attr = {0.25f, 1.0f, 0.0f, 0.7f, 0, 0, 0, 0};
  auto fs = draw(r, a, b, c);
  ASSERT_FALSE(fs.empty());
  for (const auto& f : fs) {
    EXPECT_FLOAT_EQ(f.attr[0], 0.25f);
    EXPECT_FLOAT_EQ(f.attr[1], 1.0f);
    EXPECT_EQ(f.attr[2], 0.0f);
    EXPECT_FLOAT_EQ(f.attr[3], 0.7f);
    EXPECT_EQ(f.attr[4], 0.0f) << "attributes beyond the count stay zero";
  }
}

// A's depth is beyond one plane, B's and C's inside: the plane crosses the triangle at
// half of AB and AC, i.e. along x_w + y_w = 32 in a 64 x 64 viewport.
void expectHalfClipped(float a_z, float bc_z, bool near) {
  const uint32_t n = 64;
  Rasterizer r(n, n);
  auto fs = draw(r, {{-1, -1, a_z, 1}}, {{1, -1, bc_z, 1}}, {{-1, 1, bc_z, 1}});
  EXPECT_EQ(r.stats().clipped, 1u);
  // Kept: 31 <= x + y <= 62 (the clip edge is a left edge, the hypotenuse a right edge).
  std::set<Pixel> expected;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x)
      if (x + y >= 31 && x + y <= 62) expected.insert({x, y});
  EXPECT_EQ(expected.size(), 1520u);
  EXPECT_EQ(fs.size(), 1520u);
  EXPECT_EQ(pixels(fs), expected);
  for (const auto& f : fs) {
    const double t = (f.x + f.y + 1) / 32.0 - 1;  // 0 on the clip edge, ~1 at the hypotenuse
    EXPECT_NEAR(f.z, near ? t : 1 - t, 1e-6);
  }
}

TEST(RasterClipping, NearPlaneCutsTheTriangleWhereDepthCrossesMinusOne) {
  expectHalfClipped(-3, 1, true);
}

TEST(RasterClipping, FarPlaneCutsTheTriangleWhereDepthCrossesOne) {
  expectHalfClipped(3, -1, false);
}

TEST(RasterClipping, VertexBehindTheCameraIsClippedNotProjected) {
  // A floor triangle with one vertex behind the eye. Projecting that vertex would
  // flip it to the top of the screen; clipping keeps the visible part only. Compare
  // with the triangle clipped by hand in view space at the near plane.
  const uint32_t w = 80, h = 60;
  Camera cam;
  cam.eye = {0, 1, 0};
  cam.target = {0, 0.5f, -3};
  cam.aspect = double(w) / h;
  cam.near_plane = 0.5;
  cam.far_plane = 50;
  const Mat4 vp = cam.viewProjection(), view = cam.view();
  const Vec3 A{-2, 0, -6}, B{2, 0, -6}, C{0.3f, 0, 3};
  Rasterizer r(w, h);
  auto fs = draw(r, {vp.transformPoint(A)}, {vp.transformPoint(B)}, {vp.transformPoint(C)});
  EXPECT_EQ(r.stats().clipped, 1u);
  // By hand: where AC and BC cross view depth -near (a hair inside, so that the
  // reference triangles need no clipping themselves).
  auto cut = [&](Vec3 in, Vec3 out) {
    const float zi = view.transformPoint(in).z, zo = view.transformPoint(out).z;
    const float t = static_cast<float>((-cam.near_plane * 1.0001 - zi) / (zo - zi));
    return lerp(in, out, t);
  };
  const Vec3 P = cut(A, C), Q = cut(B, C);
  Rasterizer ref(w, h);
  auto ref_fs = draw(ref, {vp.transformPoint(A)}, {vp.transformPoint(B)}, {vp.transformPoint(Q)});
  auto more = draw(ref, {vp.transformPoint(A)}, {vp.transformPoint(Q)}, {vp.transformPoint(P)});
  ref_fs.insert(ref_fs.end(), more.begin(), more.end());
  for (const Vec3& q : {P, Q}) {
    const Vec4 c = vp.transformPoint(q);
    EXPECT_GT(c.z + c.w, 0) << "the reference is in front of the near plane";
  }
  const auto got = pixels(fs), want = pixels(ref_fs);
  ASSERT_GT(want.size(), 1000u);
  std::vector<Pixel> diff;
  std::set_symmetric_difference(got.begin(), got.end(), want.begin(), want.end(), std::back_inserter(diff));
  EXPECT_LE(diff.size(), 4u) << "rounding may move a few boundary centres, nothing more";
  EXPECT_EQ(got.size(), fs.size()) << "no pixel twice";
  for (const auto& f : fs) {
    EXPECT_GE(f.z, 0.0f);
    EXPECT_LE(f.z, 1.0f);
  }
}

TEST(RasterClipping, ScissorsToTheViewportAndRejectsBeyondTheGuardBand) {
  const uint32_t n = 16;
  Rasterizer r(n, n);
  // Square from (-4, -4) to (4, 4): only pixels 0..3 x 0..3 are in the viewport.
  auto a = draw(r, win(-4, -4, n, n), win(4, -4, n, n), win(4, 4, n, n));
  auto b = draw(r, win(-4, -4, n, n), win(4, 4, n, n), win(-4, 4, n, n));
  std::set<Pixel> all = pixels(a);
  for (const auto& p : pixels(b)) EXPECT_TRUE(all.insert(p).second);
  EXPECT_EQ(all.size(), 16u);
  for (const auto& [x, y] : all) EXPECT_TRUE(x < 4 && y < 4);
  // Off screen but inside the guard band: rasterized to nothing.
  EXPECT_TRUE(draw(r, {{2, 2, 0, 1}}, {{3, 2, 0, 1}}, {{2, 3, 0, 1}}).empty());
  EXPECT_EQ(r.stats().rejected, 0u);
  // Beyond the guard band: rejected before rasterization.
  EXPECT_TRUE(draw(r, {{5, 0, 0, 1}}, {{6, 0, 0, 1}}, {{5, 1, 0, 1}}).empty());
  EXPECT_EQ(r.stats().rejected, 1u);
}

TEST(RasterRules, CullModesUseCounterClockwiseFrontFaces) {
  Rasterizer r(16, 16);
  const ClipVertex a = win(0, 0, 16, 16), b = win(8, 0, 16, 16), c = win(0, 8, 16, 16);
  r.setCullMode(CullMode::Back);
  EXPECT_EQ(draw(r, a, b, c).size(), 28u);  // counter-clockwise: front
  EXPECT_EQ(draw(r, a, c, b).size(), 0u);
  r.setCullMode(CullMode::Front);
  EXPECT_EQ(draw(r, a, b, c).size(), 0u);
  EXPECT_EQ(draw(r, a, c, b).size(), 28u);
  EXPECT_EQ(r.stats().culled, 2u);
}

TEST(RasterRules, EmitsRowsBottomToTopAndPixelsLeftToRight) {
  Rasterizer r(12, 9);
  auto fs = draw(r, {{-1, -1, 0, 1}}, {{3, -1, 0, 1}}, {{-1, 3, 0, 1}});
  ASSERT_EQ(fs.size(), 12u * 9u);
  for (size_t i = 0; i < fs.size(); ++i) {
    EXPECT_EQ(fs[i].x, i % 12);
    EXPECT_EQ(fs[i].y, i / 12);
  }
}

TEST(RasterRules, DegenerateTrianglesCoverNothing) {
  Rasterizer r(16, 16);
  EXPECT_TRUE(draw(r, win(1, 1, 16, 16), win(5, 5, 16, 16), win(9, 9, 16, 16)).empty());
  EXPECT_TRUE(draw(r, win(1, 1, 16, 16), win(1, 1, 16, 16), win(9, 3, 16, 16)).empty());
}

TEST(RasterRules, SnapsToOneTwoHundredFiftySixthOfAPixel) {
  Rasterizer r(64, 64);
  // x_w = 3.25 -> 832; 3.2 * 256 = 819.2 -> 819; y_w = 10 + 0.6/256 -> 2561.
  auto s = r.snap(win(3.25, 10 + 0.6 / 256, 64, 64).pos);
  EXPECT_EQ(s.x, 832);
  EXPECT_EQ(s.y, 2561);
  EXPECT_EQ(r.snap(win(3.2, 0, 64, 64).pos).x, 819);
}

TEST(RasterRules, RejectsBadConfiguration) {
  EXPECT_THROW(Rasterizer(0, 10), std::invalid_argument);
  EXPECT_THROW(Rasterizer(10, 70000), std::invalid_argument);
  Rasterizer r(4, 4);
  EXPECT_THROW(r.setAttributeCount(kMaxAttributes + 1), std::invalid_argument);
  EXPECT_THROW(r.setAttributeCount(-1), std::invalid_argument);
}

}  // namespace
}  // namespace oit::gen
