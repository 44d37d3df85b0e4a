// Reading a memory-mapped file that another process may shrink. Touching a
// page of a mapping past the file's new end raises SIGBUS, which would kill
// the process without a word. The binary trace reader copies every batch out
// of its mapping through copyFromMapping(): a SIGBUS during the copy returns
// false instead (the caller reports "the trace changed while it was read"),
// and nothing else ever touches the mapping.
#pragma once

#include <cstddef>

namespace oit::detail {

// memcpy(dst, src, n); false (dst partly written) when reading src raised
// SIGBUS. The SIGBUS handler is installed on first use and passes a SIGBUS
// raised anywhere else on to the handler that was there before (by default:
// the process dies of the signal, as without it).
bool copyFromMapping(void* dst, const void* src, size_t n);

}  // namespace oit::detail
