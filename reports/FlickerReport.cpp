#include "reports/FlickerReport.hpp"

#include <algorithm>
#include <stdexcept>

namespace oit::reports {

nlohmann::json flickerJson(const model::FlickerMetrics& m, const std::vector<uint64_t>& input_seeds,
                           const std::vector<nlohmann::json>& seed_stats, const std::string& png_file) {
  if (input_seeds.size() != m.images || seed_stats.size() != m.images || m.errors.size() != m.images)
    throw std::logic_error("flickerJson: one seed, stats and error per image");
  nlohmann::json per_seed = nlohmann::json::array();
  uint64_t cycles_min = UINT64_MAX, cycles_max = 0;
  double cycles_sum = 0;
  for (size_t i = 0; i < m.images; ++i) {
    const nlohmann::json& s = seed_stats[i];
    const uint64_t cycles = s.at("timing").at("cycles");
    cycles_min = std::min(cycles_min, cycles);
    cycles_max = std::max(cycles_max, cycles);
    cycles_sum += double(cycles);
    per_seed.push_back({{"input_seed", input_seeds[i]},
                        {"rmse", m.errors[i].rmse},
                        {"psnr", m.errors[i].psnr},
                        {"cycles", cycles},
                        {"lock_wait_cycles", s.at("lock").at("wait_cycles")},
                        {"lost_updates", s.at("lock").at("lost_updates")}});
  }
  return {{"seeds", m.images},
          {"std_mean", m.mean_std},
          {"std_max", m.max_std},
          {"differing_pixels", m.differing_pixels},
          {"differing_fraction", m.differing_fraction},
          {"rmse_mean", m.rmse_mean},
          {"rmse_worst", m.rmse_worst},
          {"cycles_mean", m.images ? cycles_sum / m.images : 0.0},
          {"cycles_min", m.images ? cycles_min : 0},
          {"cycles_max", cycles_max},
          {"per_seed", per_seed},
          {"png", png_file},
          {"png_scale", kFlickerPngScale}};
}

}  // namespace oit::reports
