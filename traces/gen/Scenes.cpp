// The scene catalogue and the generator: each scene is a camera, an optional
// backdrop and the content of its family (SceneContent.cpp), planned as draws
// (ScenePlan.hpp) and rasterised on generate().
#include "traces/gen/Scenes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "traces/gen/Mesh.hpp"
#include "traces/gen/ScenePlan.hpp"

namespace oit::gen {

namespace {

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
