// The blending-array cache tests' shared set-up (test_blend_array_cache.cpp,
// test_blend_array_cache_reference.cpp): a whole-cycle DRAM, caches of
// one-line tiles and accesses that acquire and release at once.
#pragma once

#include <span>

#include "oit_rop/memory/BlendArrayCache.hpp"
#include "oit_rop/memory/DramSystem.hpp"

namespace oit::rop::cache_testutil {

inline constexpr uint32_t kLine = 256;  // bytes per tile line in these tests

// Whole-cycle DRAM: 1000 MHz core, tCK 1 ns, 16 B/cycle; controller 40,
// CL = tRCD = tRP = 11. A 256 B line is 16 bus cycles; an unloaded line read
// on a closed bank takes 40 + 11 + 11 + 16 = 78 cycles.
inline DramConfig roundDram(unsigned channels = 1) {
  DramConfig c;
  c.channels = channels;
  c.channel_gbps = 16.0;
  c.tck_ns = 1.0;
  c.cl = c.trcd = c.trp = 11;
  c.controller_ns = 40.0;
  return c;
}
inline constexpr double kMhz = 1000.0;

inline CacheConfig cacheOf(uint32_t lines, unsigned ways, unsigned miss_queue = 16, unsigned hit_latency = 10) {
  CacheConfig c;
  c.size_bytes = uint64_t(lines) * kLine;
  c.ways = ways;
  c.miss_queue = miss_queue;
  c.hit_latency = hit_latency;
  return c;
}

// Most tests use one line per tile (the old tile-sized lines): a tile's
// arrays are one line of `bytes`, read whole and, for a write, written whole.
inline TileLines oneLine(uint32_t bytes = kLine) { return {bytes, bytes, 1}; }
inline constexpr LineTouch kReadLine{0, 1, 0}, kWriteLine{0, 1, 1};
inline std::span<const LineTouch> whole(bool write) { return {write ? &kWriteLine : &kReadLine, 1}; }
inline Cycle acquire(BlendArrayCache& cache, Cycle now, uint32_t tile, bool write) {
  return cache.acquire(now, tile, whole(write));
}
inline bool release(BlendArrayCache& cache, uint32_t tile) { return cache.release(tile, whole(false)); }

// One access whose use ends at once (acquire, then release when accepted):
// for the tests of LRU, fills and the miss queue, where no line stays in use.
// (Lines in use are the subject of test_blend_array_cache.cpp's LinesInUse tests.)
inline Cycle use(BlendArrayCache& cache, Cycle now, uint32_t tile, bool write) {
  const Cycle t = acquire(cache, now, tile, write);
  if (t != kNever) release(cache, tile);
  return t;
}

// Acquire like a pipeline would: on kNever, retry one cycle later.
inline Cycle acquireRetrying(BlendArrayCache& cache, Cycle& now, uint32_t tile, bool write) {
  for (;;) {
    const Cycle t = use(cache, now, tile, write);
    if (t != kNever) return t;
    ++now;
  }
}

}  // namespace oit::rop::cache_testutil
