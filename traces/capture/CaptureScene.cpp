#include "traces/capture/CaptureScene.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "traces/gen/Backdrop.hpp"

namespace oit::capture {

using gen::Vec3;

CaptureScene::CaptureScene(const CaptureOptions& opts) : opts_(opts) {
  const size_t n = opts_.meshes.size();
  spread_ = 1.1 * static_cast<double>(n - 1);
  fit_radius_ = 0.82 + spread_;  // gen's mesh-scene fit, widened for a row of meshes
  for (size_t i = 0; i < n; ++i) {
    auto mesh = std::make_shared<gen::Mesh>(gen::loadMesh(gen::resolveMeshPath(opts_.meshes[i])));
    const gen::MeshBounds b = gen::meshBounds(*mesh);
    if (!(b.radius > 0))
      throw std::runtime_error(fmt::format("mesh '{}' is degenerate (all vertices coincide)", opts_.meshes[i]));
    // Exactly gen's placement (radius 1 at the origin) for one mesh, so the
    // vertices are bitwise the same; a row along x for several.
    const float scale = 1.0f / b.radius;
    Vec3 offset = -b.centre * scale;
    offset.x += static_cast<float>(2.2 * static_cast<double>(i) - spread_);
    // As gen's addMesh: coordinates near fp32's limit cannot be scaled into view.
    auto finite = [](const Vec3& v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); };
    auto cannotFrame = [&] {
      throw std::runtime_error(fmt::format(
          "mesh '{}' cannot be framed: its bounding-sphere radius {} does not scale to a finite fp32 placement; "
          "rescale its coordinates",
          opts_.meshes[i], b.radius));
    };
    if (!std::isfinite(b.radius) || !std::isfinite(scale) || !(scale > 0) || !finite(offset)) cannotFrame();
    for (Vec3& v : mesh->positions) v = v * scale + offset;
    for (const auto& tri : mesh->triangles)
      for (uint32_t k : tri)
        if (!finite(mesh->positions[k])) cannotFrame();
    meshes_.push_back(std::move(mesh));
    names_.push_back(gen::meshDisplayName(opts_.meshes[i]));
  }
}

// gen's setCamera for the mesh scene (azimuth 30, elevation 5, fov 40).
gen::Camera CaptureScene::camera(double azimuth_offset) const {
  const double aspect = static_cast<double>(opts_.width) / opts_.height;
  const double fovy = opts_.fov_deg.value_or(40.0);
  const double half_y = gen::radians(fovy) / 2, half_x = std::atan(aspect * std::tan(half_y));
  const double dist = opts_.distance > 0 ? opts_.distance : fit_radius_ / std::sin(std::min(half_x, half_y));
  gen::Camera c = gen::Camera::orbit({0, 0, 0}, opts_.azimuth_deg.value_or(30.0) + azimuth_offset,
                                     opts_.elevation_deg.value_or(5.0), dist, fovy, aspect);
  c.near_plane = std::max(0.05 * dist, dist - 2.0 - spread_);
  c.far_plane = dist + 4.0 + gen::Backdrop::kWallBehind + spread_;
  return c;
}

TraceHeader CaptureScene::header() const {
  TraceHeader header;
  header.width = opts_.width;
  header.height = opts_.height;
  header.encoding = ColourEncoding::Fp32;
  const gen::Camera c = camera(0);
  header.camera = CameraPlanes{static_cast<float>(c.near_plane), static_cast<float>(c.far_plane)};
  uint32_t id = 0;
  if (opts_.backdrop) {
    header.draws.push_back({id++, DrawClass::Opaque, "backdrop"});
    header.draws.push_back({id++, DrawClass::Opaque, "pillar"});
  }
  for (const std::string& name : names_) header.draws.push_back({id++, DrawClass::Transparent, name});
  return header;
}

