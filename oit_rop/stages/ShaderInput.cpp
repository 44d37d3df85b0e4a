#include "oit_rop/stages/ShaderInput.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

namespace oit::rop {

ShaderInput::ShaderInput(const InputConfig& cfg)
    : cfg_(cfg), rate_(cfg.fragments_per_clock), wheel_(std::max(cfg.latency_min, cfg.latency_max) + 2) {
  if (cfg.latency_model == LatencyModel::Uniform && cfg.latency_max < cfg.latency_min)
    throw std::invalid_argument("input.latency_max must be >= input.latency_min");
  draw_.fixed = cfg.latency_model == LatencyModel::Fixed || cfg.latency_max == cfg.latency_min;
  draw_.span = draw_.fixed ? 1 : uint64_t(cfg.latency_max - cfg.latency_min) + 1;
  draw_.span_inv = ~uint64_t(0) / draw_.span;  // floor((2^64 - 1) / span) = floor(2^64 / span) unless span | 2^64
  draw_.fixed_lat = std::max(1u, cfg.latency_min);
  draw_.min = cfg.latency_min;
  if (!std::has_single_bit(cfg.warp_size))
    throw std::invalid_argument("input.warp_size must be a power of two");
  draw_.warp_shift = unsigned(std::countr_zero(cfg.warp_size));
}

unsigned ShaderInput::latencyOf(uint64_t seq, unsigned pass) const {
  // A fragment leaves the shader at least one cycle after it entered.
  if (cfg_.latency_model == LatencyModel::Fixed || cfg_.latency_max == cfg_.latency_min)
    return std::max(1u, cfg_.latency_min);
  // The fragments of one warp (warp_size consecutive sequence numbers) share the draw.
  const uint64_t h = mix64(mix64(cfg_.seed ^ (uint64_t(pass) << 56)) ^ (seq >> draw_.warp_shift));
  const uint64_t span = uint64_t(cfg_.latency_max - cfg_.latency_min) + 1;
  return std::max(1u, cfg_.latency_min + unsigned(h % span));
}

}  // namespace oit::rop
