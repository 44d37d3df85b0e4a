// What the scene generator (Scenes.cpp) and the scenes' content (SceneContent.cpp)
// share: the plan of draws a scene is made of, the emitter that rasterises and
// shades them into the sink, geometry helpers, and the content of each scene
// family. Internal to traces/gen.
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <initializer_list>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "traces/gen/Backdrop.hpp"
#include "traces/gen/Math.hpp"
#include "traces/gen/Random.hpp"
#include "traces/gen/Rasterizer.hpp"
#include "traces/gen/Scenes.hpp"

namespace oit::gen {

// Named (not anonymous) so that ScenePlan, which Scenes.hpp declares, may hold them.
namespace scene_impl {

// World layout shared by the scenes: transparent content within ~1 of the origin,
// an optional floor just below it and a back wall behind it.
constexpr float kFloorY = Backdrop::kFloorY;
constexpr float kWallBehind = Backdrop::kWallBehind;

inline std::array<float, 3> hsv(double h, double s, double v) {
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
inline Vec3 inBall(Rng& rng, float radius) {
  for (;;) {
    Vec3 p{rng.uniformf(-1, 1), rng.uniformf(-1, 1), rng.uniformf(-1, 1)};
    if (dot(p, p) <= 1.0f) return p * radius;
  }
}

// A uniform point in the disc of the given radius in the xz plane.
inline Vec3 inDiscXZ(Rng& rng, float radius) {
  for (;;) {
    float x = rng.uniformf(-1, 1), z = rng.uniformf(-1, 1);
    if (x * x + z * z <= 1.0f) return {x * radius, 0, z * radius};
  }
}

inline ClipVertex clipVertex(const Mat4& vp, const Vec3& p, std::initializer_list<float> attr = {}) {
  ClipVertex v;
  v.pos = vp.transformPoint(p);
  size_t i = 0;
  for (float a : attr) v.attr[i++] = a;
  return v;
}

inline float clamp01(float v) { return v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v); }

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
inline Vec3 mix(const Vec3& a, const Vec3& b, float t) { return a * (1.0f - t) + b * t; }

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

namespace scene_impl {

// The content of each scene family (SceneContent.cpp), appended to the plan as
// draws and passes.

struct ParticleParams {
  uint32_t count;
  Vec3 centre;
  float radius;          // of the ball the particles fill
  float size_min, size_max;  // quad half-size
};

void addParticles(ScenePlan& p, const std::string& name, const ParticleParams& pp);

void addHair(ScenePlan& p, uint32_t strands);
void addFoliage(ScenePlan& p, uint32_t cards);
void addGlass(ScenePlan& p, uint32_t panes);

struct MeshPlacement {
  float radius = 1.0f;    // bounding-sphere radius in the world
  bool on_floor = false;  // rest on the floor instead of centring on the origin
  std::array<float, 3> colour{0.95f, 0.62f, 0.35f};  // unless --colour
  float alpha = 0.35f;                               // unless --alpha
};
// A transparent mesh, normalised to the placement; returns the world centre.
Vec3 addMesh(ScenePlan& p, const MeshPlacement& place);

}  // namespace scene_impl

}  // namespace oit::gen