// The shared backdrop (traces/gen/Backdrop.hpp): checkered wall and floor, then a pillar.
void CaptureScene::addBackdrop(Scene& s) const {
  using gen::Backdrop;
  static_assert(Backdrop::kCell == 0.25f, "the fragment shader's checker uses 0.25");
  const Backdrop bd = gen::makeBackdrop(s.camera.eye, s.camera.target);

  DrawGeom wall{0, DrawClass::Opaque, {}};
  auto mix = [](const Vec3& a, const Vec3& b, float t) { return a * (1.0f - t) + b * t; };
  for (const Backdrop::Checker& sf : bd.surfaces) {
    Part part;
    part.first_tri = s.triCount();
    part.shade = kChecker;
    part.colour = sf.light;
    part.dark = sf.dark;
    part.axis_u = sf.u_axis;
    part.axis_v = sf.v_axis;
    auto at = [&](int i, int j) {
      const float u = static_cast<float>(i) / Backdrop::kGrid, v = static_cast<float>(j) / Backdrop::kGrid;
      return mix(mix(sf.p00, sf.p10, u), mix(sf.p01, sf.p11, u), v);
    };
    for (int j = 0; j < Backdrop::kGrid; ++j)
      for (int i = 0; i < Backdrop::kGrid; ++i) {
        s.tri(at(i, j), at(i + 1, j), at(i + 1, j + 1), {});
        s.tri(at(i, j), at(i + 1, j + 1), at(i, j + 1), {});
      }
    part.tris = s.triCount() - part.first_tri;
    wall.parts.push_back(part);
  }
  wall.cull_back = true;  // gen draws the backdrop with CullMode::Back
  s.draws.push_back(std::move(wall));

  DrawGeom pillar{1, DrawClass::Opaque, {}};
  Part part;
  part.first_tri = s.triCount();
  part.shade = kLambertOneSided;
  part.colour = Backdrop::kPillarColour;
  const Vec3* corner = bd.pillar;
  for (const auto& q : Backdrop::kPillarFaces) {
    const Vec3 n = gen::normalize(gen::cross(corner[q[1]] - corner[q[0]], corner[q[3]] - corner[q[0]]));
    s.tri(corner[q[0]], corner[q[1]], corner[q[2]], n);
    s.tri(corner[q[0]], corner[q[2]], corner[q[3]], n);
  }
  part.tris = s.triCount() - part.first_tri;
  pillar.parts.push_back(part);
  pillar.cull_back = true;  // its back faces would add hidden fragments gen does not make
  s.draws.push_back(std::move(pillar));
}

Scene CaptureScene::build(double azimuth_offset) const {
  Scene s;
  s.camera = camera(azimuth_offset);
  s.vp = s.camera.viewProjection();
  s.light = gen::normalize(-s.camera.forward() + s.camera.trueUp() * 0.8f - s.camera.right() * 0.6f);
  uint64_t total = opts_.backdrop ? 2 * 2 * 64 + 12 : 0;
  for (const auto& m : meshes_) total += m->triangles.size();
  s.soup.reserve(total * 3);
  if (opts_.backdrop) addBackdrop(s);
  const uint32_t first_id = opts_.backdrop ? 2 : 0;
  for (size_t i = 0; i < meshes_.size(); ++i) {
    const gen::Mesh& m = *meshes_[i];
    DrawGeom d{first_id + static_cast<uint32_t>(i), DrawClass::Transparent, {}};
    Part part;
    part.first_tri = s.triCount();
    part.shade = opts_.shading == gen::Shading::Lambert ? kLambertTwoSided : kConstant;
    // gen's mesh-scene defaults.
    part.colour = opts_.colours.empty() ? std::array<float, 3>{0.95f, 0.62f, 0.35f}
                                       : opts_.colours[std::min(i, opts_.colours.size() - 1)];
    part.alpha = opts_.alphas.empty() ? 0.35f : opts_.alphas[std::min(i, opts_.alphas.size() - 1)];
    for (const auto& t : m.triangles) {
      const Vec3 &a = m.positions[t[0]], &b = m.positions[t[1]], &c = m.positions[t[2]];
      s.tri(a, b, c, gen::normalize(gen::cross(b - a, c - a)));
    }
    part.tris = s.triCount() - part.first_tri;
    d.parts.push_back(part);
    s.draws.push_back(std::move(d));
  }
  return s;
}

}  // namespace oit::capture
