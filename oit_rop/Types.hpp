// Payload and counter types shared by the stages of the timing model.
#pragma once

#include <array>
#include <cstdint>

namespace oit::rop {

using Cycle = uint64_t;  // core-clock cycles since the start of the frame
inline constexpr Cycle kNever = ~Cycle(0);

// Memory surfaces the ROP touches; DRAM bytes are split by these.
enum class Surface : uint8_t { BlendArrays = 0, Depth = 1, Colour = 2, Resolve = 3 };
inline constexpr unsigned kSurfaceCount = 4;
const char* toString(Surface s);

// Bits set in a sector mask; one sector (no sectors: a whole line) without a
// call (the build targets plain x86-64, where popcount is a library call).
inline uint32_t sectorCount(uint32_t mask) {
  return (mask & (mask - 1)) == 0 ? (mask != 0) : uint32_t(__builtin_popcount(mask));
}

// Calls fn(first, end) for each run of consecutive set bits of `mask` (the
// sectors a cache moves in one request: a fill or a write-back per run).
template <class Fn>
inline void forEachRun(uint32_t mask, Fn&& fn) {
  uint32_t s = 0;
  while (mask >> s) {
    if (!(mask >> s & 1)) {
      ++s;
      continue;
    }
    uint32_t e = s;
    while (e < 32 && (mask >> e & 1)) ++e;
    fn(s, e);
    s = e;
    if (s == 32) break;
  }
}

// Bytes a cache still holds dirty (at the frame's end): [addr, addr + bytes) of `surface`.
struct DirtyRange {
  uint64_t addr = 0;
  uint32_t bytes = 0;
  Surface surface = Surface::BlendArrays;
};

}  // namespace oit::rop
