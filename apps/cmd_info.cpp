// oitsim info TRACE: what an architect wants to know before replaying a trace.
#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>

#include "apps/Commands.hpp"
#include "apps/OutputFiles.hpp"
#include "apps/TraceOptions.hpp"
#include "apps/Progress.hpp"
#include "model/Image.hpp"
#include "traces/TraceStats.hpp"
#include "traces/UnmodelledDraws.hpp"

namespace oit::cli {
namespace {

struct InfoArgs {
  std::string trace;
  uint32_t width = 0, height = 0;
  bool width_given = false, height_given = false;
  bool json = false;
  std::string heatmap;  // --heatmap FILE.pfm
  bool heatmap_given = false;
};

nlohmann::json complexityJson(const ComplexityStats& c) {
  nlohmann::json hist = nlohmann::json::array();
  for (unsigned b = 0; b < kComplexityBins; ++b) {
    auto [lo, hi] = complexityBinRange(b);
    nlohmann::json bin = {{"min", lo}, {"pixels", c.histogram[b]}};
    if (b + 1 < kComplexityBins) bin["max"] = hi;
    hist.push_back(bin);
  }
  return {{"covered_pixels", c.covered_pixels}, {"fragments", c.fragments},
          {"mean", c.mean()},                   {"max", c.max},
          {"max_at", {c.max_x, c.max_y}},       {"histogram", hist}};
}

void printComplexity(const char* title, const ComplexityStats& c, uint64_t pixels) {
  fmt::print("{}\n", title);
  if (c.covered_pixels == 0) {
    fmt::print("  (no fragments)\n");
    return;
  }
  fmt::print("  covered {} of {} pixels ({:.1f}%), mean {:.2f}, max {} at ({}, {})\n",
             c.covered_pixels, pixels, 100.0 * double(c.covered_pixels) / double(pixels), c.mean(),
             c.max, c.max_x, c.max_y);
  uint64_t peak = 1;
  unsigned last = 0;
  for (unsigned b = 0; b < kComplexityBins; ++b) {
    peak = std::max(peak, c.histogram[b]);
    if (c.histogram[b]) last = b;
  }
  for (unsigned b = 0; b <= last; ++b) {
    auto [lo, hi] = complexityBinRange(b);
    std::string range = lo == hi ? fmt::format("{}", lo)
                        : b + 1 == kComplexityBins ? fmt::format("{}+", lo)
                                                   : fmt::format("{}-{}", lo, hi);
    const int bar = static_cast<int>(40.0 * double(c.histogram[b]) / double(peak) + 0.5);
    fmt::print("  {:>11} |{:<40} {}\n", range, std::string(bar, '#'), c.histogram[b]);
  }
}

// Transparent fragments per pixel as a grey PFM (count in every channel), for
// the sweep report's depth-complexity heatmap; a second pass over the trace.
void writeHeatmap(FragmentSource& src, const std::string& path) {
  const TraceHeader& h = src.header();
  std::vector<bool> transparent;
  for (const DrawInfo& d : h.draws) {
    if (d.id >= transparent.size()) transparent.resize(d.id + 1, false);
    transparent[d.id] = d.cls == DrawClass::Transparent;
  }
  model::Image img(h.width, h.height);
  src.rewind();
  for (auto batch = src.next(); !batch.empty(); batch = src.next())
    for (const Fragment& f : batch)
      if (f.draw < transparent.size() && transparent[f.draw]) img.pixels[img.index(f.x, f.y)].r += 1.0f;
  for (model::Rgb& p : img.pixels) p.g = p.b = p.r;
  model::writePfm(img, path);
}

void runInfo(const InfoArgs& a) {
  checkFrameSizeOptions(a.width_given, a.width, a.height_given, a.height);
  if (a.heatmap_given) {  // before the trace is read
    checkOutputFile("--heatmap", a.heatmap);
    checkNotInput("--heatmap", a.heatmap, "trace", a.trace);
    // It writes PFM only: a .png (or any other) name would hold a PFM.
    if (std::filesystem::path(a.heatmap).extension() != ".pfm")
      throw std::invalid_argument(fmt::format(
          "--heatmap {}: expected a file name ending in .pfm (the heatmap is a PFM image; no other format)",
          a.heatmap));
  }
  auto src = openTraceWithSize(a.trace, a.width, a.height);
  // Per-pixel depth-complexity counts: transparent, opaque and all (3 x u32).
  checkFrameFitsInMemory(a.trace, src->header().width, src->header().height, 12, "its per-pixel counts");
  if (a.heatmap_given) {
    writeHeatmap(*src, a.heatmap);
    src->rewind();
  }
  Progress progress("info", !a.json);
  TraceStats st = computeTraceStats(*src, [&](uint64_t done, uint64_t total) {
    progress.update(total ? double(done) / double(total) : 0.0, humanCount(double(done)) + " fragments");
  });
  progress.finish();
  const TraceHeader& h = st.header;
  const uint64_t pixels = uint64_t(h.width) * h.height;
  const bool csv = isCsvTracePath(a.trace);  // as the reader decides (".CSV" too)

  if (a.json) {
    nlohmann::json j;
    j["trace"] = a.trace;
    j["format"] = csv ? "csv" : "binary";
    j["version"] = h.version;
    j["width"] = h.width;
    j["height"] = h.height;
    j["encoding"] = toString(h.encoding);
    j["fragments"] = st.fragments;
    if (h.camera) j["camera"] = {{"near", h.camera->near_plane}, {"far", h.camera->far_plane}};
    j["draws"] = nlohmann::json::array();
    for (const DrawStats& d : st.draws)
      j["draws"].push_back({{"id", d.draw.id}, {"name", d.draw.name}, {"class", toString(d.draw.cls)},
                            {"fragments", d.fragments},
                            // as the table's prims>=: the largest primitive id + 1, a lower bound
                            {"primitives_at_least", d.fragments ? d.max_prim + 1ull : 0ull}});
    const UnmodelledDraws u = unmodelledDraws(h.draws);
    j["not_modelled"] = {{"draws", u.draws}, {"fragments", u.fragments}};
    j["depth_complexity"] = {{"all", complexityJson(st.all)},
                             {"transparent", complexityJson(st.transparent)},
                             {"opaque", complexityJson(st.opaque)}};
    std::cout << j.dump(2) << "\n";
    return;
  }

  fmt::print("trace        {} ({} v{}, {} colour)\n", a.trace, csv ? "CSV" : "binary", h.version,
             toString(h.encoding));
  fmt::print("resolution   {} x {} ({} pixels)\n", h.width, h.height, pixels);
  if (h.camera)
    fmt::print("camera       near {} far {}\n", h.camera->near_plane, h.camera->far_plane);
  else
    fmt::print("camera       none (view-space weights unavailable)\n");
  fmt::print("fragments    {} ({} transparent, {} opaque)\n", st.fragments, st.transparent.fragments,
             st.opaque.fragments);
  fmt::print("draws        {}\n", st.draws.size());
  fmt::print("  {:>4}  {:<11}  {:<20}  {:>12}  {:>6}  {:>10}\n", "id", "class", "name", "fragments",
             "share", "prims>=");
  for (const DrawStats& d : st.draws)
    fmt::print("  {:>4}  {:<11}  {:<20}  {:>12}  {:>5.1f}%  {:>10}\n", d.draw.id, toString(d.draw.cls),
               d.draw.name, d.fragments,
               st.fragments ? 100.0 * double(d.fragments) / double(st.fragments) : 0.0,
               d.fragments ? d.max_prim + 1ull : 0ull);
  if (const UnmodelledDraws u = unmodelledDraws(h.draws); u.draws)
    fmt::print("not modelled {} (blend modes the model does not blend; in the draw state table, in no record)\n",
               u.describe());
  fmt::print("covered      {} pixels ({:.1f}%) by any fragment\n", st.all.covered_pixels,
             pixels ? 100.0 * double(st.all.covered_pixels) / double(pixels) : 0.0);
  printComplexity("depth complexity, transparent fragments per covered pixel:", st.transparent, pixels);
  printComplexity("depth complexity, all fragments per covered pixel:", st.all, pixels);
}

}  // namespace

void addInfoCommand(CLI::App& app) {
  auto args = std::make_shared<InfoArgs>();
  CLI::App* cmd = app.add_subcommand("info", "Describe a trace: resolution, draws, depth complexity");
  cmd->add_option("trace", args->trace, "Trace file (.oitt binary or .csv)")->required();
  CLI::Option* width =
      cmd->add_option("--width", args->width, "Frame width of a CSV trace without a width comment (1..65535)");
  CLI::Option* height =
      cmd->add_option("--height", args->height, "Frame height of a CSV trace without a height comment (1..65535)");
  cmd->add_flag("--json", args->json, "Print the statistics as JSON");
  CLI::Option* heatmap = cmd->add_option("--heatmap", args->heatmap,
                                         "Also write transparent fragments per pixel (depth complexity) as a PFM file "
                                         "(FILE must end in .pfm)");
  cmd->callback([args, heatmap, width, height] {
    args->width_given = width->count() > 0;
    args->height_given = height->count() > 0;
    args->heatmap_given = heatmap->count() > 0;
    runInfo(*args);
  });
}

}  // namespace oit::cli
