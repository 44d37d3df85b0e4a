#include "traces/gen/Scenes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "traces/gen/Backdrop.hpp"
#include "traces/gen/Math.hpp"
#include "traces/gen/Mesh.hpp"
#include "traces/gen/Random.hpp"
#include "traces/gen/Rasterizer.hpp"

namespace oit::gen {

// Named (not anonymous) so that ScenePlan, which the header declares, may hold them.
namespace scene_impl {

// World layout shared by the scenes: transparent content within ~1 of the origin,
// an optional floor just below it and a back wall behind it.
constexpr float kFloorY = Backdrop::kFloorY;
constexpr float kWallBehind = Backdrop::kWallBehind;

struct Catalogue {
  const char* name;
  const char* description;
  uint32_t default_count;
  const char* count_unit;
  // Default camera: orbit angles, and the radius of the sphere around the origin
  // that distance 0 fits in the view.
  double azimuth, elevation, fit_radius;
};

// Default counts keep each scene at about 0.5-4 M fragments at 1280x720.
constexpr Catalogue kScenes[] = {
    {"particles", "camera-facing low-alpha quads with radial falloff, random order", 2000, "quads",
     0, 10, 1.05},
    {"hair", "thin 1-2 px strands gathered into tight bundles: depth complexity in the hundreds",
     3000, "strands", 20, 5, 1.05},
    {"foliage", "alpha-textured leaf cards: alpha exactly 0 outside the leaf, 1 in its core", 700,
     "cards", 30, 15, 1.05},
    {"glass", "a few large overlapping coloured panes, submitted out of depth order", 6, "panes",
     0, 8, 1.1},
    // Meshes fill their bounding sphere loosely: fit a smaller one.
    {"mesh", "one transparent mesh (--mesh, default bunny), constant or Lambert shading", 0, "",
     30, 5, 0.82},
    {"demo", "opaque backdrop + transparent bunny + a particle cloud around it", 1200,
     "particles", 30, 12, 1.15},
};

std::string sceneNames() {
  std::string s;
  for (const Catalogue& c : kScenes) s += (s.empty() ? "" : ", ") + std::string(c.name);
  return s;
}

const Catalogue* findScene(const std::string& name) {
  for (const Catalogue& c : kScenes)
    if (name == c.name) return &c;
  return nullptr;
}

std::array<float, 3> hsv(double h, double s, double v) {
  h = (h - std::floor(h)) * 6.0;
  const int i = static_cast<int>(h) % 6;
  const double f = h - std::floor(h);
  const double p = v * (1 - s), q = v * (1 - s * f), t = v * (1 - s * (1 - f));
  double r, g, b;
  switch (i) {
    case 0: r = v, g = t, b = p; break;
    case 1: r = q, g = v, b = p; break;
    case 2: r = p, g = v, b = t; break;
    case 3: r = p, g = q, b = v; break;
    case 4: r = t, g = p, b = v; break;
    default: r = v, g = p, b = q; break;
  }
  return {static_cast<float>(r), static_cast<float>(g), static_cast<float>(b)};
}

// A uniform point in the ball of the given radius (rejection from the cube).
Vec3 inBall(Rng& rng, float radius) {
  for (;;) {
    Vec3 p{rng.uniformf(-1, 1), rng.uniformf(-1, 1), rng.uniformf(-1, 1)};
    if (dot(p, p) <= 1.0f) return p * radius;
  }
}

// A uniform point in the disc of the given radius in the xz plane.
Vec3 inDiscXZ(Rng& rng, float radius) {
  for (;;) {
    float x = rng.uniformf(-1, 1), z = rng.uniformf(-1, 1);
    if (x * x + z * z <= 1.0f) return {x * radius, 0, z * radius};
  }
}

ClipVertex clipVertex(const Mat4& vp, const Vec3& p, std::initializer_list<float> attr = {}) {
  ClipVertex v;
  v.pos = vp.transformPoint(p);
  size_t i = 0;
  for (float a : attr) v.attr[i++] = a;
  return v;
}

float clamp01(float v) { return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); }

// Receives the rasterizer's fragments for the current draw and primitive, lets a
// per-primitive shader colour them, and hands them to the sink in batches.
class Emitter {
 public:
  Emitter(uint32_t width, uint32_t height, size_t draws, uint64_t total_prims, FragmentSink& sink,
          const std::function<void(double)>& progress)
      : raster_(width, height), sink_(sink), progress_(progress), total_prims_(total_prims) {
    result_.draws = static_cast<uint32_t>(draws);
    result_.fragments_per_draw.assign(draws, 0);
    result_.primitives_per_draw.assign(draws, 0);
    buf_.reserve(kBatch);
  }

