// FNV-1a (64-bit) over bytes, for the tests' fingerprints of fragment streams
// and images: chained by passing the previous value as `h`.
#pragma once

#include <cstddef>
#include <cstdint>

namespace oit::test {

constexpr uint64_t kFnv1aOffset = 0xcbf29ce484222325ull;

inline uint64_t fnv1a64(const void* data, size_t n, uint64_t h = kFnv1aOffset) {
  const auto* b = static_cast<const unsigned char*>(data);
  for (size_t i = 0; i < n; ++i) h = (h ^ b[i]) * 0x100000001b3ull;
  return h;
}

}  // namespace oit::test
