// A small deterministic random source for the randomised reference tests of
// the timing model's building blocks: a 64-bit LCG (Knuth's MMIX constants),
// so every standard library gives the same sequence (std::uniform_* does not).
#pragma once

#include <cstdint>

namespace oit::rop::testutil {

struct TestLcg {
  uint64_t x;      // state (the seed)
  unsigned shift;  // which high bits a draw uses
  // Uniform-ish in [0, n).
  uint64_t operator()(uint64_t n) {
    x = x * 6364136223846793005ull + 1442695040888963407ull;
    return (x >> shift) % n;
  }
};

}  // namespace oit::rop::testutil
