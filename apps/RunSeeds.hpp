// `oitsim run`'s ordering options: --seeds N (the frame replayed with N
// shader-latency seeds in child processes, oit_rop/ChildRuns.hpp, and the
// flicker across them, model/Flicker.hpp) and lock.mode against --mode. Kept
// apart from RunReplay.cpp, which calls these.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "apps/Progress.hpp"
#include "model/Image.hpp"
#include "model/OitAlgorithm.hpp"
#include "oit_rop/TimingRun.hpp"

namespace oit::cli {

// Throws std::invalid_argument (one line naming the option) for --seeds 0,
// --seeds outside timing mode and, once the ROP configuration is resolved
// (`cfg` not null), lock.mode unordered or none in functional mode (the
// functional model inserts in submission order, which is lock.mode=ordered).
void checkOrderingOptions(const std::string& mode, bool seeds_given, unsigned seeds,
                          const rop::RopConfig* cfg = nullptr);

// report.json's image.order: the order of each pixel's inserts that made the image.
const char* imageOrder(const std::string& mode, const rop::RopConfig& cfg);

// Every seed's image and stats, in seed order (input.seed, +1, ...).
struct SeedRuns {
  std::vector<model::Image> images;
  std::vector<uint64_t> input_seeds;
  std::vector<nlohmann::json> stats;

  // The frame with `seeds` seeds, on every core; returns seed 0's run (the
  // main image and report) and keeps every seed's image and stats.
  rop::TimingResult run(const std::string& trace, uint32_t width, uint32_t height, const std::string& algo,
                        const model::AlgorithmParams& params, unsigned seeds, const rop::RopConfig& cfg,
                        const rop::TimingOptions& options, Progress& progress);
  // Adds image.flicker (and image.files.flicker_png) to the report and
  // returns flicker.png's image.
  model::Image addFlicker(nlohmann::json& report, const model::Image& reference) const;
};

// The summary line of image.flicker.
void printFlicker(const nlohmann::json& flicker);

}  // namespace oit::cli
