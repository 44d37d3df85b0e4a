// `oitsim run`'s report sections and summary lines built from measured
// values: the error metrics and FLIP as report.json objects, the algorithm
// with the settings it uses, and the timing summary printed from the report.
#pragma once

#include <nlohmann/json.hpp>

#include <string>

#include "model/Flip.hpp"
#include "model/Metrics.hpp"
#include "model/OitAlgorithm.hpp"

namespace oit::cli {

// image.metrics: the error metrics against the reference.
nlohmann::json metricsJson(const model::ImageMetrics& m);
// image.metrics.flip: LDR-FLIP's pooled values and the viewing condition.
nlohmann::json flipJson(const model::FlipMap& f, double ppd);
// "mlab (k=4, format fp32)": only the settings the algorithm uses
// (model/AlgorithmSettings.hpp); "abuffer" alone.
std::string algorithmWithSettings(const std::string& algo, const model::AlgorithmParams& p);
// Cycles, frame time, root causes, utilisation, stalls by cause, DRAM bytes,
// traffic against compulsory, footprint, lock and cache, from the report `j`.
void printTimingSummary(const nlohmann::json& j);

}  // namespace oit::cli
