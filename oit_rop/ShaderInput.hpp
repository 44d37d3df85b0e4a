// ShaderInput: fragments routed to this partition enter the pixel shader at
// input.fragments_per_clock and leave it after a latency that is Fixed
// (latency_min) or Uniform[min, max] drawn from a seeded hash of the
// fragment's sequence number (deterministic, no global RNG), so shaded
// fragments reach the PixelLock out of submission order. A timing wheel holds
// the fragments in flight (no heap). Issue needs a scoreboard entry: the
// partition stalls issue with "scoreboard full" when none is free.
#pragma once

#include <cstdint>

#include "oit_rop/PipelineQueues.hpp"
#include "oit_rop/RopConfig.hpp"

namespace oit::rop {

class ShaderInput {
 public:
  explicit ShaderInput(const InputConfig& cfg);

  // Pixel-shader latency of the fragment with sequence number `seq` in `pass`.
  unsigned latencyOf(uint64_t seq, unsigned pass) const;
  // How many fragments may issue at `now` (input rate); take one per issue().
  unsigned slots(Cycle now) { return rate_.available(now); }
  void issue(Cycle now, uint32_t token, uint64_t seq, unsigned pass);
  // Calls f(token) for each fragment whose shader finishes at `now`.
  template <class F>
  void finished(Cycle now, F&& f) {
    wheel_.drain(now, f);
  }
  Cycle nextFinish(Cycle now) const { return wheel_.nextDue(now); }
  Cycle nextSlot(Cycle now) const { return rate_.nextAvailable(now); }
  size_t inShader() const { return wheel_.size(); }
  uint64_t issued() const { return issued_; }

 private:
  InputConfig cfg_;
  RateLimiter rate_;
  TimingWheel wheel_;
  uint64_t issued_ = 0;
  bool fixed_ = true;
  uint64_t span_ = 1;                    // latency_max - latency_min + 1
  unsigned mix_pass_ = ~0u;              // pass whose hash half is in pass_mix_
  uint64_t pass_mix_ = 0;
};

}  // namespace oit::rop
