// ShaderInput: fragments routed to this partition enter the pixel shader at
// input.fragments_per_clock and leave it after a latency that is Fixed
// (latency_min) or Uniform[min, max] drawn from a seeded hash of the
// fragment's sequence number (deterministic, no global RNG), so shaded
// fragments reach the PixelLock out of submission order. The uniform draw is
// per warp: input.warp_size consecutive sequence numbers share one latency. A
// timing wheel holds the fragments in flight (no heap). Issue needs a
// scoreboard entry: the partition stalls issue with "scoreboard full" when
// none is free.
#pragma once

#include <algorithm>
#include <cstdint>

#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

class ShaderInput {
 public:
  __extension__ typedef unsigned __int128 U128;  // GCC/Clang extension (mulx)
  explicit ShaderInput(const InputConfig& cfg);

  // Pixel-shader latency of the fragment with sequence number `seq` in `pass`
  // (uniform model: drawn for its warp, seq >> log2(warp_size)).
  unsigned latencyOf(uint64_t seq, unsigned pass) const;
  // How many fragments may issue at `now` (input rate); take one per issue().
  unsigned slots(Cycle now) { return rate_.available(now); }
  void issue(Cycle now, uint32_t token, uint64_t seq, unsigned pass) {  // inline: once per fragment
    rate_.take();
    wheel_.schedule(now + latency(seq, pass), token);
    ++issued_;
  }
  // latencyOf() with the per-pass half of the hash computed once per pass
  // (inline: once per fragment).
  unsigned latency(uint64_t seq, unsigned pass) {
    if (draw_.fixed) return draw_.fixed_lat;
    if (pass != mix_pass_) newPass(pass);
    return draw_(seq);
  }
  // The draw of one pass as a value, latency(seq, pass) = draw(pass)(seq):
  // the approximate engine keeps it in registers for the pass. (latency()
  // tests `fixed` first itself: 0.3 % fewer instructions in the cycle engine.)
  struct Draw {
    bool fixed = true;
    unsigned fixed_lat = 1, min = 0, warp_shift = 0;
    uint64_t pass_mix = 0, span = 1;
    // h % span without a 64-bit division (it was the costliest instruction of
    // the issue): with M = span_inv = floor((2^64 - 1) / span) >= 2^64 / span - 1,
    // h M / 2^64 lies in (h / span - 1, h / span], so q = mulhi(h, M) is
    // floor(h / span) or one below it and one select gives the exact remainder.
    // (A loop there mispredicted: with span 81 about a third of the draws need
    // the correction, at random.)
    uint64_t span_inv = 0;
    unsigned operator()(uint64_t seq) const {
      if (fixed) return fixed_lat;
      const uint64_t h = mix64(pass_mix ^ (seq >> warp_shift));
      const uint64_t q = uint64_t(U128(h) * span_inv >> 64);
      uint64_t r = h - q * span;
      r -= r >= span ? span : 0;
      return std::max(1u, min + unsigned(r));
    }
  };
  Draw draw(unsigned pass) {
    if (!draw_.fixed && pass != mix_pass_) newPass(pass);
    return draw_;
  }
  static uint64_t mix64(uint64_t z) {  // splitmix64 finaliser
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
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
  Draw draw_;                // fixed model, or the uniform model's draw of pass mix_pass_
  unsigned mix_pass_ = ~0u;  // pass whose hash half is in draw_.pass_mix
  [[gnu::cold, gnu::noinline]] void newPass(unsigned pass) {  // once per pass: out of the inlined issue()
    mix_pass_ = pass;
    draw_.pass_mix = mix64(cfg_.seed ^ (uint64_t(pass) << 56));
  }
};

}  // namespace oit::rop
