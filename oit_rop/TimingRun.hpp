// The timing mode of oitsim: replays a fragment trace through the SystemC ROP
// model (OitRop) and returns the image (with lock.mode = ordered bit-identical
// to FunctionalRenderer's by construction; with unordered or none in the
// order the timing decides, DESIGN.md "Ordering") with the timing, traffic and
// lock statistics. The schema of `stats` is in oit_rop/DESIGN.md.
//
// SystemC elaborates once per process: runTiming() may be called once per
// process (it throws std::logic_error on a second call).
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "model/FunctionalRenderer.hpp"
#include "model/Image.hpp"
#include "model/OitAlgorithm.hpp"
#include "oit_rop/config/RopConfig.hpp"
#include "traces/TraceIO.hpp"

namespace oit::rop {

struct TimingOptions {
  model::Rgb clear_colour{0.0f, 0.0f, 0.0f};
  // fraction in [0, 1] of the trace passes done, and what is running.
  std::function<void(double fraction, const std::string& what)> progress;
  std::string vcd_path;  // empty: no VCD
};

struct TimingResult {
  model::Image image;
  model::RenderCounts counts;
  nlohmann::json stats;       // sections timing, fragments, memory, lock, cache, skips, depth, timeseries, per_draw
  double wall_seconds = 0.0;  // not in stats: stats are deterministic
  uint64_t pool_bytes = 0;    // the algorithm's poolBytes() after the run (A-buffer nodes)
};

// The file a VCD path names: SystemC appends ".vcd" unless the path ends in it.
std::string vcdFilePath(const std::string& path);
// Throws std::invalid_argument naming the file when the VCD cannot be written
// (missing folder, no permission, a directory); leaves no file behind.
void checkVcdWritable(const std::string& path);

// Errors of the trace (TraceError: file, byte offset, record, field) come out as
// thrown by the reader, whether they happen before or during the simulation.
// The A-buffer under test's budgets from the ROP configuration (abuffer.*):
// what makeAlgorithm("abuffer", ...) takes in both modes, so a functional run
// drops and truncates exactly as the timing run does.
inline model::ABufferBudget abufferBudget(const ABufferConfig& c) {
  model::ABufferBudget b;
  b.pool_bytes = c.pool_bytes;
  b.nodes_per_pixel = c.nodes_per_pixel;
  b.max_sorted = c.max_sorted;
  b.overflow = c.overflow == ABufferOverflowPolicy::Truncate ? model::ABufferOverflow::Truncate
                                                              : model::ABufferOverflow::Spill;
  return b;
}

TimingResult runTiming(FragmentSource& src, model::OitAlgorithm& algo, const RopConfig& cfg,
                       const TimingOptions& opt);

}  // namespace oit::rop
