#include "traces/capture/ApiOrder.hpp"

#include <algorithm>
#include <array>

namespace oit::capture {

namespace detail {

unsigned bitWidth(uint64_t v) {
  unsigned b = 0;
  while (v >> b) ++b;
  return b;
}

// LSD radix sort, stable, digits of at most 12 bits (4096 counters: they stay in
// the L1 cache), as few passes as `bits` needs.
void radixSort(std::vector<KeyIndex>& items, std::vector<KeyIndex>& scratch, unsigned bits) {
  if (items.size() < 2 || bits == 0) return;
  constexpr unsigned kMaxDigit = 12;
  const unsigned passes = (bits + kMaxDigit - 1) / kMaxDigit;
  const unsigned digit = (bits + passes - 1) / passes;
  const uint64_t mask = (uint64_t(1) << digit) - 1;
  std::vector<uint32_t> count(size_t(1) << digit);
  scratch.resize(items.size());
  for (unsigned pass = 0; pass < passes; ++pass) {
    const unsigned shift = pass * digit;
    std::fill(count.begin(), count.end(), 0u);
    for (const KeyIndex& it : items) ++count[(it.key >> shift) & mask];
    uint32_t sum = 0;
    for (uint32_t& c : count) {
      const uint32_t here = c;
      c = sum;
      sum += here;
    }
    for (const KeyIndex& it : items) scratch[count[(it.key >> shift) & mask]++] = it;
    items.swap(scratch);
  }
}

}  // namespace detail

std::vector<uint32_t> apiOrderOfKeys(const std::vector<RecordKey>& keys) {
  return apiOrder(keys.size(), [&](size_t i) { return keys[i]; });
}

}  // namespace oit::capture
