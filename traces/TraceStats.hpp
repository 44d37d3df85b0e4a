// Statistics of a trace, as `oitsim info` prints them: per-draw fragment counts,
// covered pixels and per-pixel depth complexity.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <vector>

#include "traces/TraceIO.hpp"

namespace oit {

// Histogram bins of depth complexity: bin 0 holds exactly 1, bin i (i >= 1)
// holds [2^(i-1)+1, 2^i], i.e. 1, 2, 3-4, 5-8, ..., last bin open-ended.
constexpr unsigned kComplexityBins = 14;
unsigned complexityBin(uint32_t fragments);
// Lower and upper bound of a bin (upper is UINT32_MAX for the last bin).
std::pair<uint32_t, uint32_t> complexityBinRange(unsigned bin);

struct ComplexityStats {
  uint64_t covered_pixels = 0;  // pixels with at least one fragment of the class
  uint64_t fragments = 0;
  uint32_t max = 0;
  uint32_t max_x = 0, max_y = 0;  // first pixel (in row order from the bottom) reaching max
  std::array<uint64_t, kComplexityBins> histogram{};
  double mean() const { return covered_pixels ? double(fragments) / double(covered_pixels) : 0.0; }
};

struct DrawStats {
  DrawInfo draw;
  uint64_t fragments = 0;
  uint32_t max_prim = 0;  // largest primitive id seen (+1 is a lower bound of the primitive count)
};

struct TraceStats {
  TraceHeader header;
  uint64_t fragments = 0;
  std::vector<DrawStats> draws;  // in draw-table order
  ComplexityStats all;           // every fragment
  ComplexityStats transparent;   // transparent draws only: what the OIT arrays hold
  ComplexityStats opaque;
};

// Reads the whole source once (from its current position). Throws TraceError on bad data.
TraceStats computeTraceStats(FragmentSource& src,
                             const std::function<void(uint64_t done, uint64_t total)>& progress = {});

}  // namespace oit
