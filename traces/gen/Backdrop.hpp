// The opaque backdrop of every scene (`--backdrop`): a checkered back wall and
// floor facing the camera, and an opaque pillar standing in the content. One
// description, built by the software rasterizer's scenes (Scenes.cpp) and by
// the Mesa capture (traces/capture), so both draw the same backdrop.
#pragma once

#include <array>
#include <cmath>

#include "traces/gen/Math.hpp"

namespace oit::gen {

struct Backdrop {
  static constexpr float kFloorY = -1.05f;
  static constexpr float kWallBehind = 1.7f;  // wall distance behind the origin, along the view
  static constexpr float kCell = 0.25f;       // checker square size in world units
  static constexpr int kGrid = 8;             // each surface is kGrid x kGrid quads

  // A checkered quad p00-p10-p01-p11; the checker runs along u_axis and v_axis.
  struct Checker {
    Vec3 p00, p10, p01, p11;
    Vec3 u_axis, v_axis;
    std::array<float, 3> light, dark;
  };
  Checker surfaces[2];  // wall, floor (the wall's bottom edge is the floor's far edge)

  // Pillar corner k: bit 0 = +right, bit 1 = +up, bit 2 = +fwd; faces share corners
  // exactly, counter-clockwise seen from outside: +right, -right, +up, -up, +fwd, -fwd.
  Vec3 pillar[8];
  static constexpr int kPillarFaces[6][4] = {{1, 5, 7, 3}, {0, 2, 6, 4}, {2, 3, 7, 6},
                                             {0, 4, 5, 1}, {4, 6, 7, 5}, {0, 1, 3, 2}};
  static constexpr std::array<float, 3> kPillarColour{0.18f, 0.42f, 0.48f};
};

// Placed for a camera looking from eye at target: the wall faces the horizontal
// view direction and is wider than any view of it.
inline Backdrop makeBackdrop(const Vec3& eye, const Vec3& target) {
  Vec3 fwd = target - eye;
  fwd.y = 0;
  fwd = length(fwd) > 1e-4f ? normalize(fwd) : Vec3{0, 0, -1};
  const Vec3 right = normalize(cross(fwd, Vec3{0, 1, 0}));
  const Vec3 up{0, 1, 0};
  const float extent = 4.0f * (length(eye - target) + 2.0f);

  Backdrop b;
  const Vec3 base = fwd * Backdrop::kWallBehind + Vec3{0, Backdrop::kFloorY, 0};
  const Vec3 bl = base - right * extent, br = base + right * extent;
  const Vec3 tl = bl + up * (2 * extent), tr = br + up * (2 * extent);
  const Vec3 nl = bl - fwd * (2 * extent), nr = br - fwd * (2 * extent);
  b.surfaces[0] = {bl, br, tl, tr, right, up, {0.80f, 0.80f, 0.82f}, {0.62f, 0.63f, 0.66f}};   // wall
  b.surfaces[1] = {br, bl, nr, nl, right, fwd, {0.58f, 0.52f, 0.45f}, {0.34f, 0.30f, 0.27f}};  // floor

  constexpr float kHalf = 0.11f, kTop = 0.85f;
  const float half_h = (kTop - Backdrop::kFloorY) / 2;
  const Vec3 centre = right * 0.55f + fwd * 0.15f + Vec3{0, Backdrop::kFloorY + half_h, 0};
  for (int k = 0; k < 8; ++k)
    b.pillar[k] = centre + right * ((k & 1) ? kHalf : -kHalf) + up * ((k & 2) ? half_h : -half_h) +
                  fwd * ((k & 4) ? kHalf : -kHalf);
  return b;
}

}  // namespace oit::gen
