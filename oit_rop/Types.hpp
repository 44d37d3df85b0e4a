// Payload and counter types shared by the stages of the timing model.
#pragma once

#include <array>
#include <cstdint>

namespace oit::rop {

using Cycle = uint64_t;  // core-clock cycles since the start of the frame
inline constexpr Cycle kNever = ~Cycle(0);

// Memory surfaces the ROP touches; DRAM bytes are split by these.
enum class Surface : uint8_t { BlendArrays = 0, Depth = 1, Colour = 2, Resolve = 3 };
inline constexpr unsigned kSurfaceCount = 4;
const char* toString(Surface s);

}  // namespace oit::rop
