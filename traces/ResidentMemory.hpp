// Resident memory of this process: what the memory tests sample while a trace
// streams and what `oitsim run` measures against its estimate (apps/RunMemory).
#pragma once

#include <cstdint>

namespace oit {

// Resident set now (bytes, file-backed mapped pages included; /proc/self/statm), 0 unknown.
uint64_t residentBytes();
// The peak resident set of the process so far (bytes; getrusage), 0 unknown.
uint64_t peakResidentBytes();

}  // namespace oit
