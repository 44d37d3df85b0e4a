// The fixture of the `oitsim capture --apitrace` tests (test_apitrace_capture.cpp,
// test_apitrace_deletes.cpp): a small GLX application of our own
// (apitrace_app/GlTestApp.cpp) draws the mesh capture's own clip-space triangles of
// a cube with the program kinds and GL states a scene file asks for; it is traced
// with `apitrace trace` under Xvfb, and the tests capture the trace through the
// interposer. Skips, saying why, without apitrace, glretrace, Xvfb or headless GL.
#pragma once

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "apps/CaptureVerify.hpp"
#include "capture/CaptureTestUtil.hpp"
#include "traces/capture/ApitraceCapture.hpp"
#include "traces/capture/GlCapture.hpp"

namespace oit::capture::test_util {

// Records equal bit for bit (Fragment has no padding: 2 + 2 + 4 + 16 + 4 + 4 bytes).
inline bool same(const std::vector<Fragment>& a, const std::vector<Fragment>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Fragment)) == 0);
}


inline bool onPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string dirs = path ? path : "/usr/bin:/bin";
  size_t start = 0;
  while (true) {
    const size_t colon = dirs.find(':', start);
    const std::string dir = dirs.substr(start, colon == std::string::npos ? std::string::npos : colon - start);
    if (::access(((dir.empty() ? "." : dir) + "/" + name).c_str(), X_OK) == 0) return true;
    if (colon == std::string::npos) return false;
    start = colon + 1;
  }
}

inline int run(const std::string& command, std::string* out) { return runCommand(command, out); }

// A cube, so that every pixel it covers has a front and a back face: depth
// complexity 2, which the depth test with writes halves.
inline const char* const kCubeObj =
    "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
    "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 4 7 3\nf 4 8 7\nf 1 5 8\nf 1 8 4\nf 2 3 7\nf 2 7 6\n";

inline constexpr uint32_t kWidth = 64, kHeight = 48;
inline constexpr float kColour[4] = {0.25f, 0.5f, 0.75f, 0.5f};

