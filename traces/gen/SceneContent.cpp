// The transparent content of each scene family: particles, hair, foliage, glass
// and meshes (ScenePlan.hpp); the scenes combine them in Scenes.cpp.
#include <algorithm>
#include <cmath>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include "traces/gen/Mesh.hpp"
#include "traces/gen/ScenePlan.hpp"

namespace oit::gen::scene_impl {

// Every random draw is a statement of its own (or one declarator, or one element
// of a braced list, which C++ sequences): the order in which one expression's
// operands or a call's arguments are evaluated is left to the compiler (g++
// goes right to left, clang left to right), so two draws in one call made the
// generated traces differ between compilers. The order kept is the one g++
// drew in, so the traces, and every figure made from them, stay as committed
// (tests/traces/test_generator_golden.cpp holds each scene's fingerprint).
using Plan = ScenePlan;

// Camera-facing quads (two triangles sharing the diagonal) scattered in a ball, in
// generation order (random with respect to depth). Alpha falls off radially from
// the peak at the centre to exactly 0 on and outside the inscribed circle.
void addParticles(Plan& p, const std::string& name, const ParticleParams& pp) {
  const uint32_t id = p.addDraw(name, DrawClass::Transparent);
  const SceneOptions o = p.opts;
  const Mat4 vp = p.vp;
  const Vec3 right = p.camera.right(), up = p.camera.trueUp();
  p.addPass(id, 2ull * pp.count, CullMode::None, [=](Emitter& e) {
    Rng rng(o.seed, "particles");
    const float peak = o.alpha.value_or(0.3f);
    for (uint32_t i = 0; i < pp.count; ++i) {
      const Vec3 c = pp.centre + inBall(rng, pp.radius);
      const float s = rng.uniformf(pp.size_min, pp.size_max);
      std::array<float, 3> col;
      if (o.colour) {
        col = *o.colour;
      } else {  // value, saturation, hue: the draws one by one (the header comment)
        const double v = rng.uniform(0.75, 1.0), sat = rng.uniform(0.55, 0.95);
        col = hsv(rng.uniform(), sat, v);
      }
      const Vec3 r = right * s, u = up * s;
      const ClipVertex v[4] = {clipVertex(vp, c - r - u, {-1, -1}), clipVertex(vp, c + r - u, {1, -1}),
                               clipVertex(vp, c + r + u, {1, 1}), clipVertex(vp, c - r + u, {-1, 1})};
      auto shade = [&](const RasterFragment& rf, Fragment& f) {
        const float d2 = rf.attr[0] * rf.attr[0] + rf.attr[1] * rf.attr[1];
        f.r = col[0], f.g = col[1], f.b = col[2];
        f.a = peak * std::max(0.0f, 1.0f - d2);
      };
      e.triangle(v[0], v[1], v[2], 2, shade);
      e.triangle(v[0], v[2], v[3], 2, shade);
    }
  });
}

// Strands as screen-space ribbons 1-2 px wide, gathered by clumps through a tight
// knot, so hundreds of strands cross the same few pixels there.
void addHair(Plan& p, uint32_t strands) {
  const uint32_t id = p.addDraw("hair", DrawClass::Transparent);
  const SceneOptions o = p.opts;
  const Mat4 vp = p.vp;
  constexpr int kRootSegs = 10, kTipSegs = 22, kSegs = kRootSegs + kTipSegs;
  constexpr int kClumps = 6;
  p.addPass(id, 2ull * kSegs * strands, CullMode::None, [=](Emitter& e) {
    Rng rng(o.seed, "hair");
    struct Clump {
      Vec3 root, knot, tip;
    };
    Clump clumps[kClumps];
    for (int c = 0; c < kClumps; ++c) {
      Clump& k = clumps[c];
      k.root = {-0.75f + 1.5f * (c + 0.5f) / kClumps + rng.uniformf(-0.05, 0.05),
                0.72f + rng.uniformf(-0.08, 0.08), rng.uniformf(-0.35, 0.35)};
      k.knot = k.root + Vec3{rng.uniformf(-0.1, 0.1), rng.uniformf(-0.5, -0.4), rng.uniformf(-0.1, 0.1)};
      k.tip = k.knot + Vec3{rng.uniformf(-0.2, 0.2), rng.uniformf(-1.1, -0.95), rng.uniformf(-0.15, 0.15)};
    }
    const std::array<float, 3> base = o.colour.value_or(std::array<float, 3>{0.45f, 0.28f, 0.14f});
    const float alpha = o.alpha.value_or(0.45f);
    const float sx = 2.0f / static_cast<float>(o.width), sy = 2.0f / static_cast<float>(o.height);
    const float hw = static_cast<float>(o.width) / 2, hh = static_cast<float>(o.height) / 2;

    Vec4 clip[kSegs + 1];
    ClipVertex left[kSegs + 1], right[kSegs + 1];
    for (uint32_t s = 0; s < strands; ++s) {
      const Clump& k = clumps[s % kClumps];
      const Vec3 root = k.root + inDiscXZ(rng, 0.28f);
      const Vec3 knot = k.knot + inDiscXZ(rng, 0.012f);
      // Drawn one by one: the order of draws inside one expression is the
      // compiler's choice (SceneContent's header comment).
      const float tip_dy = rng.uniformf(-0.08, 0.08);
      const Vec3 tip = k.tip + inDiscXZ(rng, 0.32f) + Vec3{0, tip_dy, 0};
      const float phase = rng.uniformf(0, 2 * kPi), wave = rng.uniformf(0.01, 0.03);
      const float half_px = rng.uniformf(0.5, 1.0);  // ribbon 1-2 px wide
      const float tint = rng.uniformf(0.8, 1.2);
      // Quadratic Beziers root->knot (bulging up) and knot->tip (swinging out).
      const Vec3 c1 = (root + knot) * 0.5f + Vec3{0, 0.08f, 0};
      const Vec3 c2 = knot + (tip - knot) * 0.5f + Vec3{(tip.x - knot.x) * 0.4f, 0, 0};
      for (int j = 0; j <= kSegs; ++j) {
        Vec3 q;
        if (j <= kRootSegs) {
          const float t = static_cast<float>(j) / kRootSegs;
          q = root * ((1 - t) * (1 - t)) + c1 * (2 * t * (1 - t)) + knot * (t * t);
        } else {
          const float t = static_cast<float>(j - kRootSegs) / kTipSegs;
          q = knot * ((1 - t) * (1 - t)) + c2 * (2 * t * (1 - t)) + tip * (t * t);
          q.x += wave * t * std::sin(phase + 9.0f * t);
        }
        clip[j] = vp.transformPoint(q);
      }
      // Offset each point across the strand's screen-space direction by half_px.
      for (int j = 0; j <= kSegs; ++j) {
        const Vec4& a = clip[std::max(j - 1, 0)];
        const Vec4& b = clip[std::min(j + 1, kSegs)];
        float ox = 0, oy = 0;
        if (a.w > 1e-6f && b.w > 1e-6f) {
          const float tx = (b.x / b.w - a.x / a.w) * hw, ty = (b.y / b.w - a.y / a.w) * hh;
          const float len = std::sqrt(tx * tx + ty * ty);
          const float nx = len > 0 ? -ty / len : 1.0f, ny = len > 0 ? tx / len : 0.0f;
          ox = nx * half_px * sx * clip[j].w;
          oy = ny * half_px * sy * clip[j].w;
        }
        const float t = static_cast<float>(j) / kSegs;
        left[j].pos = {clip[j].x + ox, clip[j].y + oy, clip[j].z, clip[j].w};
        right[j].pos = {clip[j].x - ox, clip[j].y - oy, clip[j].z, clip[j].w};
        left[j].attr[0] = right[j].attr[0] = t;
      }
      auto shade = [&](const RasterFragment& rf, Fragment& f) {
        const float t = rf.attr[0];  // 0 at the root, 1 at the tip
        const float lum = tint * (0.75f + 0.45f * t);
        f.r = base[0] * lum, f.g = base[1] * lum, f.b = base[2] * lum;
        f.a = alpha * (1.0f - 0.5f * t);
      };
      for (int j = 0; j < kSegs; ++j) {
        e.triangle(left[j], right[j], right[j + 1], 1, shade);
        e.triangle(left[j], right[j + 1], left[j + 1], 1, shade);
      }
    }
  });
}

namespace {

// The leaf texture, evaluated procedurally at (u, v): a leaf along v with its stem at
// v = 0.04 and tip at 0.96. Alpha is exactly 1 within 70% of the half-width from the
// midrib, exactly 0 outside the outline, smoothstep in between.
float leafAlpha(float u, float v, float* across) {
  const float t = (v - 0.04f) / 0.92f;
  *across = 1.0f;
  if (!(t > 0.0f && t < 1.0f)) return 0.0f;
  const float half_width = 0.46f * std::pow(std::sin(static_cast<float>(kPi) * t), 0.75f);
  if (half_width <= 0.0f) return 0.0f;
  const float d = std::fabs(u - 0.5f) / half_width;
  *across = std::min(d, 1.0f);
  if (d <= 0.7f) return 1.0f;
  if (d >= 1.0f) return 0.0f;
  const float s = (d - 0.7f) / 0.3f;
  return 1.0f - s * s * (3.0f - 2.0f * s);
}

}  // namespace

// Leaf cards along branches of a bush, the leaf texture sampled per fragment at the
// perspective-correct uv.
void addFoliage(Plan& p, uint32_t cards) {
  const uint32_t id = p.addDraw("foliage", DrawClass::Transparent);
  const SceneOptions o = p.opts;
  const Mat4 vp = p.vp;
  const Vec3 light = p.lightDir();
  p.addPass(id, 2ull * cards, CullMode::None, [=](Emitter& e) {
    Rng rng(o.seed, "foliage");
    constexpr int kBranches = 12;
    const Vec3 base_pt{0, -0.95f, 0};
    Vec3 tips[kBranches];
    for (Vec3& t : tips) {
      Vec3 d = inBall(rng, 1.0f);
      d.y = std::fabs(d.y) * 0.9f + 0.1f;  // upper half: a bush grows up and out
      t = base_pt + normalize(d) * rng.uniformf(1.3, 1.8);
    }
    const std::array<float, 3> green = o.colour.value_or(std::array<float, 3>{0.25f, 0.52f, 0.14f});
    const float alpha_scale = o.alpha.value_or(1.0f);
    for (uint32_t i = 0; i < cards; ++i) {
      const Vec3& tip = tips[rng.below(kBranches)];
      const Vec3 jitter = inBall(rng, 0.12f);
      const Vec3 pos = lerp(base_pt, tip, rng.uniformf(0.35, 1.0)) + jitter;
      const float len = rng.uniformf(0.16, 0.30), wid = 0.6f * len;
      const Vec3 axis = normalize(normalize(tip - base_pt) + inBall(rng, 0.8f));
      Vec3 n = normalize(cross(axis, inBall(rng, 1.0f) + Vec3{0.01f, 0, 0}));
      if (length(n) == 0) n = normalize(cross(axis, Vec3{0, 0, 1}));
      const Vec3 side = cross(n, axis);
      const float lit = 0.55f + 0.45f * std::fabs(dot(n, light));
      const float vary = rng.uniformf(0.8, 1.15);
      const std::array<float, 3> col{green[0] * lit * vary, green[1] * lit * vary,
                                     green[2] * lit * rng.uniformf(0.7, 1.3)};
      auto corner = [&](float u, float v) {
        return clipVertex(vp, pos + side * ((u - 0.5f) * wid) + axis * (v * len), {u, v});
      };
      const ClipVertex c[4] = {corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)};
      auto shade = [&](const RasterFragment& rf, Fragment& f) {
        float across = 0;
        const float a = leafAlpha(rf.attr[0], rf.attr[1], &across);
        // Lighter midrib, darker towards the rim.
        const float vein = std::fabs(rf.attr[0] - 0.5f) < 0.012f ? 1.35f : 1.0f;
        const float k = vein * (1.05f - 0.3f * across);
        f.r = col[0] * k, f.g = col[1] * k, f.b = col[2] * k;
        f.a = a * alpha_scale;
      };
      e.triangle(c[0], c[1], c[2], 2, shade);
      e.triangle(c[0], c[2], c[3], 2, shade);
    }
  });
}

