// Numerical stress suite of the functional model: tiny deterministic traces
// (one to four pixels) that push every algorithm to its numerical limits
// (depth complexity 4096, alpha 0 / 1e-7 / 1/255 / 1 - 1e-7 / 1, equal and
// denormal depths, long merge chains, accumulator range limits), and a runner
// that renders each of them with every algorithm x storage format x k and
// checks the output against the `abuffer` reference.
// Used by `oitsim stress` (apps/cmd_stress.cpp) and tests/model/test_stress.cpp;
// the committed table and its column meanings are in reports/stress/README.md.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "model/FunctionalRenderer.hpp"
#include "model/OitAlgorithm.hpp"
#include "traces/Fragment.hpp"

namespace oit::model::stress {

// Draw ids every case uses.
inline constexpr uint32_t kOpaqueDraw = 0;
inline constexpr uint32_t kGlassDraw = 1;

// Camera planes in every case header (wboit eq. 7-9 need view distance):
// window depth 0 maps to view distance 0.1, depth 1 to 100.
inline constexpr float kNear = 0.1f, kFar = 100.0f;

struct StressCase {
  std::string name;
  std::string what;  // one line: what it stresses
  TraceHeader header;
  std::vector<Fragment> fragments;  // submission order
  Rgb clear{0.0f, 0.0f, 0.0f};      // background where no opaque fragment landed
};

// Small deterministic PRNG (splitmix64, Steele et al. 2014): the cases must be
// bit-identical on every platform, which std:: distributions do not promise.
class SplitMix64 {
 public:
  explicit SplitMix64(uint64_t seed) : s_(seed) {}
  uint64_t next() {
    uint64_t z = (s_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in the open interval (0,1): (i + 0.5) / 2^24, exact in float.
  float open01() { return (float(next() >> 40) + 0.5f) * 0x1p-24f; }
  // Uniform in [0, n).
  uint32_t below(uint32_t n) { return uint32_t((next() >> 32) * n >> 32); }

 private:
  uint64_t s_;
};

// Case names in suite order.
const std::vector<std::string>& caseNames();
// Builds one case (deterministic). Throws std::invalid_argument naming the
// valid names for an unknown one.
StressCase makeCase(std::string_view name);

// Renders a case with one algorithm (the case's clear colour, its header).
RenderResult renderCase(const StressCase& c, OitAlgorithm& algo);

// One algorithm configuration of the sweep: an algorithm plus a variant of
// its non-k parameters (wboit weight equation, slab coverage masks,
// stochastic sample count).
struct StressConfig {
  std::string algorithm;
  std::string variant;  // "" when the algorithm has a single configuration
  AlgorithmParams params;
};
// Every algorithm of algorithmNames() (none skipped) with its variants.
std::vector<StressConfig> stressConfigs();

enum class RowStatus : uint8_t {
  Ok,             // finite, in [0,1], outcome counts balanced
  NotApplicable,  // makeAlgorithm rejected the format / k (std::invalid_argument)
  Violation,      // NaN/Inf, a channel outside [0,1], or unbalanced outcome counts
  Error,          // render threw (anything but the makeAlgorithm rejection)
};
const char* toString(RowStatus s);

struct StressRow {
  std::string case_name, algorithm, variant, format;
  unsigned k = 0;  // 0: the algorithm's state does not depend on k (run once)
  RowStatus status = RowStatus::Ok;
  std::string note;  // n/a reason, exception text, or the violations found
  uint64_t fragments = 0;
  // Output checks over every channel of every pixel of the frame.
  uint64_t non_finite = 0;    // NaN or Inf channels
  uint64_t out_of_range = 0;  // finite channels outside [0,1]
  double min_value = 0, max_value = 0;  // over finite channels
  bool balanced = true;  // opaque + culled + outcomes == fragments in, every pass
  // Error against the abuffer reference (NaN when the output is not finite):
  // max |img - ref| over all channels of the frame, and RMSE over the channels
  // of the pixels the case covers (at least one fragment).
  double max_abs_error = 0, rmse = 0;
  uint64_t stored = 0, merged = 0, discarded = 0, culled = 0;  // first pass
  unsigned bytes_per_pixel = 0;

  bool violation() const { return status == RowStatus::Violation || status == RowStatus::Error; }
};

struct StressOptions {
  std::vector<std::string> algorithms;  // empty: all
  std::vector<std::string> cases;       // empty: all
  std::vector<unsigned> layers{1, 4, 16, 64};
  // Called once per case before it runs (progress display).
  std::function<void(const std::string& case_name)> on_case;
};

// Throws std::invalid_argument for an unknown algorithm or case name.
std::vector<StressRow> runStress(const StressOptions& opt = {});

// Rows as a Markdown document (summary, violations, full table) and as CSV.
// `command` is the command line recorded in the Markdown header.
std::string toMarkdown(const std::vector<StressRow>& rows, const std::string& command);
std::string toCsv(const std::vector<StressRow>& rows);
// Writes <dir>/stress-table.md and <dir>/stress-table.csv, each to a
// temporary file in dir then renamed over the target (creates dir).
// Throws std::runtime_error naming the file on I/O failure.
void writeStressTables(const std::vector<StressRow>& rows, const std::string& dir, const std::string& command);

}  // namespace oit::model::stress
