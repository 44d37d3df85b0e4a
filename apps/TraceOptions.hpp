// Checks on the options that describe an input trace, shared by the trace
// commands (info, convert).
#pragma once

#include <cstdint>

namespace oit::cli {

// --width / --height for a CSV trace without size comments: when given, each
// must be 1..65535 (x and y are u16). Throws std::invalid_argument naming the
// option, as `oitsim run` does: "--width 0: expected a frame width of at least 1 pixel".
void checkFrameSizeOptions(bool width_given, uint32_t width, bool height_given, uint32_t height);

}  // namespace oit::cli
