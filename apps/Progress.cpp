#include "apps/Progress.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace oit::cli {

Progress::Progress(std::string label, bool enabled)
    : label_(std::move(label)), enabled_(enabled), tty_(isatty(fileno(stderr)) != 0),
      start_(Clock::now()), last_(start_) {}

Progress::~Progress() { finish(); }

void Progress::update(double fraction, const std::string& detail) {
  if (!enabled_) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  const auto now = Clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (tty_) {
    if (drawn_ && now - last_ < std::chrono::milliseconds(100)) return;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    fmt::print(stderr, "\r{} [{}{}] {:5.1f}% {} {:.1f}s\x1b[K", label_, std::string(filled, '#'),
               std::string(kWidth - filled, '.'), fraction * 100.0, detail, elapsed);
    std::fflush(stderr);
    drawn_ = true;
    last_ = now;
  } else {
    const int quarter = static_cast<int>(fraction * 4.0);
    if (elapsed < 2.0 || quarter <= last_quarter_ || quarter >= 4) return;
    last_quarter_ = quarter;
    fmt::print(stderr, "{}: {:.0f}% {} ({:.1f}s)\n", label_, quarter * 25.0, detail, elapsed);
  }
}

void Progress::finish() {
  if (enabled_ && tty_ && drawn_) {
    fmt::print(stderr, "\r\x1b[K");
    std::fflush(stderr);
  }
  drawn_ = false;
  enabled_ = false;
}

std::string humanCount(double n) {
  if (n >= 1e9) return fmt::format("{:.2f} G", n / 1e9);
  if (n >= 1e6) return fmt::format("{:.2f} M", n / 1e6);
  if (n >= 1e4) return fmt::format("{:.1f} k", n / 1e3);
  return fmt::format("{:.0f}", n);
}

std::string counted(uint64_t n, std::string_view one, std::string_view many) {
  return fmt::format("{} {}", n, n == 1 ? one : many);
}

std::string humanBytes(double b) {
  if (b >= 1024.0 * 1024 * 1024) return fmt::format("{:.2f} GiB", b / (1024.0 * 1024 * 1024));
  if (b >= 1024.0 * 1024) return fmt::format("{:.1f} MiB", b / (1024.0 * 1024));
  if (b >= 1024.0) return fmt::format("{:.1f} KiB", b / 1024.0);
  return fmt::format("{:.0f} B", b);
}

}  // namespace oit::cli
