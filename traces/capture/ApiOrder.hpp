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
#include <memory>
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
struct KeyIndex {
  uint64_t key;
  uint32_t index;
};
// Two uninitialised arrays of n items (no zero fill: every item is written before
// it is read), on transparent huge pages where the kernel offers them.
struct KeyIndexBuffers {
  explicit KeyIndexBuffers(size_t n);
  std::unique_ptr<KeyIndex[]> items, scratch;
  size_t n;
};
// Radix-sorts b.items (the sorted items end in b.items) whose keys use only the
// low `bits` bits.
void radixSort(KeyIndexBuffers& b, unsigned bits);
unsigned bitWidth(uint64_t v);
// Asks for transparent huge pages for the whole 2 MiB pages inside [p, p + bytes)
// (THP "madvise" mode); changes nothing where THP is off.
void adviseHugePages(const void* p, size_t bytes);
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
  detail::KeyIndexBuffers b(n);
  for (size_t i = 0; i < n; ++i) {
    const RecordKey k = key(i);
    b.items[i] = {(uint64_t(k.prim - min_prim) << (xb + yb)) | (uint64_t(k.xy >> 16) << xb) | (k.xy & 0xFFFF),
                  static_cast<uint32_t>(i)};
  }
  detail::radixSort(b, pb + xb + yb);
  std::vector<uint32_t> order(n);
  for (size_t i = 0; i < n; ++i) order[i] = b.items[i].index;
  return order;
}

}  // namespace oit::capture