// Large tilted coloured panes, shuffled so that their submission order is neither
// front-to-back nor back-to-front.
void addGlass(Plan& p, uint32_t panes) {
  const uint32_t id = p.addDraw("glass", DrawClass::Transparent);
  const SceneOptions o = p.opts;
  const Mat4 vp = p.vp;
  const Camera cam = p.camera;
  p.addPass(id, 2ull * panes, CullMode::None, [=](Emitter& e) {
    Rng rng(o.seed, "glass");
    struct Pane {
      Vec3 centre, s, t;
      std::array<float, 3> colour;
      float alpha;
      float shade[4];
    };
    std::vector<Pane> list(panes);
    for (uint32_t i = 0; i < panes; ++i) {
      Pane& pn = list[i];
      pn.centre = {rng.uniformf(-0.55, 0.55), rng.uniformf(-0.35, 0.35), rng.uniformf(-0.7, 0.7)};
      const float yaw = static_cast<float>(radians(rng.uniform(-55, 55)));
      const float pitch = static_cast<float>(radians(rng.uniform(-20, 20)));
      const Vec3 sx{std::cos(yaw), 0, -std::sin(yaw)};
      const Vec3 ty{std::sin(yaw) * std::sin(pitch), std::cos(pitch), std::cos(yaw) * std::sin(pitch)};
      pn.s = sx * rng.uniformf(0.55, 0.9);
      pn.t = ty * rng.uniformf(0.45, 0.75);
      if (o.colour) {
        pn.colour = *o.colour;
      } else {  // value, saturation, hue: the draws one by one (the header comment)
        const double v = rng.uniform(0.85, 1.0), sat = rng.uniform(0.7, 0.95);
        pn.colour = hsv((i + rng.uniform(0, 0.5)) / panes, sat, v);
      }
      pn.alpha = o.alpha.value_or(rng.uniformf(0.3, 0.5));
      for (float& s : pn.shade) s = rng.uniformf(0.75, 1.0);  // per-corner tint
    }
    // Fisher-Yates, then break a monotone depth order by swapping the first two.
    for (uint32_t i = panes; i > 1; --i) std::swap(list[i - 1], list[rng.below(i)]);
    if (panes >= 3) {
      auto depth = [&](const Pane& pn) { return dot(pn.centre - cam.eye, cam.forward()); };
      bool inc = true, dec = true;
      for (uint32_t i = 1; i < panes; ++i) {
        inc = inc && depth(list[i - 1]) <= depth(list[i]);
        dec = dec && depth(list[i - 1]) >= depth(list[i]);
      }
      if (inc || dec) std::swap(list[0], list[1]);
    }
    for (const Pane& pn : list) {
      auto corner = [&](float u, float v, float k) {
        return clipVertex(vp, pn.centre + pn.s * u + pn.t * v,
                          {pn.colour[0] * k, pn.colour[1] * k, pn.colour[2] * k});
      };
      const ClipVertex c[4] = {corner(-1, -1, pn.shade[0]), corner(1, -1, pn.shade[1]),
                               corner(1, 1, pn.shade[2]), corner(-1, 1, pn.shade[3])};
      auto shade = [&](const RasterFragment& rf, Fragment& f) {
        f.r = rf.attr[0], f.g = rf.attr[1], f.b = rf.attr[2], f.a = pn.alpha;
      };
      e.triangle(c[0], c[1], c[2], 3, shade);
      e.triangle(c[0], c[2], c[3], 3, shade);
    }
  });
}

