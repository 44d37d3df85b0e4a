#include "oit_rop/ShaderInput.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

namespace oit::rop {

ShaderInput::ShaderInput(const InputConfig& cfg)
    : cfg_(cfg), rate_(cfg.fragments_per_clock), wheel_(std::max(cfg.latency_min, cfg.latency_max) + 2) {
  if (cfg.latency_model == LatencyModel::Uniform && cfg.latency_max < cfg.latency_min)
    throw std::invalid_argument("input.latency_max must be >= input.latency_min");
  fixed_ = cfg.latency_model == LatencyModel::Fixed || cfg.latency_max == cfg.latency_min;
  span_ = fixed_ ? 1 : uint64_t(cfg.latency_max - cfg.latency_min) + 1;
  span_inv_ = ~uint64_t(0) / span_;  // floor((2^64 - 1) / span_) = floor(2^64 / span_) unless span_ | 2^64
  fixed_lat_ = std::max(1u, cfg.latency_min);
  if (!std::has_single_bit(cfg.warp_size))
    throw std::invalid_argument("input.warp_size must be a power of two");
  warp_shift_ = unsigned(std::countr_zero(cfg.warp_size));
}

unsigned ShaderInput::latencyOf(uint64_t seq, unsigned pass) const {
  // A fragment leaves the shader at least one cycle after it entered.
  if (cfg_.latency_model == LatencyModel::Fixed || cfg_.latency_max == cfg_.latency_min)
    return std::max(1u, cfg_.latency_min);
  // The fragments of one warp (warp_size consecutive sequence numbers) share the draw.
  const uint64_t h = mix64(mix64(cfg_.seed ^ (uint64_t(pass) << 56)) ^ (seq >> warp_shift_));
  const uint64_t span = uint64_t(cfg_.latency_max - cfg_.latency_min) + 1;
  return std::max(1u, cfg_.latency_min + unsigned(h % span));
}

}  // namespace oit::rop
