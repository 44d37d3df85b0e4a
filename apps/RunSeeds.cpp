#include "apps/RunSeeds.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "apps/Commands.hpp"
#include "model/Flicker.hpp"
#include "oit_rop/ChildRuns.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "reports/FlickerReport.hpp"

namespace oit::cli {

void checkOrderingOptions(const std::string& mode, bool seeds_given, unsigned seeds, const rop::RopConfig* cfg) {
  if (seeds_given && seeds == 0)
    throw std::invalid_argument("--seeds 0: expected the number of shader-latency seeds to run, at least 1");
  if (seeds_given && mode != "timing")
    throw std::invalid_argument(fmt::format(
        "--seeds {}: flicker across shader-latency seeds needs the timing model; drop --mode {} (the default is "
        "timing)",
        seeds, mode));
  if (cfg && mode != "timing" && cfg->lock.mode != rop::LockMode::Ordered)
    throw std::invalid_argument(fmt::format(
        "lock.mode={} needs the timing model (its image follows the order the timing run lets fragments into "
        "the lock); --mode {} inserts in submission order, which is lock.mode=ordered",
        rop::lockModeName(cfg->lock.mode), mode));
}

const char* imageOrder(const std::string& mode, const rop::RopConfig& cfg) {
  if (mode != "timing") return "submission";
  switch (cfg.lock.mode) {
    case rop::LockMode::Ordered: return "submission";
    case rop::LockMode::Unordered: return "lock_entry";
    case rop::LockMode::None: return "race";
  }
  return "submission";
}

rop::TimingResult SeedRuns::run(const std::string& trace, uint32_t width, uint32_t height, const std::string& algo,
                                const model::AlgorithmParams& params, unsigned seeds, const rop::RopConfig& cfg,
                                const rop::TimingOptions& options, Progress& progress) {
  rop::SeedRunsRequest rq;
  rq.cfg = cfg;
  rq.seeds = seeds;
  rq.options = options;
  rq.open_trace = [&] { return openTraceWithSize(trace, width, height); };
  rq.make_algorithm = [&] { return model::makeAlgorithm(algo, params); };
  rq.progress = [&](double f) { progress.update(f, fmt::format("{} seeds", seeds)); };
  std::vector<rop::TimingResult> runs = rop::runTimingSeeds(rq);
  for (size_t i = 0; i < runs.size(); ++i) {
    // Seed 0's image is also the run's own (returned below): copied; the others moved.
    images.push_back(i == 0 ? runs[i].image : std::move(runs[i].image));
    input_seeds.push_back(cfg.input.seed + i);
    stats.push_back(runs[i].stats);
  }
  return std::move(runs[0]);
}

model::Image SeedRuns::addFlicker(nlohmann::json& report, const model::Image& reference) const {
  model::FlickerMetrics fm = model::measureFlicker(images, reference, reports::kFlickerPngScale);
  report["image"]["flicker"] = reports::flickerJson(fm, input_seeds, stats, "flicker.png");
  report["image"]["files"]["flicker_png"] = "flicker.png";
  return std::move(fm.image);
}

void printFlicker(const nlohmann::json& f) {
  fmt::print("flicker     {} seeds: per-pixel std {:.3f} mean, {:.2f} max sRGB8 levels; {:.4f} % of pixels differ; "
             "RMSE {:.6f} mean, {:.6f} worst; {} - {} cycles\n",
             f["seeds"].get<unsigned>(), f["std_mean"].get<double>(), f["std_max"].get<double>(),
             100.0 * f["differing_fraction"].get<double>(), f["rmse_mean"].get<double>(),
             f["rmse_worst"].get<double>(), f["cycles_min"].get<uint64_t>(), f["cycles_max"].get<uint64_t>());
}

}  // namespace oit::cli
