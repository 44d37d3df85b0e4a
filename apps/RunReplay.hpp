// oitsim run's work behind its options: check them, replay the trace
// (functional or timing, one seed or several), compare with the reference and
// write the outputs and report.json all at once (nothing is written unless the
// whole run succeeded); then print the summary. The command (apps/cmd_run.cpp)
// only declares the options.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "model/Flip.hpp"
#include "model/OitAlgorithm.hpp"

namespace oit::cli {

struct RunArgs {
  std::string trace, out, algo = "mlab", mode = "timing", format = "fp32";
  std::string preset, config_file, vcd;  // preset empty: the --config file's "preset", else iris-pro-5200
  std::string reference = "abuffer";      // abuffer (exact, in bands), none, or a PFM file
  std::string memory_budget;              // empty: kDefaultBudgetPercent of physical memory
  bool config_given = false;
  std::string out_of_memory;  // the message for a failed allocation, once the frame is known
  std::vector<std::string> sets;
  uint32_t width = 0, height = 0;
  bool width_given = false, height_given = false;
  bool vcd_given = false;  // --vcd on the command line (an empty path is an error, not "no VCD")
  model::AlgorithmParams params;
  double ppd = model::kFlipDefaultPpd;  // FLIP's pixels per degree
  std::vector<float> background{0.0f, 0.0f, 0.0f};
  bool quiet = false;
  std::string command_line;  // recorded in the report
  unsigned seeds = 0;        // --seeds N (0: not given)
  bool seeds_given = false;
};

// The whole run. Throws std::invalid_argument for a bad option (naming it) and
// std::runtime_error for a bad trace or a failed write; a.out_of_memory is set
// once the frame is known, for the caller's message on std::bad_alloc.
void runReplay(RunArgs& a);

}  // namespace oit::cli
