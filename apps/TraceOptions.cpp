#include "apps/TraceOptions.hpp"

#include <fmt/format.h>

#include <unistd.h>

#include <fstream>
#include <sstream>
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

uint64_t machineMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  uint64_t bytes = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : 0;
  std::ifstream meminfo("/proc/meminfo");
  for (std::string line; std::getline(meminfo, line);)
    if (line.rfind("SwapTotal:", 0) == 0) {
      uint64_t kib = 0;
      std::istringstream(line.substr(10)) >> kib;
      bytes += kib * 1024;
    }
  return bytes;
}

void checkFrameFitsInMemory(const std::string& trace, uint32_t width, uint32_t height, uint64_t bytes_per_pixel,
                            const std::string& what) {
  const uint64_t need = uint64_t(width) * height * bytes_per_pixel, have = machineMemoryBytes();
  constexpr double kGiB = 1024.0 * 1024.0 * 1024.0;
  if (have != 0 && need > have)
    throw std::invalid_argument(fmt::format(
        "{}: a {} x {} frame needs at least {:.1f} GiB for {} ({} B per pixel); this machine has {:.1f} GiB "
        "(RAM + swap)",
        trace, width, height, double(need) / kGiB, what, bytes_per_pixel, double(have) / kGiB));
}

}  // namespace oit::cli
