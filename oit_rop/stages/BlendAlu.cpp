#include "oit_rop/stages/BlendAlu.hpp"

#include <algorithm>
#include <stdexcept>

namespace oit::rop {

BlendAlu::BlendAlu(const AluConfig& cfg, double format_rate)
    : cfg_(cfg), rate_(double(cfg.blends_per_clock) * format_rate) {
  if (cfg.blends_per_clock == 0) throw std::invalid_argument("alu.blends_per_clock must be > 0");
}

double BlendAlu::formatRate(const AluConfig& cfg, const model::StateLayout& layout) {
  switch (layout.format) {
    case model::StorageFormat::Rgba8T8Z32: return 1.0;
    case model::StorageFormat::Fp16: return cfg.fp16_rate;
    case model::StorageFormat::Fp32: return cfg.fp32_rate;
  }
  return 1.0;
}

}  // namespace oit::rop
