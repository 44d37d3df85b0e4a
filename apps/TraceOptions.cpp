#include "apps/TraceOptions.hpp"

#include <fmt/format.h>

#include <stdexcept>

#include "traces/TraceFormat.hpp"

namespace oit::cli {

void checkFrameSizeOptions(bool width_given, uint32_t width, bool height_given, uint32_t height) {
  const struct {
    bool given;
    uint32_t value;
    const char* option;
    const char* what;
  } sizes[] = {{width_given, width, "--width", "width"}, {height_given, height, "--height", "height"}};
  for (const auto& s : sizes) {
    if (!s.given) continue;
    if (s.value == 0)
      throw std::invalid_argument(fmt::format("{} 0: expected a frame {} of at least 1 pixel", s.option, s.what));
    if (s.value > format_v1::kMaxFrameSize)
      throw std::invalid_argument(fmt::format("{} {}: expected a frame {} of 1..{} pixels (x and y are u16)",
                                              s.option, s.value, s.what, format_v1::kMaxFrameSize));
  }
}

}  // namespace oit::cli
