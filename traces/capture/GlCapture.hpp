// Headless fragment capture through a real OpenGL implementation (Mesa llvmpipe
// via EGL surfaceless, OpenGL 4.5 core): the same meshes, camera and shading as
// `oitsim gen mesh`, rasterised by GL, every fragment recorded by the fragment
// shader into a storage buffer, then sorted into API order and written as a trace.
//
// Only this library links GL; everything else in oitsim stays GL-free.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "traces/Fragment.hpp"
#include "traces/TraceIO.hpp"
#include "traces/gen/Scenes.hpp"

namespace oit::capture {

// An EGL or GL failure: names the call, the error code and what to install or check.
class GlError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CaptureOptions {
  uint32_t width = 1280, height = 720;
  // Named meshes or .obj/.off/.ply[.gz] paths, one transparent draw each, in this
  // submission order. One mesh is placed exactly as `oitsim gen mesh` places it;
  // several stand side by side along x, each scaled to the unit sphere.
  std::vector<std::string> meshes{"bunny"};
  // Per-mesh colour and alpha: empty = gen's defaults, one value = all meshes,
  // else one per mesh.
  std::vector<std::array<float, 3>> colours;
  std::vector<float> alphas;
  gen::Shading shading = gen::Shading::Lambert;
  bool backdrop = false;  // gen's opaque wall + floor + pillar, drawn first
  // Camera, with `oitsim gen` conventions (orbit around the origin; unset = gen's
  // mesh-scene defaults: azimuth 30, elevation 5, fov 40, distance fits).
  std::optional<double> azimuth_deg, elevation_deg, fov_deg;
  double distance = 0;
  // Records one GL draw call may produce (the storage buffer's size); 0 = as many
  // as the implementation's largest shader storage block holds. A draw that
  // overflows is re-issued in halves.
  uint64_t max_records_per_draw = 0;
};

struct CaptureStats {
  uint64_t fragments = 0;
  uint64_t triangles = 0;
  uint64_t gl_draws = 0;      // draw calls that produced the trace (after splitting)
  uint64_t gl_redraws = 0;    // draw calls re-issued in halves after an overflow
  uint64_t capacity = 0;      // records per draw call
  std::vector<uint64_t> fragments_per_draw;  // indexed by trace draw id
  double seconds = 0;         // vertex setup, GL draws, read back, sort, writing to the sink
};

// GL's own images of one frame, for checking a captured trace.
struct GlReference {
  uint32_t width = 0, height = 0;
  // RGBA32F framebuffer, cleared to 0, opaque draws with depth test LESS, then the
  // transparent draws blended SRC_ALPHA / ONE_MINUS_SRC_ALPHA in submission order
  // (depth test LESS, no depth write). Row 0 is the bottom row.
  std::vector<float> rgba;
  // Fragments per pixel: 1.0 added per fragment (blend ONE, ONE), no depth test.
  std::vector<float> count;
};

struct Scene;

class Capturer {
 public:
  // Loads the meshes and creates the GL context; throws std::invalid_argument for
  // bad options, std::runtime_error for an unloadable mesh, GlError for EGL/GL.
  explicit Capturer(CaptureOptions opts);
  ~Capturer();
  Capturer(const Capturer&) = delete;
  Capturer& operator=(const Capturer&) = delete;

  // Frame size, fp32 encoding, camera planes and the draw table (backdrop and
  // pillar first when asked, then one draw per mesh).
  const TraceHeader& header() const;
  // "llvmpipe (LLVM 15.0.6, 256 bits)", "4.5 (Core Profile) Mesa 22.3.6".
  std::string renderer() const;
  std::string glVersion() const;
  uint64_t recordsPerDraw() const;

  // Renders the frame with the camera's azimuth turned by azimuth_offset_deg and
  // writes every fragment in API order: by draw, then primitive, then (y, x).
  // Does not commit the sink.
  CaptureStats capture(FragmentSink& sink, double azimuth_offset_deg = 0);
  // The same frame blended and counted by GL itself.
  GlReference reference(double azimuth_offset_deg = 0);
  // The clip-space (x, y, z, w) vertices of trace draw `draw`, three per triangle
  // in submission order, exactly as capture() feeds them to GL (so an application
  // drawing them rasterises the same fragments).
  std::vector<std::array<float, 4>> clipVertices(uint32_t draw, double azimuth_offset_deg = 0) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Why EGL + OpenGL 4.5 core cannot be initialised here, or nullopt when it can.
std::optional<std::string> glUnavailableReason();

// File name of frame i of n: "out.oitt" itself for n = 1, else "out-0000.oitt"...
std::string frameFileName(const std::string& output, uint32_t frame, uint32_t frames);

}  // namespace oit::capture
