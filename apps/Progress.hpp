// A progress display for long runs, on stderr so stdout stays clean for data.
// On a terminal it redraws one line at most ten times a second; in a log it
// prints a line every 25% once the run has lasted two seconds.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>

namespace oit::cli {

class Progress {
 public:
  explicit Progress(std::string label, bool enabled = true);
  ~Progress();
  // fraction in [0,1]; detail is shown after the bar, e.g. "1.2 M fragments".
  void update(double fraction, const std::string& detail = {});
  void finish();

 private:
  using Clock = std::chrono::steady_clock;
  std::string label_;
  bool enabled_;
  bool tty_;
  bool drawn_ = false;
  Clock::time_point start_;
  Clock::time_point last_;
  int last_quarter_ = 0;
};

// "12.3 M", "456 k", "789": short counts for summaries.
std::string humanCount(double n);
// "1.2 GiB", "34.5 MiB", "12 B".
std::string humanBytes(double bytes);
// "1 draw", "3 draws", "2 passes": a count with its noun in number.
std::string counted(uint64_t n, std::string_view one, std::string_view many);

}  // namespace oit::cli