  const Rasterizer& raster() const { return raster_; }

  void beginDraw(uint32_t draw, CullMode cull) {
    draw_ = draw;
    prim_ = 0;
    raster_.setCullMode(cull);
  }

  // shade(const RasterFragment&, Fragment&) sets r, g, b, a.
  template <class Shade>
  void triangle(const ClipVertex& a, const ClipVertex& b, const ClipVertex& c, int nattr,
                Shade&& shade) {
    raster_.setAttributeCount(nattr);
    const uint32_t prim = prim_++;
    uint64_t n = 0;
    raster_.drawTriangle(a, b, c, [&](const RasterFragment& rf) {
      if (buf_.size() == kBatch) flush();
      Fragment& f = buf_.emplace_back();
      f.x = rf.x;
      f.y = rf.y;
      f.z = rf.z;
      shade(rf, f);
      // Interpolation can overshoot by an ulp; the trace format demands [0, 1].
      f.r = clamp01(f.r), f.g = clamp01(f.g), f.b = clamp01(f.b), f.a = clamp01(f.a);
      f.prim = prim;
      f.draw = draw_;
      ++n;
    });
    result_.fragments += n;
    result_.fragments_per_draw[draw_] += n;
    ++result_.primitives_per_draw[draw_];
    ++result_.primitives;
    if (progress_ && total_prims_ > 0) {
      const int pct = static_cast<int>(result_.primitives * 100 / total_prims_);
      if (pct > last_pct_) {
        last_pct_ = pct;
        progress_(static_cast<double>(result_.primitives) / static_cast<double>(total_prims_));
      }
    }
  }

  GenResult finish() {
    flush();
    if (progress_ && last_pct_ < 100) progress_(1.0);
    return std::move(result_);
  }

 private:
  static constexpr size_t kBatch = 1 << 14;
  void flush() {
    if (!buf_.empty()) sink_.write(std::span<const Fragment>(buf_));
    buf_.clear();
  }

