#include "oit_rop/ShaderInput.hpp"

#include <stdexcept>

namespace oit::rop {

namespace {
uint64_t mix64(uint64_t z) {  // splitmix64 finaliser
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}
}  // namespace

ShaderInput::ShaderInput(const InputConfig& cfg)
    : cfg_(cfg), rate_(cfg.fragments_per_clock), wheel_(std::max(cfg.latency_min, cfg.latency_max) + 2) {
  if (cfg.latency_model == LatencyModel::Uniform && cfg.latency_max < cfg.latency_min)
    throw std::invalid_argument("input.latency_max must be >= input.latency_min");
  fixed_ = cfg.latency_model == LatencyModel::Fixed || cfg.latency_max == cfg.latency_min;
  span_ = fixed_ ? 1 : uint64_t(cfg.latency_max - cfg.latency_min) + 1;
}

unsigned ShaderInput::latencyOf(uint64_t seq, unsigned pass) const {
  // A fragment leaves the shader at least one cycle after it entered.
  if (cfg_.latency_model == LatencyModel::Fixed || cfg_.latency_max == cfg_.latency_min)
    return std::max(1u, cfg_.latency_min);
  const uint64_t h = mix64(mix64(cfg_.seed ^ (uint64_t(pass) << 56)) ^ seq);
  const uint64_t span = uint64_t(cfg_.latency_max - cfg_.latency_min) + 1;
  return std::max(1u, cfg_.latency_min + unsigned(h % span));
}

void ShaderInput::issue(Cycle now, uint32_t token, uint64_t seq, unsigned pass) {
  rate_.take();
  unsigned lat;
  if (fixed_) {
    lat = std::max(1u, cfg_.latency_min);
  } else {
    // latencyOf() with the per-pass half of the hash computed once per pass.
    if (pass != mix_pass_) {
      mix_pass_ = pass;
      pass_mix_ = mix64(cfg_.seed ^ (uint64_t(pass) << 56));
    }
    lat = std::max(1u, cfg_.latency_min + unsigned(mix64(pass_mix_ ^ seq) % span_));
  }
  wheel_.schedule(now + lat, token);
  ++issued_;
}

}  // namespace oit::rop
