// The `image.flicker` section of report.json (reports/REPORT.md): flicker
// across the shader-latency seeds of `oitsim run --seeds N`.
#pragma once

#include <nlohmann/json.hpp>

#include <cstdint>
#include <string>
#include <vector>

#include "model/Flicker.hpp"

namespace oit::reports {

// Fixed, so flicker.png files compare across runs: PNG code = min(255, 8 x
// the per-pixel standard deviation in sRGB8 levels).
inline constexpr double kFlickerPngScale = 8.0;

// `seeds`: each seed run's input.seed and its report's stats (timing, lock
// sections), in seed order, as measured by `m`.
nlohmann::json flickerJson(const model::FlickerMetrics& m, const std::vector<uint64_t>& input_seeds,
                           const std::vector<nlohmann::json>& seed_stats, const std::string& png_file);

}  // namespace oit::reports
