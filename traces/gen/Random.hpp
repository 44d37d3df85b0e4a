// The generators' own PRNG, so a seed gives the same trace on every platform:
// std:: distributions are implementation-defined and would not.
//
// Xoshiro256** (Blackman & Vigna), state filled by SplitMix64 from
// seed ^ FNV-1a(stream name): every draw uses its own named stream, so adding or
// removing one draw (e.g. the backdrop) leaves the others' geometry unchanged.
// Floats come from the top bits of a 64-bit output (exact, no rounding up to 1).
#pragma once

#include <cstdint>
#include <string_view>

namespace oit::gen {

inline uint64_t splitmix64(uint64_t& state) {
  uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

inline uint64_t fnv1a64(std::string_view s) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : s) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  return h;
}

class Rng {
 public:
  explicit Rng(uint64_t seed, std::string_view stream = {}) {
    uint64_t sm = seed ^ fnv1a64(stream);
    for (uint64_t& w : s_) w = splitmix64(sm);
  }

  uint64_t next() {
    const uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  // [0, 1) with 53 random bits.
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  // [lo, hi)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  float uniformf(double lo, double hi) { return static_cast<float>(uniform(lo, hi)); }

  // Uniform integer in [0, n), n > 0; rejection keeps it unbiased.
  uint64_t below(uint64_t n) {
    const uint64_t limit = ~uint64_t{0} - (~uint64_t{0} % n);
    uint64_t x;
    do x = next();
    while (x >= limit);
    return x % n;
  }

 private:
  static uint64_t rotl(uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  uint64_t s_[4];
};

}  // namespace oit::gen
