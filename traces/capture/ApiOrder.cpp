#include "traces/capture/ApiOrder.hpp"

#include <algorithm>
#include <array>

#include <sys/mman.h>

namespace oit::capture {

namespace detail {

unsigned bitWidth(uint64_t v) {
  unsigned b = 0;
  while (v >> b) ++b;
  return b;
}

void adviseHugePages(const void* p, size_t bytes) {
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  const auto begin = reinterpret_cast<uintptr_t>(p);
  const uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t last = (begin + bytes) & ~(kHuge - 1);
  if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
}

KeyIndexBuffers::KeyIndexBuffers(size_t count)
    : items(std::make_unique_for_overwrite<KeyIndex[]>(count)),
      scratch(std::make_unique_for_overwrite<KeyIndex[]>(count)),
      n(count) {
  adviseHugePages(items.get(), n * sizeof(KeyIndex));
  adviseHugePages(scratch.get(), n * sizeof(KeyIndex));
}

// LSD radix sort, stable, digits of at most 12 bits (4096 counters: they stay in
// the L1 cache), as few passes as `bits` needs.
void radixSort(KeyIndexBuffers& b, unsigned bits) {
  if (b.n < 2 || bits == 0) return;
  constexpr unsigned kMaxDigit = 12;
  const unsigned passes = (bits + kMaxDigit - 1) / kMaxDigit;
  const unsigned digit = (bits + passes - 1) / passes;
  const uint64_t mask = (uint64_t(1) << digit) - 1;
  std::vector<uint32_t> count(size_t(1) << digit);
  for (unsigned pass = 0; pass < passes; ++pass) {
    const unsigned shift = pass * digit;
    std::fill(count.begin(), count.end(), 0u);
    const KeyIndex* in = b.items.get();
    KeyIndex* out = b.scratch.get();
    for (size_t i = 0; i < b.n; ++i) ++count[(in[i].key >> shift) & mask];
    uint32_t sum = 0;
    for (uint32_t& c : count) {
      const uint32_t here = c;
      c = sum;
      sum += here;
    }
    for (size_t i = 0; i < b.n; ++i) out[count[(in[i].key >> shift) & mask]++] = in[i];
    b.items.swap(b.scratch);
  }
}

}  // namespace detail

std::vector<uint32_t> apiOrderOfKeys(const std::vector<RecordKey>& keys) {
  return apiOrder(keys.size(), [&](size_t i) { return keys[i]; });
}

}  // namespace oit::capture
