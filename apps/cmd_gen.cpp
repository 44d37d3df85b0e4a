// oitsim gen SCENE -o FILE: render a synthetic scene into a fragment trace.
// oitsim scenes: list the generator scenes and the named meshes.
#include <array>
#include <charconv>
#include <chrono>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "apps/Commands.hpp"
#include "apps/OutputFiles.hpp"
#include "apps/Progress.hpp"
#include "traces/TraceIO.hpp"
#include "traces/gen/Mesh.hpp"
#include "traces/gen/Scenes.hpp"

namespace oit::cli {

namespace {

struct GenArgs {
  std::string scene;
  std::string output;
  gen::SceneOptions opts;
  double azimuth = 0, elevation = 0, fov = 40;
  float alpha = 1;
  std::string colour;
  std::string shading = "lambert";
  std::string encoding = "fp32";
  bool quiet = false;
};

// "r,g,b" with each component a number in [0, 1].
std::array<float, 3> parseColour(const std::string& text) {
  std::array<float, 3> c{};
  std::string_view rest = text;
  for (int i = 0; i < 3; ++i) {
    const size_t comma = rest.find(',');
    if ((i < 2) != (comma != std::string_view::npos))
      throw std::invalid_argument(fmt::format("--colour expects r,g,b (three numbers), got '{}'", text));
    std::string_view part = rest.substr(0, comma);
    while (!part.empty() && part.front() == ' ') part.remove_prefix(1);
    while (!part.empty() && part.back() == ' ') part.remove_suffix(1);
    auto [p, ec] = std::from_chars(part.data(), part.data() + part.size(), c[i]);
    if (ec != std::errc() || p != part.data() + part.size() || !(c[i] >= 0 && c[i] <= 1))
      throw std::invalid_argument(
          fmt::format("--colour component '{}' is not a number in [0, 1] (in '{}')", part, text));
    rest = comma == std::string_view::npos ? std::string_view{} : rest.substr(comma + 1);
  }
  return c;
}

const char* encodingName(ColourEncoding e) { return e == ColourEncoding::Unorm8 ? "unorm8" : "fp32"; }

void runGen(GenArgs& a, bool has_az, bool has_el, bool has_fov, bool has_alpha) {
  gen::SceneOptions& o = a.opts;
  if (has_az) o.azimuth_deg = a.azimuth;
  if (has_el) o.elevation_deg = a.elevation;
  if (has_fov) o.fov_deg = a.fov;
  if (has_alpha) o.alpha = a.alpha;
  if (!a.colour.empty()) o.colour = parseColour(a.colour);
  o.shading = a.shading == "constant" ? gen::Shading::Constant : gen::Shading::Lambert;
  o.encoding = a.encoding == "unorm8" ? ColourEncoding::Unorm8 : ColourEncoding::Fp32;

  // -o is checked before the scene is built (a bad path failed only at the end).
  checkOutputFile("-o", a.output);
  // Never overwrite the mesh being read (a named mesh is its installed file).
  const gen::NamedMesh* named = gen::findNamedMesh(o.mesh);
  checkNotInput("-o", a.output, "mesh --mesh", named ? named->path : o.mesh);
  const auto start = std::chrono::steady_clock::now();
  gen::SceneGenerator generator(a.scene, o);  // validates before any file is created
  std::unique_ptr<FragmentSink> writer = createTraceWriter(a.output, generator.header());
  Progress bar("gen " + a.scene, !a.quiet);
  const gen::GenResult r = generator.generate(*writer, [&](double f) { bar.update(f); });
  writer->commit();
  bar.finish();

  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  fmt::print("{} -> {}: {} fragments, {}, {} primitives, {} x {}, {} colour, {:.2f} s ({}fragments/s)\n",
             a.scene, a.output, r.fragments, counted(r.draws, "draw", "draws"), r.primitives, o.width, o.height,
             encodingName(o.encoding), secs, humanCount(secs > 0 ? r.fragments / secs : 0.0) + " ");
}

}  // namespace

void addGenCommand(CLI::App& app) {
  auto args = std::make_shared<GenArgs>();
  CLI::App* cmd = app.add_subcommand("gen", "Render a synthetic scene into a fragment trace");
  cmd->add_option("scene", args->scene, "Scene name (see `oitsim scenes`)")->required();
  cmd->add_option("-o,--output", args->output, "Trace file to write (.csv for CSV)")->required();
  gen::SceneOptions& o = args->opts;
  // 65535: x and y are u16 in a trace record (traces/FORMAT.md).
  cmd->add_option("--width", o.width, "Frame width in pixels")->capture_default_str()->check(unsignedRange(1, 65535));
  cmd->add_option("--height", o.height, "Frame height in pixels")->capture_default_str()->check(unsignedRange(1, 65535));
  cmd->add_option("--seed", o.seed, "Random seed; the same seed gives the same trace")->capture_default_str();
  cmd->add_flag("--backdrop", o.backdrop, "Draw an opaque wall, floor and pillar first");
  cmd->add_option("--count", o.count, "Number of quads/strands/cards/panes (0 = scene default)");
  cmd->add_option("--density", o.density, "Multiply the element count")->capture_default_str();
  cmd->add_option("--mesh", o.mesh, "Mesh for the mesh scene: a name or an .obj/.off/.ply[.gz] path")
      ->capture_default_str();
  CLI::Option* az = cmd->add_option("--azimuth", args->azimuth, "Camera azimuth in degrees (0 looks from +z)");
  CLI::Option* el = cmd->add_option("--elevation", args->elevation, "Camera elevation in degrees");
  cmd->add_option("--distance", o.distance, "Camera distance from the scene centre (0 = fit)");
  CLI::Option* fov = cmd->add_option("--fov", args->fov, "Vertical field of view in degrees (default 40)");
  CLI::Option* alpha = cmd->add_option("--alpha", args->alpha, "Main transparent alpha in [0, 1]");
  cmd->add_option("--colour,--color", args->colour, "Main colour as r,g,b in [0, 1]");
  cmd->add_option("--shading", args->shading, "Mesh shading")
      ->capture_default_str()
      ->check(CLI::IsMember({"constant", "lambert"}));
  cmd->add_option("--encoding", args->encoding, "Colour encoding of the trace records")
      ->capture_default_str()
      ->check(CLI::IsMember({"fp32", "unorm8"}));
  cmd->add_flag("-q,--quiet", args->quiet, "No progress display");
  cmd->callback([args, az, el, fov, alpha] {
    runGen(*args, az->count() > 0, el->count() > 0, fov->count() > 0, alpha->count() > 0);
  });
}

void addScenesCommand(CLI::App& app) {
  CLI::App* cmd = app.add_subcommand("scenes", "List the generator scenes and the named meshes");
  cmd->callback([] {
    fmt::print("Scenes (oitsim gen SCENE -o FILE):\n");
    for (const gen::SceneInfo& s : gen::sceneCatalog()) {
      const std::string count =
          s.default_count ? fmt::format(" [default {} {}]", s.default_count, s.count_unit) : "";
      fmt::print("  {:<10} {}{}\n", s.name, s.description, count);
    }
    fmt::print("\nNamed meshes (--mesh NAME for gen mesh and capture; any .obj/.off/.ply file,\n"
               "optionally .gz, by path):\n");
    for (const gen::NamedMesh& m : gen::namedMeshes()) {
      const std::string state =
          gen::fileReadable(m.path) ? "installed" : fmt::format("missing: {}", gen::meshInstallHint(m));
      fmt::print("  {:<12} {} (package {}, {})\n               {}\n", m.name, m.description, m.package,
                 state, m.path);
    }
  });
}

}  // namespace oit::cli
