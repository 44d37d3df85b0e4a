// The mesh capture's scene, without GL: the meshes placed in world space as
// `oitsim gen mesh` places them, gen's camera, the trace's draw table, and per
// frame the triangle soup GL draws (GlCapture.cpp uploads and draws it).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "traces/TraceIO.hpp"
#include "traces/capture/GlCapture.hpp"
#include "traces/gen/Math.hpp"
#include "traces/gen/Mesh.hpp"

namespace oit::capture {

// Shading modes of the fragment shader (u_shade).
enum ShadeMode : int { kConstant = 0, kLambertTwoSided = 1, kLambertOneSided = 2, kChecker = 3 };

// Geometry of one frame: per trace draw, parts with their own shading, all in one
// triangle soup of (clip, world, normal) vertices.
struct Part {
  uint64_t first_tri = 0, tris = 0;  // in the soup
  int shade = kConstant;
  std::array<float, 3> colour{}, dark{};
  float alpha = 1;
  gen::Vec3 axis_u, axis_v;
};
struct DrawGeom {
  uint32_t id = 0;
  DrawClass cls = DrawClass::Transparent;
  std::vector<Part> parts;
  bool cull_back = false;  // as gen's CullMode::Back (the backdrop's wall and pillar)
};
struct Vertex {
  float clip[4];
  float world[3];
  float normal[3];
};

struct Scene {
  gen::Camera camera;
  gen::Mat4 vp;
  gen::Vec3 light;
  std::vector<DrawGeom> draws;
  std::vector<Vertex> soup;

  // Appends triangle (a, b, c) with face normal n; returns nothing, counts by soup size.
  void tri(const gen::Vec3& a, const gen::Vec3& b, const gen::Vec3& c, const gen::Vec3& n) {
    for (const gen::Vec3* p : {&a, &b, &c}) {
      const gen::Vec4 cp = vp.transformPoint(*p);
      soup.push_back({{cp.x, cp.y, cp.z, cp.w}, {p->x, p->y, p->z}, {n.x, n.y, n.z}});
    }
  }
  uint64_t triCount() const { return soup.size() / 3; }
};

class CaptureScene {
 public:
  // Loads and places opts.meshes (options already checked by Capturer); throws
  // std::runtime_error for an unloadable, degenerate or unframeable mesh.
  explicit CaptureScene(const CaptureOptions& opts);

  // Frame size, fp32 encoding, camera planes and the draw table (backdrop and
  // pillar first when asked, then one draw per mesh).
  TraceHeader header() const;
  // The frame with the camera's azimuth turned by azimuth_offset degrees.
  Scene build(double azimuth_offset) const;

 private:
  gen::Camera camera(double azimuth_offset) const;
  void addBackdrop(Scene& s) const;

  CaptureOptions opts_;
  std::vector<std::shared_ptr<gen::Mesh>> meshes_;  // in world space (placed)
  std::vector<std::string> names_;
  double fit_radius_ = 0.82, spread_ = 0;
};

}  // namespace oit::capture