class ApitraceCapture : public ::testing::Test {
 protected:
  void SetUp() override {
    for (const char* tool : {"apitrace", "glretrace", "Xvfb", "xvfb-run"})
      if (!onPath(tool))
        GTEST_SKIP() << tool << " not found: the apitrace capture tests trace a GLX program under Xvfb "
                     << "(apt-get install apitrace xvfb; scripts/setup.sh installs them)";
    static const std::optional<std::string> reason = glUnavailableReason();
    if (reason) GTEST_SKIP() << "EGL + OpenGL 4.5 core unavailable: " << *reason;
    dir_ = std::filesystem::path(OITSIM_BINARY_DIR) / "test-apitrace" /
           ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::filesystem::remove_all(dir_);
    std::filesystem::create_directories(dir_);
    std::ofstream(path("cube.obj")) << kCubeObj;
    // The mesh capture of the cube: its fragments and its triangles.
    CaptureOptions o;
    o.width = kWidth;
    o.height = kHeight;
    o.meshes = {path("cube.obj")};
    o.colours = {{kColour[0], kColour[1], kColour[2]}};
    o.alphas = {kColour[3]};
    o.shading = gen::Shading::Constant;
    o.azimuth_deg = 35;
    o.elevation_deg = 25;
    Capturer cap(o);
    cap.capture(mesh_);
    clip_ = cap.clipVertices(0);
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Writes the scene file, runs the application under apitrace on Xvfb; the trace's path.
  // Frame 0 of a replay is drawn while glretrace's window may still be taking the
  // application's size (the first frame's back buffer can be the old size): the
  // tests capture frames from 1 on.
  // `extra`: more lines of the scene file (GlTestApp.cpp's keys), before the draws.
  std::string traceApp(const std::vector<std::string>& draws, int frames = 3, bool fbo = true,
                       const std::string& extra = "") {
    std::string scene = fmt::format("size {} {}\nframes {}\nfbo {}\n{}", kWidth, kHeight, frames, fbo ? 1 : 0, extra);
    for (const std::string& d : draws) {
      scene += fmt::format("draw {} {} {} {} {}\n", d, kColour[0], kColour[1], kColour[2], kColour[3]);
      scene.pop_back();
      scene += fmt::format(" {}\n", clip_.size());
      for (const auto& v : clip_) scene += fmt::format("{} {} {} {}\n", v[0], v[1], v[2], v[3]);
    }
    const std::string name = fmt::format("app{}", traces_++);
    std::ofstream(path(name + ".txt")) << scene;
    const std::string trace = path(name + ".trace");
    std::string out;
    const int rc = run(fmt::format("xvfb-run -a -s '-screen 0 640x480x24' apitrace trace -o {} {} {}", trace,
                                   OITSIM_GL_TESTAPP, path(name + ".txt")),
                       &out);
    EXPECT_EQ(rc, 0) << out;
    return trace;
  }
  ApitraceOptions options(const std::string& trace, uint32_t frame) const {
    ApitraceOptions o;
    o.trace = trace;
    o.first_frame = o.last_frame = frame;
    o.interposer = std::string(OITSIM_BINARY_DIR) + "/apps/liboitsim_interposer.so";
    return o;
  }
  // Frame 1 of the trace captured with --verify (GL's check drawing, its records).
  ApitraceResult verifiedCapture(const std::string& trace) const {
    ApitraceOptions o = options(trace, 1);
    o.verify = true;
    return captureApitrace(o);
  }
  // The mesh capture's fragments as draw `draw`, kept where keep(fragment) holds.
  template <typename Keep>
  std::vector<Fragment> expected(uint32_t draw, Keep keep) const {
    std::vector<Fragment> out;
    for (Fragment f : mesh_.fragments)
      if (keep(f)) {
        f.draw = draw;
        out.push_back(f);
      }
    return out;
  }
  std::vector<Fragment> expected(uint32_t draw) const {
    return expected(draw, [](const Fragment&) { return true; });
  }
  static std::vector<Fragment> ofDraw(const FrameCapture& f, uint32_t draw) {
    std::vector<Fragment> out;
    for (const Fragment& x : f.fragments)
      if (x.draw == draw) out.push_back(x);
    return out;
  }
  static const DrawInfo* drawOf(const FrameCapture& f, uint32_t id) { return f.header.findDraw(id); }

  std::filesystem::path dir_;
  int traces_ = 0;
  VectorSink mesh_;
  std::vector<std::array<float, 4>> clip_;
};

// The records of a draw into the window against the mesh capture's (drawn into a
// framebuffer object): every field equal but depth, within 2 ulp. Measured on this
// cube: drawn into an FBO, all 3408 records are bit-identical; drawn into the
// window (llvmpipe keeps window buffers upside down), 1645 of them have
// gl_FragCoord.z 1 or 2 ulp off, x, y, primitive and colour still equal.
// Returns "" or the first difference.
inline std::string sameUpToDepthUlp(const std::vector<Fragment>& a, const std::vector<Fragment>& b) {
  if (a.size() != b.size()) return fmt::format("{} records against {}", a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    Fragment x = a[i];
    x.z = b[i].z;
    if (std::memcmp(&x, &b[i], sizeof(Fragment)) != 0 || ulpDistance(a[i].z, b[i].z) > 2)
      return fmt::format("record {}: ({}, {}) z {} rgba {} {} {} {} prim {} vs ({}, {}) z {} rgba {} {} {} {} prim {}", i,
                         a[i].x, a[i].y, a[i].z, a[i].r, a[i].g, a[i].b, a[i].a, a[i].prim, b[i].x, b[i].y, b[i].z,
                         b[i].r, b[i].g, b[i].b, b[i].a, b[i].prim);
  }
  return "";
}

// The first record that differs, field by field.
inline std::string firstDifference(const std::vector<Fragment>& a, const std::vector<Fragment>& b) {
  for (size_t i = 0; i < std::min(a.size(), b.size()); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(Fragment)) != 0)
      return fmt::format("record {}: ({}, {}) z {} rgba {} {} {} {} prim {} draw {} vs ({}, {}) z {} rgba {} {} {} {} prim {} draw {}",
                         i, a[i].x, a[i].y, a[i].z, a[i].r, a[i].g, a[i].b, a[i].a, a[i].prim, a[i].draw, b[i].x, b[i].y,
                         b[i].z, b[i].r, b[i].g, b[i].b, b[i].a, b[i].prim, b[i].draw);
  return a.size() == b.size() ? "none" : fmt::format("sizes {} and {}", a.size(), b.size());
}

}  // namespace oit::capture::test_util
