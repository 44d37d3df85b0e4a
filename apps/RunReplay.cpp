// oitsim run's work: replay a trace through an OIT algorithm and write the image, the
// A-buffer reference, the enhanced difference and report.json. The timing mode
// (default) replays it through the SystemC ROP and adds cycles, stalls, DRAM
// traffic and footprint; its image is the functional one by construction with
// lock.mode=ordered (image.order). --seeds N: apps/RunSeeds.hpp; the renders
// and --reference: apps/RunRender.hpp; the memory pre-check: apps/RunMemory.hpp;
// the summary lines: apps/RunSummary.hpp.
//
// Nothing is written until the whole run has succeeded: a bad trace (which the
// reader reports with file, byte offset, record and field) leaves no report.
#include <fmt/core.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "apps/Commands.hpp"
#include "apps/RunReplay.hpp"
#include "apps/OutputFiles.hpp"
#include "apps/Progress.hpp"
#include "apps/RunMemory.hpp"
#include "apps/RunRender.hpp"
#include "apps/RunSeeds.hpp"
#include "apps/RunSummary.hpp"
#include "apps/StagedOutputs.hpp"
#include "apps/TraceOptions.hpp"
#include "model/AlgorithmSettings.hpp"
#include "model/Flip.hpp"
#include "model/FunctionalRenderer.hpp"
#include "model/Metrics.hpp"
#include "oit_rop/ChildRuns.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/TimingRun.hpp"
#include "reports/JsonReport.hpp"
#include "traces/TempFiles.hpp"
#include "traces/TraceIO.hpp"
#include "traces/UnmodelledDraws.hpp"
namespace oit::cli {

namespace fs = std::filesystem;

namespace {

// Every option is checked before the trace is read or anything is written.
void checkOptions(const RunArgs& a) {
  if (a.mode != "functional" && a.mode != "timing")
    throw std::invalid_argument("--mode: expected functional or timing, got '" + a.mode + "'");
  if (a.background.size() != 3)
    throw std::invalid_argument("--background: expected r,g,b (three linear values in [0,1])");
  for (float c : a.background)
    if (!(c >= 0.0f && c <= 1.0f)) throw std::invalid_argument("--background: each channel must be in [0,1]");
  checkFrameSizeOptions(a.width_given, a.width, a.height_given, a.height);
  if (!(a.ppd > 0.0 && a.ppd <= 10000.0))
    throw std::invalid_argument(fmt::format("--ppd: expected pixels per degree in (0, 10000], got {}", a.ppd));
  if (a.vcd_given && a.vcd.empty()) throw std::invalid_argument("--vcd: expected a file name, got an empty path");
  if (a.trace.empty()) throw std::invalid_argument("--trace: expected a trace file (.oitt or .csv), got an empty path");
  if (a.config_given && a.config_file.empty())
    throw std::invalid_argument("--config: expected a JSON file, got an empty path");
  if (a.reference.empty())
    throw std::invalid_argument("--reference: expected abuffer, none or a PFM file, got an empty value");
  checkOutputFolder("--out", a.out);
  if (!a.vcd.empty() && a.mode != "timing")
    throw std::invalid_argument(
        fmt::format("--vcd {}: a VCD needs the timing model; drop --mode {} (the default is timing)", a.vcd, a.mode));
  checkOrderingOptions(a.mode, a.seeds_given, a.seeds);
  if (a.seeds_given && a.reference == "none")
    throw std::invalid_argument(fmt::format(
        "--seeds {}: the flicker measures each seed's image against the reference; --reference none has none "
        "(give --reference abuffer or FILE.pfm)",
        a.seeds));
}

// The files a run writes into --out, the report last.
constexpr const char* kOutputs[] = {"image.png", "image.pfm", "reference.pfm", "diff.png", "flip.png", "flicker.png",
                                    "report.json"};

}  // namespace

void runReplay(RunArgs& a) {
  returnLargeBlocksToTheSystem();  // what the memory estimate assumes
  const fs::path out(a.out);
  const bool reference_file = a.reference != "abuffer" && a.reference != "none";
  // Never overwrite or remove the input: no output may be the trace itself
  // (nor the --reference file).
  for (const char* name : kOutputs) {
    if (sameFile((out / name).string(), a.trace))
      throw std::invalid_argument(fmt::format("--out {}: {} would overwrite the input trace --trace {}", a.out,
                                              (out / name).string(), a.trace));
    if (reference_file && sameFile((out / name).string(), a.reference))
      throw std::invalid_argument(fmt::format(
          "--reference {}: is {}, which this run replaces; copy it out of the --out folder first", a.reference,
          (out / name).string()));
  }
  if (!a.vcd.empty() && sameFile(rop::vcdFilePath(a.vcd), a.trace))
    throw std::invalid_argument(
        fmt::format("--vcd {}: {} is the input trace --trace {}", a.vcd, rop::vcdFilePath(a.vcd), a.trace));
  // An earlier run's outputs in the folder must never pass for this run's, also
  // when this run fails on an option or the trace: remove them before any check,
  // with what a run killed outright left staged (its process is gone).
  std::error_code ec;
  std::vector<std::string> names(std::begin(kOutputs), std::end(kOutputs));
  if (fs::is_directory(out, ec)) {
    removeAbandonedOutputs(out, names);
    for (const char* name : kOutputs) {
      fs::remove(out / name, ec);
      if (ec && ec != std::errc::no_such_file_or_directory)
        throw std::invalid_argument(
            fmt::format("--out {}: cannot remove the old {}: {}", a.out, name, ec.message()));
    }
  }
  if (!a.vcd.empty()) {
    // The VCD likewise: an earlier run's (a regular file; nothing else is
    // touched) and what a killed run left staged.
    const fs::path vcd_file(rop::vcdFilePath(a.vcd));
    removeAbandonedOutputs(vcd_file.parent_path(), {vcd_file.filename().string()});
    if (fs::is_regular_file(fs::symlink_status(vcd_file, ec))) fs::remove(vcd_file, ec);
  }
  checkOptions(a);
  a.params.format = model::parseStorageFormat(a.format);
  const bool timing = a.mode == "timing";
  const MemoryBudget budget = parseMemoryBudget(a.memory_budget);
  // Resolve and validate the ROP configuration before any work, whatever the
  // mode, so a bad --preset, --config or --set fails at once and never passes
  // silently in functional mode (which does not use it).
  const rop::ConfigTree tree = rop::resolveTree(a.preset, a.config_file, a.sets);
  checkOrderingOptions(a.mode, a.seeds_given, a.seeds, &tree.config());
  if (!a.vcd.empty()) {
    try {
      rop::checkVcdWritable(a.vcd);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(fmt::format("--vcd {}: {}", a.vcd, e.what()));
    }
  }

  // The A-buffer under test takes its pool and local array from the ROP
  // configuration in both modes (the exact reference below does not).
  if (a.algo == "abuffer") a.params.abuffer = rop::abufferBudget(tree.config().abuffer);
  auto algo = model::makeAlgorithm(a.algo, a.params);  // algorithm, k and its limits: before the trace too
  auto src = openTraceWithSize(a.trace, a.width, a.height);  // header and size are validated here
  const TraceHeader& h = src->header();
  // A pool that cannot hold the frame's heads: one line naming abuffer.pool_bytes, before any work.
  const uint64_t pool_nodes =
      a.algo == "abuffer" ? model::capacityNodes(a.params.abuffer, h.width, h.height, algo->poolNodeBytes()) : 0;
  // The run's peak memory, phase by phase, against the budget: a frame that
  // cannot fit is refused before any work (RunMemory.hpp).
  RunShape shape;
  shape.width = h.width;
  shape.height = h.height;
  shape.fragments = h.fragment_count;
  shape.bytes_per_pixel = algo->bytesPerPixel();
  shape.pool_bytes_per_fragment = algo->poolBytesPerFragment();
  shape.timing = timing;
  if (timing)
    shape.timing_level_bytes = sharedLevelHostBytes(tree.config(), (shape.bytes_per_pixel + 8) * uint64_t(h.width) * h.height);
  shape.reference = a.reference == "abuffer" ? ReferenceKind::Exact
                    : a.reference == "none"  ? ReferenceKind::None
                                             : ReferenceKind::File;
  // An abuffer run that is exact itself (fp32 nodes, unlimited pool and
  // local array) is its own reference; otherwise the exact A-buffer is.
  shape.run_is_reference =
      a.algo == "abuffer" && a.params.format == model::StorageFormat::Fp32 && a.params.abuffer.unlimited();
  if (a.seeds_given) {
    shape.seeds = a.seeds;
    shape.seed_processes = std::min(rop::usableCores(), a.seeds);
  }
  // The A-buffer under test holds transparent fragments only: a quick pass
  // counts them, for its reservation and the estimate (the record count would
  // refuse a frame with many opaque ones). The reference's bands need no count
  // here (they count what reaches them); its estimate takes the record count.
  // A preallocated pool holds no more than its nodes (the rest are dropped).
  if (shape.pool_bytes_per_fragment > 0) shape.fragments = std::min(transparentFragments(*src), pool_nodes);
  const RunMemoryEstimate mem = estimateRunMemory(shape, residentBytes(), budget.bytes);
  checkRunFitsBudget(mem, budget, a.trace, shape, a.algo);
  if (shape.reference == ReferenceKind::File) checkReferenceFile(a.reference, h.width, h.height);
  a.out_of_memory = outOfMemoryMessage(mem, budget, a.trace, shape, a.algo);
  algo->reservePool(shape.pool_bytes_per_fragment > 0 ? shape.fragments : 0);
  const model::Rgb clear{a.background[0], a.background[1], a.background[2]};

  TimedRender run;
  nlohmann::json timing_stats;
  SeedRuns seed_runs;
  // SystemC writes the VCD while it runs: under a staged name (ending in
  // ".vcd", which SystemC would append), renamed with the other outputs.
  StagedOutputs staged;
  const std::string vcd_staged = a.vcd.empty() ? std::string() : staged.stage(rop::vcdFilePath(a.vcd), ".vcd");
  if (timing) {
    Progress progress(a.algo + " (timing)", !a.quiet);
    rop::TimingOptions to;
    to.clear_colour = clear;
    to.vcd_path = vcd_staged;
    to.progress = [&](double fraction, const std::string& what) { progress.update(fraction, what); };
    rop::TimingResult t = a.seeds_given ? seed_runs.run(a.trace, a.width, a.height, a.algo, a.params, a.seeds,
                                                        tree.config(), to, progress)
                                        : rop::runTiming(*src, *algo, tree.config(), to);
    progress.finish();
    run.result.image = std::move(t.image);
    run.result.counts = t.counts;
    run.result.state_bytes = uint64_t(h.width) * h.height * algo->bytesPerPixel() + t.pool_bytes;
    run.wall_seconds = t.wall_seconds;
    timing_stats = std::move(t.stats);
  } else {
    run = renderWith(*src, *algo, clear, !a.quiet, a.algo);
  }
  // The reference is the exact A-buffer (unlimited pool and local array, fp32
  // nodes) whatever the algorithm under test: the run itself when it is that,
  // else built in bands that fit the memory the rest of the run needs anyway;
  // or a file, or none.
  TimedRender ref;
  unsigned ref_bands = 0;
  uint64_t band_file_bytes = 0;
  if (shape.reference == ReferenceKind::Exact && shape.run_is_reference) {
    ref = run;
  } else if (shape.reference == ReferenceKind::Exact) {
    // The band file (several bands only) goes beside the outputs: the
    // --out folder, or the nearest folder of its path that exists.
    fs::path spill = fs::absolute(out, ec);
    while (!spill.empty() && !fs::is_directory(spill, ec) && spill != spill.parent_path()) spill = spill.parent_path();
    model::BandedRender b =
        renderReference(*src, clear, mem.reference_band_bytes, spill.string(), !a.quiet, ref.wall_seconds);
    ref.result = std::move(b.result);
    ref_bands = b.bands;
    band_file_bytes = b.spill_bytes;
  } else if (shape.reference == ReferenceKind::File) {
    const auto t0 = std::chrono::steady_clock::now();
    ref.result.image = readReferenceFile(a.reference);
    ref.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  const bool compared = shape.reference != ReferenceKind::None;
  const model::ImageMetrics m = compared ? model::compareImages(run.result.image, ref.result.image) : model::ImageMetrics{};
  const model::FlipMap flip =
      compared ? model::ldrFlip(model::toSrgb8Image(ref.result.image), model::toSrgb8Image(run.result.image), a.ppd)
               : model::FlipMap{};
  const model::RenderCounts& c = run.result.counts;
  if (!c.balanced())
    throw std::logic_error(fmt::format("fragment outcomes do not sum to fragments in ({} != {} + {} + {} + {} + {})",
                                       c.fragments_in, c.opaque, c.culled, c.stored, c.merged, c.discarded));

  nlohmann::json j;
  j["schema"] = reports::kReportSchema;
  j["oitsim"] = {{"version", OITSIM_VERSION}, {"command", a.command_line}};
  nlohmann::json draws = nlohmann::json::array();
  for (const DrawInfo& d : h.draws) draws.push_back({{"id", d.id}, {"name", d.name}, {"class", toString(d.cls)}});
  j["trace"] = {{"path", a.trace},       {"width", h.width},        {"height", h.height},
                {"fragments", h.fragment_count}, {"encoding", toString(h.encoding)}, {"draws", draws}};
  if (h.camera) j["trace"]["camera"] = {{"near", h.camera->near_plane}, {"far", h.camera->far_plane}};
  j["config"] = {{"mode", a.mode},
                 {"algorithm", a.algo},
                 {"layers", a.params.layers},
                 {"format", model::toString(a.params.format)},
                 {"bits", a.params.bits},
                 {"samples", a.params.samples},
                 {"weight", a.params.weight},
                 {"seed", a.params.seed},
                 {"background", a.background},
                 {"ignored_settings", model::ignoredSettings(a.algo)}};
  if (!algo->bounded()) {
    const model::ABufferBudget& b = a.params.abuffer;
    const uint64_t cap = algo->poolCapacityNodes();
    j["config"]["abuffer"] = {{"pool_bytes", b.pool_bytes},
                              {"nodes_per_pixel", b.nodes_per_pixel},
                              {"pool_nodes", cap == UINT64_MAX ? 0 : cap},  // 0: unlimited
                              {"node_bytes", algo->poolNodeBytes()},
                              {"max_sorted", b.max_sorted},
                              {"overflow", b.overflow == model::ABufferOverflow::Truncate ? "truncate" : "spill"}};
  }
  nlohmann::json passes = nlohmann::json::array();
  for (unsigned p = 0; p < c.pass_outcomes.size(); ++p)
    passes.push_back({{"name", std::string(algo->passName(p))},
                      {"stored", c.pass_outcomes[p][0]},
                      {"merged", c.pass_outcomes[p][1]},
                      {"discarded", c.pass_outcomes[p][2]}});
  j["fragments"] = {{"in", c.fragments_in},       {"opaque", c.opaque},   {"culled_by_depth", c.culled},
                    {"stored", c.stored},         {"merged", c.merged},   {"discarded", c.discarded},
                    {"dropped_pool_full", algo->bounded() ? 0 : c.discarded},
                    {"outcomes_sum_to_in", c.balanced()}, {"passes", passes}};
  // Draws of blend modes the model does not blend (v2): counted, not replayed.
  const UnmodelledDraws unmodelled = unmodelledDraws(h.draws);
  nlohmann::json by_mode = nlohmann::json::object();
  for (size_t mode = 0; mode < UnmodelledDraws::kModes; ++mode)
    if (unmodelled.draws_by_mode[mode])
      by_mode[toString(static_cast<BlendMode>(mode))] = {{"draws", unmodelled.draws_by_mode[mode]},
                                                         {"fragments", unmodelled.fragments_by_mode[mode]}};
  j["fragments"]["not_modelled"] = {
      {"draws", unmodelled.draws}, {"fragments", unmodelled.fragments}, {"by_blend_mode", by_mode}};
  j["memory"] = {{"bytes_per_pixel", algo->bytesPerPixel()},
                 {"state_bytes", run.result.state_bytes},
                 {"state_read_bytes", c.bytes_read},
                 {"state_write_bytes", c.bytes_written},
                 {"source_passes", c.source_passes}};
  j["image"] = {{"files", {{"image_png", "image.png"}, {"image_pfm", "image.pfm"}}},
                {"reference", shape.reference == ReferenceKind::File ? "file" : a.reference},
                {"order", imageOrder(a.mode, tree.config())}};
  if (compared) {
    j["image"]["files"]["reference_pfm"] = "reference.pfm";
    j["image"]["files"]["diff_png"] = "diff.png";
    j["image"]["files"]["flip_png"] = "flip.png";
    j["image"]["metrics"] = metricsJson(m);
    j["image"]["metrics"]["flip"] = flipJson(flip, a.ppd);
  }
  if (shape.reference == ReferenceKind::File) j["image"]["reference_file"] = a.reference;
  model::Image flicker;
  if (a.seeds_given) flicker = seed_runs.addFlicker(j, ref.result.image);
  j["sim"] = {{"wall_seconds", run.wall_seconds},
              {"fragments_per_second", run.wall_seconds > 0.0 ? double(c.fragments_in) / run.wall_seconds : 0.0},
              {"reference_wall_seconds", ref.wall_seconds}};
  // Machine-dependent (the budget's default is a share of this machine's
  // memory) and measured: like the wall clock, not part of the deterministic report.
  j["sim"]["memory"] = {{"budget_bytes", budget.bytes},
                        {"estimate_bytes", mem.peak()},
                        {"estimate_phase", mem.peakPhase().name},
                        {"reference_bands", ref_bands},
                        {"reference_band_file_bytes", band_file_bytes}};
  if (timing) {
    j["config"]["rop"] = tree.toJson();
    // The timing model's sections; its fragment and memory sections extend the
    // functional ones (same outcome counts: the functional insert decides them).
    for (auto it = timing_stats.begin(); it != timing_stats.end(); ++it) {
      if (it.key() == "fragments" || it.key() == "memory") {
        for (auto f = it.value().begin(); f != it.value().end(); ++f) j[it.key()][f.key()] = f.value();
      } else {
        j[it.key()] = it.value();
      }
    }
    if (!a.vcd.empty()) j["files"]["vcd"] = rop::vcdFilePath(a.vcd);  // SystemC appends .vcd
  }
  reports::requireFinite(j);

  // Everything is known: stage every file, then rename them together (the
  // report last), so a failure or an interrupt leaves no partial set.
  fs::create_directories(out, ec);
  if (ec) throw std::runtime_error(fmt::format("--out {}: cannot create the folder: {}", a.out, ec.message()));
  model::writePng(run.result.image, staged.stage(out / "image.png"));
  model::writePfm(run.result.image, staged.stage(out / "image.pfm"));
  if (compared) {
    model::writePfm(ref.result.image, staged.stage(out / "reference.pfm"));
    model::writePng(model::differenceImage(run.result.image, ref.result.image, 4.0f), staged.stage(out / "diff.png"));
    model::writeFlipPng(flip, staged.stage(out / "flip.png"));
  }
  if (a.seeds_given) model::writePng(flicker, staged.stage(out / "flicker.png"));
  const uint64_t peak_rss = peakResidentBytes();  // every image written: only the report is left
  j["sim"]["memory"]["peak_rss_bytes"] = peak_rss;
  reports::writeJsonReport(staged.stage(out / "report.json"), j);
  staged.commit();

  if (a.quiet) return;
  fmt::print("trace       {}: {} x {}, {} fragments ({} opaque), {}\n", a.trace, h.width, h.height,
             c.fragments_in, c.opaque, counted(h.draws.size(), "draw", "draws"));
  fmt::print("algorithm   {}, mode {}{}, {} over the trace\n", algorithmWithSettings(a.algo, a.params), a.mode,
             timing ? ", preset " + tree.config().preset : "", counted(c.source_passes, "pass", "passes"));
  fmt::print("fragments   culled by depth {}, stored {}, merged {}, discarded {}\n", c.culled, c.stored,
             c.merged, c.discarded);
  if (unmodelled.draws)
    fmt::print("not modelled {}; blend modes the model does not blend: their fragments are in no record, not in the "
               "image nor the reference\n", unmodelled.describe());
  // The inserts' read-modify-writes at the ROP, not DRAM traffic (that is the
  // timing summary's dram line); the A-buffer's pool nodes count at
  // poolNodeBytes() each, as in the footprint.
  fmt::print("memory      {} B/pixel, {} of per-pixel state{}; inserts read {} and write {} of it on chip (not DRAM)\n",
             algo->bytesPerPixel(), humanBytes(double(run.result.state_bytes)),
             algo->bounded() ? std::string()
                             : fmt::format(" (heads + pool of {} B nodes)", algo->poolNodeBytes()),
             humanBytes(double(c.bytes_read)), humanBytes(double(c.bytes_written)));
  if (!algo->bounded() && c.discarded != 0)
    fmt::print("            pool full: {} fragments dropped (abuffer.pool_bytes)\n", c.discarded);
  fmt::print("resident    peak {} (estimated {}, budget {}){}\n", humanBytes(double(peak_rss)),
             humanBytes(double(mem.peak())), humanBytes(double(budget.bytes)),
             ref_bands > 1 ? fmt::format("; reference in {} bands ({} band file)", ref_bands,
                                         humanBytes(double(band_file_bytes)))
                           : std::string());
  if (timing) printTimingSummary(j);
  if (!compared) {
    fmt::print("image       no reference (--reference none): no error metrics, no reference.pfm, diff.png or flip.png\n");
  } else {
    fmt::print("image       vs {}: RMSE {:.6f}, PSNR {:.2f} dB, SSIM {:.5f}, max |err| {:.5f}, {} px > 1/255\n",
               shape.reference == ReferenceKind::File ? a.reference : "abuffer", m.rmse, m.psnr, m.ssim, m.max_abs,
               m.pixels_over_1_255);
    fmt::print("            FLIP at {:.2f} px/degree: mean {:.5f}, weighted median {:.5f}, max {:.5f} (flip.png)\n",
               a.ppd, flip.stats.mean, flip.stats.weighted_median, flip.stats.max);
  }
  if (a.seeds_given) printFlicker(j["image"]["flicker"]);
  fmt::print("speed       {:.3f} s, {} fragments/s{}\n", run.wall_seconds,
             humanCount(run.wall_seconds > 0.0 ? double(c.fragments_in) / run.wall_seconds : 0.0),
             compared ? fmt::format(" (reference {:.3f} s)", ref.wall_seconds) : std::string());
  fmt::print("report      {}\n", (out / "report.json").string());
}

}  // namespace oit::cli
