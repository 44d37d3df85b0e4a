// oitsim capture: render meshes with a real OpenGL (Mesa llvmpipe, headless) and
// record every fragment into a trace. See traces/CAPTURE.md.
#include <array>
#include <charconv>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "apps/Commands.hpp"
#include "apps/OutputFiles.hpp"
#include "apps/Progress.hpp"
#include "traces/TraceIO.hpp"
#include "traces/capture/GlCapture.hpp"
#include "traces/gen/Mesh.hpp"
#include "traces/capture/Verify.hpp"

namespace oit::cli {

namespace {

struct CaptureArgs {
  capture::CaptureOptions opts;
  std::string output;
  std::vector<std::string> colours;
  std::vector<float> alphas;
  double azimuth = 0, elevation = 0, fov = 40;
  std::string shading = "lambert";
  uint32_t frames = 1;
  double orbit_step = 10;
  bool verify = false;
  bool quiet = false;
};

// "r,g,b", each a number in [0, 1].
std::array<float, 3> parseRgb(const std::string& text) {
  std::array<float, 3> c{};
  size_t start = 0;
  for (int i = 0; i < 3; ++i) {
    const size_t comma = text.find(',', start);
    if ((i < 2) != (comma != std::string::npos))
      throw std::invalid_argument(fmt::format("--colour expects r,g,b (three numbers), got '{}'", text));
    std::string part = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    while (!part.empty() && part.front() == ' ') part.erase(0, 1);
    while (!part.empty() && part.back() == ' ') part.pop_back();
    auto [p, ec] = std::from_chars(part.data(), part.data() + part.size(), c[i]);
    if (ec != std::errc() || p != part.data() + part.size() || !(c[i] >= 0 && c[i] <= 1))
      throw std::invalid_argument(
          fmt::format("--colour component '{}' is not a number in [0, 1] (in '{}')", part, text));
    start = comma + 1;
  }
  return c;
}

void runCapture(CaptureArgs& a, bool has_az, bool has_el, bool has_fov) {
  capture::CaptureOptions& o = a.opts;
  if (has_az) o.azimuth_deg = a.azimuth;
  if (has_el) o.elevation_deg = a.elevation;
  if (has_fov) o.fov_deg = a.fov;
  for (const std::string& c : a.colours) o.colours.push_back(parseRgb(c));
  o.alphas = a.alphas;
  o.shading = a.shading == "constant" ? gen::Shading::Constant : gen::Shading::Lambert;

  // -o is checked before GL starts; never overwrite a mesh being read (a named
  // mesh is its installed file).
  for (uint32_t f = 0; f < a.frames; ++f) {
    checkOutputFile("-o", capture::frameFileName(a.output, f, a.frames));
    for (const std::string& m : o.meshes) {
      const gen::NamedMesh* named = gen::findNamedMesh(m);
      checkNotInput("-o", capture::frameFileName(a.output, f, a.frames), "mesh --mesh", named ? named->path : m);
    }
  }
  capture::Capturer cap(o);  // validates, loads meshes, creates the GL context
  if (!a.quiet) fmt::print(stderr, "capture: {} ({})\n", cap.renderer(), cap.glVersion());
  bool all_ok = true;
  for (uint32_t f = 0; f < a.frames; ++f) {
    const std::string path = capture::frameFileName(a.output, f, a.frames);
    const double az_off = a.orbit_step * f;
    std::unique_ptr<FragmentSink> writer = createTraceWriter(path, cap.header());
    const capture::CaptureStats st = cap.capture(*writer, az_off);
    writer->commit();
    fmt::print("{} -> {}: {} fragments, {} draws, {} triangles, {} x {}, {} GL draw calls "
               "(up to {} records each{}), {:.2f} s ({}fragments/s)\n",
               fmt::join(o.meshes, "+"), path, st.fragments, cap.header().draws.size(), st.triangles,
               o.width, o.height, st.gl_draws, st.capacity,
               st.gl_redraws ? fmt::format(", {} re-issued in halves", st.gl_redraws) : "", st.seconds,
               humanCount(st.seconds > 0 ? st.fragments / st.seconds : 0.0) + " ");
    if (a.verify) {
      const capture::GlReference ref = cap.reference(az_off);
      const capture::VerifyResult v = capture::verifyTrace(path, ref);
      fmt::print("  verify: alpha replay vs GL RGBA32F blend: {} of {} channels differ (max {} ulp, "
                 "{:.3g} abs); per-pixel counts vs GL count pass: {} of {} pixels differ{}\n",
                 v.channels_differing, v.channels_compared, v.max_ulps, v.max_abs, v.count_pixels_differing,
                 v.pixels, v.first_difference.empty() ? "" : "; first: " + v.first_difference);
      if (v.opaque_draws)
        fmt::print("  (opaque draws: the model composites over them once, GL at every blend step; "
                   "bound {} ulp, 1e-6)\n", capture::VerifyResult::kOpaqueUlpBound);
      all_ok = all_ok && v.passes();
    }
  }
  if (!all_ok) throw std::runtime_error("capture --verify: the trace does not reproduce GL's images (see above)");
}

}  // namespace

void addCaptureCommand(CLI::App& app) {
  auto args = std::make_shared<CaptureArgs>();
  CLI::App* cmd = app.add_subcommand(
      "capture", "Render meshes with Mesa's OpenGL (headless llvmpipe) and record every fragment");
  capture::CaptureOptions& o = args->opts;
  o.meshes.clear();
  cmd->add_option("--mesh", o.meshes,
                  "Mesh to draw, a name (see `oitsim scenes`) or an .obj/.off/.ply[.gz] path; repeat for "
                  "several draws")
      ->required();
  cmd->add_option("-o,--output", args->output,
                  "Trace file to write (.csv for CSV); with --frames N: NAME-0000.EXT ...")
      ->required();
  cmd->add_option("--width", o.width, "Frame width in pixels")->capture_default_str()->check(unsignedRange(1, 16384));
  cmd->add_option("--height", o.height, "Frame height in pixels")->capture_default_str()->check(unsignedRange(1, 16384));
  CLI::Option* az = cmd->add_option("--azimuth", args->azimuth, "Camera azimuth in degrees (default 30, as gen mesh)");
  CLI::Option* el = cmd->add_option("--elevation", args->elevation, "Camera elevation in degrees (default 5)");
  cmd->add_option("--distance", o.distance, "Camera distance from the origin (0 = fit)");
  CLI::Option* fov = cmd->add_option("--fov", args->fov, "Vertical field of view in degrees (default 40)");
  cmd->add_option("--colour,--color", args->colours,
                  "Mesh colour r,g,b in [0, 1]: once for all meshes or once per mesh");
  cmd->add_option("--alpha", args->alphas, "Mesh alpha in [0, 1]: once for all meshes or once per mesh");
  cmd->add_option("--shading", args->shading, "constant, or lambert from the face normal (two-sided)")
      ->capture_default_str()
      ->check(CLI::IsMember({"constant", "lambert"}));
  cmd->add_flag("--backdrop", o.backdrop, "Draw gen's opaque wall, floor and pillar first");
  cmd->add_option("--max-records-per-draw", o.max_records_per_draw,
                  "Records one GL draw call may hold (0 = the largest shader storage block)")
      ->capture_default_str();
  cmd->add_option("--frames", args->frames, "Frames along an orbit, one trace each")
      ->capture_default_str()
      ->check(unsignedRange(1, 100000));
  cmd->add_option("--orbit-step", args->orbit_step, "Azimuth step between frames, degrees")->capture_default_str();
  cmd->add_flag("--verify", args->verify,
                "Also check each trace against GL's own blended framebuffer and a counting pass");
  cmd->add_flag("-q,--quiet", args->quiet, "Do not print the GL renderer");
  cmd->callback([args, az, el, fov] { runCapture(*args, az->count() > 0, el->count() > 0, fov->count() > 0); });
}

}  // namespace oit::cli