  Rasterizer raster_;
  FragmentSink& sink_;
  const std::function<void(double)>& progress_;
  uint64_t total_prims_;
  std::vector<Fragment> buf_;
  uint32_t draw_ = 0, prim_ = 0;
  int last_pct_ = -1;
  GenResult result_;
};

// a (1 - t) + b t: exact at t = 0 and t = 1 and symmetric (lerp(a, b, t) ==
// lerp(b, a, 1 - t) bitwise), so surfaces built from the same two corners share
// their edge points exactly.
Vec3 mix(const Vec3& a, const Vec3& b, float t) { return a * (1.0f - t) + b * t; }

// The quad p00 p10 p11 p01, counter-clockwise seen from the side
// (p10 - p00) x (p01 - p00) points to, split into n x n cells of two triangles.
template <class Emit>
void gridQuad(const Vec3& p00, const Vec3& p10, const Vec3& p01, const Vec3& p11, int n,
              Emit&& emit) {
  auto at = [&](int i, int j) {
    const float u = static_cast<float>(i) / static_cast<float>(n);
    const float v = static_cast<float>(j) / static_cast<float>(n);
    return mix(mix(p00, p10, u), mix(p01, p11, u), v);
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      emit(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      emit(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
}

}  // namespace scene_impl

using scene_impl::Emitter;

struct ScenePlan {
  SceneOptions opts;
  TraceHeader header;
  Camera camera;
  Mat4 vp;
  struct Pass {
    uint32_t draw;
    uint64_t prims;
    CullMode cull;
    std::function<void(Emitter&)> run;
  };
  std::vector<Pass> passes;

  uint32_t addDraw(const std::string& name, DrawClass cls) {
    const uint32_t id = static_cast<uint32_t>(header.draws.size());
    header.draws.push_back({id, cls, name});
    return id;
  }
  void addPass(uint32_t draw, uint64_t prims, CullMode cull, std::function<void(Emitter&)> run) {
    passes.push_back({draw, prims, cull, std::move(run)});
  }

  // Light from the upper left of the viewer, for the Lambert terms.
  Vec3 lightDir() const {
    return normalize(-camera.forward() + camera.trueUp() * 0.8f - camera.right() * 0.6f);
  }
};

namespace {

using Plan = ScenePlan;
using namespace scene_impl;

uint32_t scaledCount(const SceneOptions& o, uint32_t scene_default) {
  const double base = o.count ? o.count : scene_default;
  return static_cast<uint32_t>(std::max(1.0, std::round(base * o.density)));
}

void validate(const SceneOptions& o) {
  auto bad = [](const std::string& what) { throw std::invalid_argument(what); };
  if (o.width < 1 || o.height < 1 || o.width > Rasterizer::kMaxViewport ||
      o.height > Rasterizer::kMaxViewport)
    bad(fmt::format("frame size {}x{} is outside 1..65536 per axis", o.width, o.height));
  if (!std::isfinite(o.density) || o.density <= 0)
    bad(fmt::format("density {} must be a positive number", o.density));
  if (o.count > 50'000'000u) bad(fmt::format("count {} exceeds the maximum of 50000000", o.count));
  if (o.azimuth_deg && !std::isfinite(*o.azimuth_deg)) bad("azimuth must be a finite angle");
  if (o.elevation_deg && !(*o.elevation_deg >= -89 && *o.elevation_deg <= 89))
    bad(fmt::format("elevation {} is outside -89..89 degrees", *o.elevation_deg));
  if (!std::isfinite(o.distance) || o.distance < 0)
    bad(fmt::format("distance {} must be >= 0 (0 fits the scene)", o.distance));
  if (o.fov_deg && !(*o.fov_deg > 1 && *o.fov_deg < 170))
    bad(fmt::format("field of view {} is outside (1, 170) degrees", *o.fov_deg));
  if (o.alpha && !(*o.alpha >= 0 && *o.alpha <= 1))
    bad(fmt::format("alpha {} is outside [0, 1]", *o.alpha));
  if (o.colour)
    for (float c : *o.colour)
      if (!(c >= 0 && c <= 1)) bad(fmt::format("colour component {} is outside [0, 1]", c));
  if (o.encoding != ColourEncoding::Fp32 && o.encoding != ColourEncoding::Unorm8)
    bad("unknown colour encoding");
}

// Camera orbiting the origin; distance 0 fits a sphere of fit_radius in the view.
void setCamera(Plan& p, double azimuth, double elevation, double fit_radius) {
  const SceneOptions& o = p.opts;
  const double aspect = static_cast<double>(o.width) / o.height;
  const double fovy = o.fov_deg.value_or(40.0);
  const double half_y = radians(fovy) / 2, half_x = std::atan(aspect * std::tan(half_y));
  const double dist = o.distance > 0 ? o.distance : fit_radius / std::sin(std::min(half_x, half_y));
  p.camera = Camera::orbit({0, 0, 0}, o.azimuth_deg.value_or(azimuth),
                           o.elevation_deg.value_or(elevation), dist, fovy, aspect);
  // Tight planes around the content and backdrop (2 in front of the origin, wall
  // and floor behind), so depth precision and view-space weights are meaningful.
  p.camera.near_plane = std::max(0.05 * dist, dist - 2.0);
  p.camera.far_plane = dist + 4.0 + kWallBehind;
  p.vp = p.camera.viewProjection();
  p.header.camera = CameraPlanes{static_cast<float>(p.camera.near_plane),
                                 static_cast<float>(p.camera.far_plane)};
}

// Opaque checkered back wall and floor, then an opaque pillar standing in the
// content so the transparent draws are partly hidden (depth culling matters).
void addBackdrop(Plan& p) {
  const Backdrop bd = makeBackdrop(p.camera.eye, p.camera.target);
  const Mat4 vp = p.vp;

  const uint32_t wall_id = p.addDraw("backdrop", DrawClass::Opaque);
  p.addPass(wall_id, 2 * 2 * Backdrop::kGrid * Backdrop::kGrid, CullMode::Back, [=](Emitter& e) {
    for (const Backdrop::Checker& sf : bd.surfaces) {
      gridQuad(sf.p00, sf.p10, sf.p01, sf.p11, Backdrop::kGrid, [&](Vec3 a, Vec3 b, Vec3 c) {
        // Checker coordinates in cells, interpolated perspective-correctly.
        auto cv = [&](Vec3 q) {
          return clipVertex(vp, q, {dot(q, sf.u_axis) / Backdrop::kCell, dot(q, sf.v_axis) / Backdrop::kCell});
        };
        e.triangle(cv(a), cv(b), cv(c), 2, [&](const RasterFragment& rf, Fragment& f) {
          const bool odd = (static_cast<int64_t>(std::floor(rf.attr[0])) +
                            static_cast<int64_t>(std::floor(rf.attr[1]))) & 1;
          const auto& col = odd ? sf.dark : sf.light;
          f.r = col[0], f.g = col[1], f.b = col[2], f.a = 1.0f;
        });
      });
    }
  });

  const uint32_t pillar_id = p.addDraw("pillar", DrawClass::Opaque);
  const Vec3 light = p.lightDir();
  p.addPass(pillar_id, 12, CullMode::Back, [=](Emitter& e) {
    const Vec3* corner = bd.pillar;
    for (const auto& q : Backdrop::kPillarFaces) {
      const Vec3 n = normalize(cross(corner[q[1]] - corner[q[0]], corner[q[3]] - corner[q[0]]));
      const float k = 0.35f + 0.65f * std::max(0.0f, dot(n, light));
      const auto& base = Backdrop::kPillarColour;
      const std::array<float, 3> col{base[0] * k, base[1] * k, base[2] * k};
      auto shade = [&](const RasterFragment&, Fragment& f) {
        f.r = col[0], f.g = col[1], f.b = col[2], f.a = 1.0f;
      };
      const ClipVertex v[4] = {clipVertex(vp, corner[q[0]]), clipVertex(vp, corner[q[1]]),
                               clipVertex(vp, corner[q[2]]), clipVertex(vp, corner[q[3]])};
      e.triangle(v[0], v[1], v[2], 0, shade);
      e.triangle(v[0], v[2], v[3], 0, shade);
    }
  });
}

struct ParticleParams {
  uint32_t count;
  Vec3 centre;
  float radius;          // of the ball the particles fill
  float size_min, size_max;  // quad half-size
};

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
      const std::array<float, 3> col =
          o.colour ? *o.colour
                   : hsv(rng.uniform(), rng.uniform(0.55, 0.95), rng.uniform(0.75, 1.0));
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
      const Vec3 tip = k.tip + inDiscXZ(rng, 0.32f) + Vec3{0, rng.uniformf(-0.08, 0.08), 0};
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
      const Vec3 pos = lerp(base_pt, tip, rng.uniformf(0.35, 1.0)) + inBall(rng, 0.12f);
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
      pn.colour = o.colour ? *o.colour
                           : hsv((i + rng.uniform(0, 0.5)) / panes, rng.uniform(0.7, 0.95),
                                 rng.uniform(0.85, 1.0));
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

struct MeshPlacement {
  float radius = 1.0f;    // bounding-sphere radius in the world
  bool on_floor = false;  // rest on the floor instead of centring on the origin
  std::array<float, 3> colour{0.95f, 0.62f, 0.35f};  // unless --colour
  float alpha = 0.35f;                               // unless --alpha
};

// A transparent mesh, normalised to the placement; returns the world centre.
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

}  // namespace

std::vector<SceneInfo> sceneCatalog() {
  std::vector<SceneInfo> v;
  for (const Catalogue& c : kScenes) v.push_back({c.name, c.description, c.default_count, c.count_unit});
  return v;
}

SceneGenerator::SceneGenerator(const std::string& scene, const SceneOptions& opts)
    : plan_(std::make_unique<ScenePlan>()) {
  const Catalogue* cat = findScene(scene);
  if (!cat) throw std::invalid_argument(fmt::format("unknown scene '{}'; valid scenes: {}", scene, sceneNames()));
  validate(opts);
  if ((opts.count ? opts.count : cat->default_count) * opts.density > 50e6)
    throw std::invalid_argument(fmt::format("count {} x density {} exceeds 50000000 {}",
                                            opts.count ? opts.count : cat->default_count,
                                            opts.density, cat->count_unit));
  ScenePlan& p = *plan_;
  p.opts = opts;
  p.header.width = opts.width;
  p.header.height = opts.height;
  p.header.encoding = opts.encoding;
  const uint32_t count = scaledCount(opts, cat->default_count);
  const std::string name = scene;

  // Camera first: backdrops and camera-facing geometry depend on it.
  setCamera(p, cat->azimuth, cat->elevation, cat->fit_radius);

  if (opts.backdrop || name == "demo") addBackdrop(p);
  if (name == "particles") addParticles(p, "particles", {count, {0, 0, 0}, 1.0f, 0.035f, 0.08f});
  else if (name == "hair") addHair(p, count);
  else if (name == "foliage") addFoliage(p, count);
  else if (name == "glass") addGlass(p, count);
  else if (name == "mesh") addMesh(p, {});
  else {
    // A stronger colour than the mesh scene's, to stand out against the pale wall.
    const Vec3 centre = addMesh(p, {1.0f, true, {0.95f, 0.42f, 0.18f}, 0.45f});
    addParticles(p, "particles", {count, centre, 1.2f, 0.025f, 0.055f});
  }
}

SceneGenerator::~SceneGenerator() = default;
SceneGenerator::SceneGenerator(SceneGenerator&&) noexcept = default;
SceneGenerator& SceneGenerator::operator=(SceneGenerator&&) noexcept = default;

const TraceHeader& SceneGenerator::header() const { return plan_->header; }

GenResult SceneGenerator::generate(FragmentSink& sink,
                                   const std::function<void(double)>& progress) const {
  const ScenePlan& p = *plan_;
  uint64_t total = 0;
  for (const auto& pass : p.passes) total += pass.prims;
  Emitter e(p.opts.width, p.opts.height, p.header.draws.size(), total, sink, progress);
  for (const auto& pass : p.passes) {
    e.beginDraw(pass.draw, pass.cull);
    pass.run(e);
  }
  return e.finish();
}

TraceHeader sceneHeader(const std::string& scene, const SceneOptions& opts) {
  return SceneGenerator(scene, opts).header();
}

GenResult generateScene(const std::string& scene, const SceneOptions& opts, FragmentSink& sink,
                        const std::function<void(double)>& progress) {
  return SceneGenerator(scene, opts).generate(sink, progress);
}

}  // namespace oit::gen
