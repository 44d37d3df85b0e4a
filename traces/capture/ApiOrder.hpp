// API order of one draw's records. The injected fragment code appends records in
// shader-thread order; a trace holds a draw's fragments in API order: primitive,
// then pixel row bottom to top, then x (as `oitsim gen` and the mesh capture emit
// them). A primitive covers a pixel at most once, so (primitive, y, x) is a total
// order, except in instanced and multi-draw calls, whose primitive ids restart:
// fragments with equal (primitive, y, x) are then ordered by depth and colour.
//
// A least-significant-digit radix sort on the packed (primitive, y, x) key: linear
// in the records, where a comparison sort of the 1.46 M records of the glmark2 frame
// was about a tenth of the capture's CPU time (bench/RESULTS-capture-apitrace.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace oit::capture {

// The sort key of a record: its primitive id and its pixel, x | y << 16 (the
// record's packed `xy`).
struct RecordKey {
  uint32_t prim;
  uint32_t xy;
};

// Indices 0..keys.size()-1 ordered by (prim, y, x); records with equal keys stay in
// their input order (stable). `keys` is read through `key(i)`, so callers need not
// copy their records.
template <typename KeyOf>
std::vector<uint32_t> apiOrder(size_t n, KeyOf&& key);

// The same for a plain array of keys (what the template does, out of line).
std::vector<uint32_t> apiOrderOfKeys(const std::vector<RecordKey>& keys);

namespace detail {
// Radix-sorts (key, index) pairs whose keys use only the low `bits` bits.
struct KeyIndex {
  uint64_t key;
  uint32_t index;
};
void radixSort(std::vector<KeyIndex>& items, std::vector<KeyIndex>& scratch, unsigned bits);
unsigned bitWidth(uint64_t v);
}  // namespace detail

template <typename KeyOf>
std::vector<uint32_t> apiOrder(size_t n, KeyOf&& key) {
  // Pack (prim - min prim, y, x) into as few bits as the draw needs, so a draw with
  // few primitives on a small frame takes fewer passes.
  uint32_t min_prim = UINT32_MAX, max_prim = 0, max_x = 0, max_y = 0;
  for (size_t i = 0; i < n; ++i) {
    const RecordKey k = key(i);
    min_prim = k.prim < min_prim ? k.prim : min_prim;
    max_prim = k.prim > max_prim ? k.prim : max_prim;
    max_x = (k.xy & 0xFFFF) > max_x ? (k.xy & 0xFFFF) : max_x;
    max_y = (k.xy >> 16) > max_y ? (k.xy >> 16) : max_y;
  }
  const unsigned xb = detail::bitWidth(max_x), yb = detail::bitWidth(max_y);
  const unsigned pb = n ? detail::bitWidth(uint64_t(max_prim) - min_prim) : 0;
  std::vector<detail::KeyIndex> items(n), scratch(n);
  for (size_t i = 0; i < n; ++i) {
    const RecordKey k = key(i);
    items[i] = {(uint64_t(k.prim - min_prim) << (xb + yb)) | (uint64_t(k.xy >> 16) << xb) | (k.xy & 0xFFFF),
                static_cast<uint32_t>(i)};
  }
  detail::radixSort(items, scratch, pb + xb + yb);
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = items[i].index;
  return order;
}

}  // namespace oit::capture
