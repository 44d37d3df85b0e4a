// The radix sort that puts a draw's records into API order (traces/capture/ApiOrder):
// the same order as a stable comparison sort by (primitive, y, x), on keys that
// need one, two and several radix passes.
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "traces/capture/ApiOrder.hpp"

namespace oit::capture {
namespace {

std::vector<uint32_t> byStableSort(const std::vector<RecordKey>& keys) {
  std::vector<uint32_t> order(keys.size());
  std::iota(order.begin(), order.end(), 0u);
  std::stable_sort(order.begin(), order.end(), [&](uint32_t a, uint32_t b) {
    const RecordKey& p = keys[a];
    const RecordKey& q = keys[b];
    if (p.prim != q.prim) return p.prim < q.prim;
    if ((p.xy >> 16) != (q.xy >> 16)) return (p.xy >> 16) < (q.xy >> 16);
    return (p.xy & 0xFFFF) < (q.xy & 0xFFFF);
  });
  return order;
}

std::vector<RecordKey> randomKeys(size_t n, uint32_t prims, uint32_t prim_base, uint32_t w, uint32_t h,
                                  uint32_t seed) {
  std::mt19937 rng(seed);
  std::vector<RecordKey> keys(n);
  for (RecordKey& k : keys) {
    const auto x = static_cast<uint32_t>(rng() % w), y = static_cast<uint32_t>(rng() % h);
    k = {prim_base + static_cast<uint32_t>(rng() % prims), x | (y << 16)};
  }
  return keys;
}

TEST(ApiOrder, HandWorkedExample) {
  // (prim, x, y): prim first, then the row, then x; the two equal keys (prim 1 at
  // (3, 2)) keep their input order, 1 before 4.
  const std::vector<RecordKey> keys = {
      {2, 0 | (0u << 16)},  // 0
      {1, 3 | (2u << 16)},  // 1
      {1, 5 | (1u << 16)},  // 2
      {0, 9 | (7u << 16)},  // 3
      {1, 3 | (2u << 16)},  // 4
      {1, 4 | (2u << 16)},  // 5
  };
  EXPECT_EQ(apiOrderOfKeys(keys), (std::vector<uint32_t>{3, 2, 1, 4, 5, 0}));
}

TEST(ApiOrder, EqualsAStableSortFromOneToSeveralPasses) {
  struct Case {
    size_t n;
    uint32_t prims, prim_base, w, h;
  };
  // Keys of 3 bits (one pass), 22 bits (two passes), 33 and 64 bits (the largest:
  // primitive ids spanning 32 bits, a 65535 x 65535 frame).
  for (const Case c : {Case{50, 1, 0, 4, 2}, Case{20000, 2, 7, 1280, 720}, Case{100000, 4400, 0, 1280, 720},
                       Case{5000, 0xFFFFFFFFu, 0, 65535, 65535}}) {
    const std::vector<RecordKey> keys = randomKeys(c.n, c.prims, c.prim_base, c.w, c.h, static_cast<uint32_t>(c.n));
    EXPECT_EQ(apiOrderOfKeys(keys), byStableSort(keys)) << c.n << " keys, " << c.prims << " primitives";
  }
  EXPECT_TRUE(apiOrderOfKeys({}).empty());
  EXPECT_EQ(apiOrderOfKeys({{5, 9}}), std::vector<uint32_t>{0});
}

}  // namespace
}  // namespace oit::capture
