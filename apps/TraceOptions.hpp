// Checks on the options that describe an input trace, shared by the trace
// commands (info, convert).
#pragma once

#include <cstdint>
#include <string>

namespace oit::cli {

// --width / --height for a CSV trace without size comments: when given, each
// must be 1..65535 (x and y are u16). Throws std::invalid_argument naming the
// option, as `oitsim run` does: "--width 0: expected a frame width of at least 1 pixel".
void checkFrameSizeOptions(bool width_given, uint32_t width, bool height_given, uint32_t height);

// Memory of this machine: physical RAM plus swap, in bytes (0 when unknown).
uint64_t machineMemoryBytes();

// A legal frame can be far too large for this machine (65535 x 65535 x 12 B is
// 51 GB): the kernel would kill the process part way through instead of any
// error. Throws std::invalid_argument naming the trace, the frame, the bytes per
// pixel `what` needs and the machine's memory when W x H x bytes_per_pixel alone
// exceeds RAM + swap (a lower bound of the real need: never a false refusal).
void checkFrameFitsInMemory(const std::string& trace, uint32_t width, uint32_t height, uint64_t bytes_per_pixel,
                            const std::string& what);

}  // namespace oit::cli
