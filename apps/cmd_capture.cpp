// oitsim capture: render meshes with a real OpenGL (Mesa llvmpipe, headless), or
// replay an apitrace trace of any GL application (--apitrace), and record every
// fragment into a trace. See traces/CAPTURE.md.
#include <array>
#include <charconv>
#include <memory>
#include <span>
#include <tuple>
#include <utility>
#include <stdexcept>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "apps/Commands.hpp"
#include "apps/OutputFiles.hpp"
#include "apps/Progress.hpp"
#include "traces/TraceIO.hpp"
#include "traces/capture/ApitraceCapture.hpp"
#include "traces/capture/GlCapture.hpp"
#include "traces/gen/Mesh.hpp"
#include "apps/CaptureVerify.hpp"

namespace oit::cli {

namespace {

struct CaptureArgs {
  capture::CaptureOptions opts;
  std::string output;
  std::vector<std::string> colours;
  std::vector<float> alphas;
  double azimuth = 0, elevation = 0, fov = 40;
  std::string shading = "lambert";
  std::string frames = "1";  // mesh: a count; --apitrace: A or A-B
  double orbit_step = 10;
  bool verify = false;
  bool quiet = false;
  std::string apitrace;      // the apitrace file (--apitrace)
  std::string retracer;
  bool strict = false;
};

// "N" (1..100000), the mesh capture's frame count.
uint32_t parseFrameCount(const std::string& text) {
  uint32_t n = 0;
  auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec != std::errc() || p != text.data() + text.size() || n < 1 || n > 100000)
    throw std::invalid_argument(fmt::format("--frames '{}': expected a frame count 1..100000 with --mesh", text));
  return n;
}

// "A" or "A-B" (swap-buffer counts from 0, A <= B), the --apitrace frame range.
std::pair<uint32_t, uint32_t> parseFrameRange(const std::string& text) {
  auto bad = [&] {
    return std::invalid_argument(
        fmt::format("--frames '{}': expected a frame A or a range A-B of swap-buffer counts (from 0, A <= B) "
                    "with --apitrace", text));
  };
  const size_t dash = text.find('-');
  auto number = [&](std::string_view v) {
    uint32_t n = 0;
    auto [p, ec] = std::from_chars(v.data(), v.data() + v.size(), n);
    if (v.empty() || ec != std::errc() || p != v.data() + v.size()) throw bad();
    return n;
  };
  const std::string_view t(text);
  const uint32_t a = number(t.substr(0, dash));
  const uint32_t b = dash == std::string::npos ? a : number(t.substr(dash + 1));
  if (a > b || b - a >= 100000) throw bad();
  return {a, b};
}

// File of frame `frame` of the range: OUT itself for one frame, else OUT-FFFF.EXT
// named by the frame's swap-buffer count.
std::string rangeFileName(const std::string& output, uint32_t frame, uint32_t first, uint32_t last) {
  return capture::frameFileName(output, frame, last - first + 1);
}

void runApitraceCapture(const CaptureArgs& a) {
  capture::ApitraceOptions o;
  o.trace = a.apitrace;
  std::tie(o.first_frame, o.last_frame) = parseFrameRange(a.frames);
  o.verify = a.verify;
  o.max_records_per_draw = a.opts.max_records_per_draw;
  o.retracer = a.retracer;
  for (uint32_t f = o.first_frame; f <= o.last_frame; ++f) {
    const std::string path = rangeFileName(a.output, f, o.first_frame, o.last_frame);
    checkOutputFile("-o", path);
    checkNotInput("-o", path, "apitrace trace --apitrace", o.trace);
  }
  const capture::ApitraceResult r = capture::captureApitrace(o);
  // Every check before the first file is written: nothing half-written.
  if (a.strict)
    for (const capture::FrameCapture& f : r.frames)
      if (!f.uncaptured.empty()) {
        const capture::UncapturedDraw& u = f.uncaptured.front();
        throw std::runtime_error(fmt::format(
            "{}: frame {}: {} draw call{} not captured (--strict), the first draw {} ({}, program {}): {}", o.trace,
            f.frame, f.uncaptured.size(), f.uncaptured.size() == 1 ? "" : "s", u.index, u.function, u.program,
            capture::uncapturedReasonName(u.reason)));
      }
  std::vector<std::unique_ptr<FragmentSink>> writers;
  for (const capture::FrameCapture& f : r.frames) {
    auto w = createTraceWriter(rangeFileName(a.output, f.frame, o.first_frame, o.last_frame), f.header);
    w->write(std::span<const Fragment>(f.fragments));
    writers.push_back(std::move(w));
  }
  bool all_ok = true;
  std::vector<std::string> verify_lines;
  for (const capture::FrameCapture& f : r.frames) {
    if (!a.verify) continue;
    const capture::TransparentVerifyResult v = capture::verifyTransparentDraws(f);
    verify_lines.push_back(fmt::format(
        "  verify frame {}: GL's check drawing of the {} transparent fragments, its records replayed with alpha vs "
        "its blend (RGBA32F): {} of {} channels differ (max {} ulp, {:.3g} abs); per-pixel counts: {} of {} pixels "
        "differ{}{}; the trace vs the check drawing: {} of {} fragments at another draw, primitive, pixel or depth, "
        "{} drawn into the window given to another primitive (a shared edge) and {} with another depth (max "
        "{:.3g}, bound {:.3g}), {} with another colour (max "
        "{:.3g}, bound {:.3g}){}",
        f.frame, v.check_fragments, v.channels_differing, v.channels_compared, v.max_ulps, v.max_abs,
        v.count_pixels_differing, v.pixels, v.first_difference.empty() ? "" : "; first: " + v.first_difference,
        v.clamped ? fmt::format(" ({} premultiplied colours above their alpha, clamped for the trace: colours not compared)",
                              v.clamped)
                  : "",
        v.drawing_mismatches, v.fragments, v.primitive_differing, v.depth_differing, v.max_depth_diff,
        capture::TransparentVerifyResult::kWindowDepthBound,
        v.colour_differing, v.max_colour_diff,
        capture::TransparentVerifyResult::kDrawingColourBound,
        v.drawingsAgree() ? "" : "; first: " + v.first_drawing_difference));
    all_ok = all_ok && v.passes();
  }
  if (!all_ok) {
    for (const std::string& l : verify_lines) fmt::print(stderr, "{}\n", l);
    throw std::runtime_error(fmt::format("{}: capture --verify: the trace does not reproduce GL's blend (see above); "
                                         "nothing written", o.trace));
  }
  uint64_t fragments = 0;
  for (size_t i = 0; i < r.frames.size(); ++i) {
    writers[i]->commit();
    const capture::FrameCapture& f = r.frames[i];
    fragments += f.fragments.size();
    fmt::print("{}\n", capture::frameSummary(f, rangeFileName(a.output, f.frame, o.first_frame, o.last_frame)));
    if (a.verify) fmt::print("{}\n", verify_lines[i]);
  }
  fmt::print("{} frame{}, {} fragments in {:.2f} s ({}fragments/s, replay included){}\n", r.frames.size(),
             r.frames.size() == 1 ? "" : "s", fragments, r.seconds,
             humanCount(r.seconds > 0 ? fragments / r.seconds : 0.0) + " ",
             r.replays > 1 ? fmt::format("; replayed twice: a draw outgrew the first record buffer ({} records), "
                                         "the second held {}",
                                         r.first_record_capacity, r.record_capacity)
                           : "");
}

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
  if (a.apitrace.empty() == a.opts.meshes.empty())
    throw std::invalid_argument("capture needs exactly one of --mesh (meshes drawn by oitsim) and --apitrace "
                                "(an apitrace trace of an application)");
  if (!a.apitrace.empty()) {
    runApitraceCapture(a);
    return;
  }
  if (a.strict || !a.retracer.empty())
    throw std::invalid_argument(fmt::format("{} applies to --apitrace only", a.strict ? "--strict" : "--retracer"));
  const uint32_t frames = parseFrameCount(a.frames);
  capture::CaptureOptions& o = a.opts;
  if (has_az) o.azimuth_deg = a.azimuth;
  if (has_el) o.elevation_deg = a.elevation;
  if (has_fov) o.fov_deg = a.fov;
  for (const std::string& c : a.colours) o.colours.push_back(parseRgb(c));
  o.alphas = a.alphas;
  o.shading = a.shading == "constant" ? gen::Shading::Constant : gen::Shading::Lambert;