Vec3 addMesh(Plan& p, const MeshPlacement& place) {
  const SceneOptions o = p.opts;
  auto mesh = std::make_shared<Mesh>(loadMesh(resolveMeshPath(o.mesh)));
  const MeshBounds b = meshBounds(*mesh);
  if (!(b.radius > 0))
    throw std::runtime_error(fmt::format("mesh '{}' is degenerate (all vertices coincide)", o.mesh));
  const float scale = place.radius / b.radius;
  Vec3 offset = -b.centre * scale;  // world = p * scale + offset
  if (place.on_floor) offset.y = kFloorY - b.min.y * scale;
  auto finite = [](const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
  auto cannotFrame = [&] {
    throw std::runtime_error(fmt::format(
        "mesh '{}' cannot be framed: its bounding-sphere radius {} does not scale to a finite fp32 placement; "
        "rescale its coordinates",
        o.mesh, b.radius));
  };
  if (!std::isfinite(b.radius) || !(scale > 0) || !std::isfinite(scale) || !finite(offset)) cannotFrame();
  for (Vec3& v : mesh->positions) v = v * scale + offset;
  for (const auto& tri : mesh->triangles)
    for (uint32_t i : tri)
      if (!finite(mesh->positions[i])) cannotFrame();

  const uint32_t id = p.addDraw(meshDisplayName(o.mesh), DrawClass::Transparent);
  const Mat4 vp = p.vp;
  const Vec3 light = p.lightDir();
  p.addPass(id, mesh->triangles.size(), CullMode::None, [=](Emitter& e) {
    const std::array<float, 3> col = o.colour.value_or(place.colour);
    const float alpha = o.alpha.value_or(place.alpha);
    for (const auto& tri : mesh->triangles) {
      const Vec3 &a = mesh->positions[tri[0]], &b2 = mesh->positions[tri[1]], &c = mesh->positions[tri[2]];
      float k = 1.0f;
      if (o.shading == Shading::Lambert) {
        // Two-sided: back faces show through a transparent surface.
        const Vec3 n = normalize(cross(b2 - a, c - a));
        k = 0.35f + 0.65f * std::fabs(dot(n, light));
      }
      const std::array<float, 3> shaded{col[0] * k, col[1] * k, col[2] * k};
      e.triangle(clipVertex(vp, a), clipVertex(vp, b2), clipVertex(vp, c), 0,
                 [&](const RasterFragment&, Fragment& f) {
                   f.r = shaded[0], f.g = shaded[1], f.b = shaded[2], f.a = alpha;
                 });
    }
  });
  return b.centre * scale + offset;
}

}  // namespace oit::gen::scene_impl
