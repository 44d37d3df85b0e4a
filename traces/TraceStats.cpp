#include "traces/TraceStats.hpp"

#include <bit>
#include <limits>
#include <unordered_map>

namespace oit {

unsigned complexityBin(uint32_t n) {
  if (n <= 1) return 0;
  // ceil(log2(n)): 2 -> 1, 3..4 -> 2, 5..8 -> 3 ...
  unsigned b = 32u - static_cast<unsigned>(std::countl_zero(n - 1));
  return b < kComplexityBins ? b : kComplexityBins - 1;
}

std::pair<uint32_t, uint32_t> complexityBinRange(unsigned bin) {
  if (bin == 0) return {1, 1};
  uint32_t lo = (1u << (bin - 1)) + 1;
  uint32_t hi = bin + 1 == kComplexityBins ? std::numeric_limits<uint32_t>::max() : (1u << bin);
  return {lo, hi};
}

namespace {
void summarise(const std::vector<uint32_t>& counts, uint32_t width, ComplexityStats& out) {
  for (size_t i = 0; i < counts.size(); ++i) {
    uint32_t n = counts[i];
    if (n == 0) continue;
    ++out.covered_pixels;
    out.fragments += n;
    ++out.histogram[complexityBin(n)];
    if (n > out.max) {
      out.max = n;
      out.max_x = static_cast<uint32_t>(i % width);
      out.max_y = static_cast<uint32_t>(i / width);
    }
  }
}
}  // namespace

TraceStats computeTraceStats(FragmentSource& src,
                             const std::function<void(uint64_t, uint64_t)>& progress) {
  TraceStats st;
  st.header = src.header();
  const TraceHeader& h = st.header;
  const size_t pixels = size_t(h.width) * h.height;
  std::vector<uint32_t> count_t(pixels, 0), count_o(pixels, 0), count_all(pixels, 0);

  // Draw ids map to table slots; the reader has already rejected unknown ids.
  std::unordered_map<uint32_t, size_t> slot;
  std::vector<uint8_t> opaque(h.draws.size());
  for (size_t i = 0; i < h.draws.size(); ++i) {
    slot.emplace(h.draws[i].id, i);
    st.draws.push_back(DrawStats{h.draws[i], 0, 0});
    opaque[i] = h.draws[i].cls == DrawClass::Opaque;
  }
  uint32_t last_draw = 0;
  size_t last_slot = h.draws.empty() ? 0 : slot.at(h.draws[0].id);
  if (!h.draws.empty()) last_draw = h.draws[0].id;

  uint64_t next_report = 0;
  for (auto batch = src.next(); !batch.empty(); batch = src.next()) {
    for (const Fragment& f : batch) {
      // Draws come in runs: cache the last lookup.
      if (f.draw != last_draw) {
        last_draw = f.draw;
        last_slot = slot.at(f.draw);
      }
      DrawStats& d = st.draws[last_slot];
      ++d.fragments;
      if (f.prim > d.max_prim) d.max_prim = f.prim;
      const size_t p = size_t(f.y) * h.width + f.x;
      ++count_all[p];
      if (opaque[last_slot])
        ++count_o[p];
      else
        ++count_t[p];
    }
    st.fragments += batch.size();
    if (progress && st.fragments >= next_report) {
      progress(st.fragments, h.fragment_count);
      next_report = st.fragments + (1u << 22);
    }
  }
  summarise(count_all, h.width, st.all);
  summarise(count_t, h.width, st.transparent);
  summarise(count_o, h.width, st.opaque);
  return st;
}

}  // namespace oit