  // -o is checked before GL starts; never overwrite a mesh being read (a named
  // mesh is its installed file).
  for (uint32_t f = 0; f < frames; ++f) {
    checkOutputFile("-o", capture::frameFileName(a.output, f, frames));
    for (const std::string& m : o.meshes) {
      const gen::NamedMesh* named = gen::findNamedMesh(m);
      checkNotInput("-o", capture::frameFileName(a.output, f, frames), "mesh --mesh", named ? named->path : m);
    }
  }
  capture::Capturer cap(o);  // validates, loads meshes, creates the GL context
  if (!a.quiet) fmt::print(stderr, "capture: {} ({})\n", cap.renderer(), cap.glVersion());
  bool all_ok = true;
  for (uint32_t f = 0; f < frames; ++f) {
    const std::string path = capture::frameFileName(a.output, f, frames);
    const double az_off = a.orbit_step * f;
    std::unique_ptr<FragmentSink> writer = createTraceWriter(path, cap.header());
    const capture::CaptureStats st = cap.capture(*writer, az_off);
    writer->commit();
    fmt::print("{} -> {}: {} fragments, {}, {} triangles, {} x {}, {} GL draw calls "
               "(up to {} records each{}), {:.2f} s ({}fragments/s)\n",
               fmt::join(o.meshes, "+"), path, st.fragments, counted(cap.header().draws.size(), "draw", "draws"), st.triangles,
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
      "capture", "Render meshes with Mesa's OpenGL (headless llvmpipe), or replay an apitrace trace of an "
                 "application through it, and record every fragment");
  capture::CaptureOptions& o = args->opts;
  o.meshes.clear();
  cmd->add_option("--mesh", o.meshes,
                  "Mesh to draw, a name (see `oitsim scenes`) or an .obj/.off/.ply[.gz] path; repeat for "
                  "several draws");
  cmd->add_option("--apitrace", args->apitrace,
                  "An apitrace trace of a GLX application (`apitrace trace -o F.trace PROGRAM`): replay it with "
                  "glretrace on a private Xvfb and capture the frames of --frames");
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
  cmd->add_option("--frames", args->frames,
                  "With --mesh: frames along an orbit, one trace each; with --apitrace: the frame A or range A-B "
                  "(swap-buffer counts from 0), one trace each (OUT-FFFF.EXT for a range)")
      ->capture_default_str();
  cmd->add_flag("--strict", args->strict,
                "With --apitrace: refuse a frame with draw calls the trace cannot express (fixed function, "
                "several render targets, MSAA, stencil, ...) instead of listing them");
  cmd->add_option("--retracer", args->retracer, "With --apitrace: apitrace's GL retracer (default glretrace on PATH)");
  cmd->add_option("--orbit-step", args->orbit_step, "Azimuth step between frames, degrees")->capture_default_str();
  cmd->add_flag("--verify", args->verify,
                "Also check each trace against GL's own blended framebuffer and a counting pass (with --apitrace: "
                "the frame's transparent draws against GL's blend of those draws)");
  cmd->add_flag("-q,--quiet", args->quiet, "Do not print the GL renderer");
  cmd->callback([args, az, el, fov] { runCapture(*args, az->count() > 0, el->count() > 0, fov->count() > 0); });
}

}  // namespace oit::cli
