// Subcommands of the oitsim executable; each lives in apps/cmd_<name>.cpp and
// registers itself on the top-level CLI11 app.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdint>
#include <memory>
#include <string>

#include "traces/TraceIO.hpp"

namespace oit::cli {

void addGenCommand(CLI::App& app);      // oitsim gen SCENE -o FILE
void addInfoCommand(CLI::App& app);     // oitsim info TRACE
void addConvertCommand(CLI::App& app);  // oitsim convert IN OUT
void addRunCommand(CLI::App& app);      // oitsim run --trace T ...
void addScenesCommand(CLI::App& app);   // oitsim scenes
void addCaptureCommand(CLI::App& app);  // oitsim capture --mesh M -o FILE (headless GL)
void addStressCommand(CLI::App& app);   // oitsim stress [--out DIR]
void addConfigCommand(CLI::App& app);   // oitsim config [--preset P] [--config F] [--set a.b=v]
void addSweepCommand(CLI::App& app);   // oitsim sweep SPEC --out DIR [--jobs N] [--emit slurm]
void addReportCommand(CLI::App& app);  // oitsim report DIR -> DIR/report.html

// CLI11 2.1 reads an unsigned option with strtoull: "-5" wraps around and a
// value past 2^64 - 1 saturates, both silently. unsignedText() takes digits
// only ("expected a non-negative integer, got 'abc'"); main() adds it to every
// unsigned option. unsignedRange(lo, hi): the same check, then the range, as
// one validator, for options with a range (CLI::Range alone, which runs before
// main()'s check, said "Value abc not in range").
CLI::Validator unsignedText();
CLI::Validator unsignedRange(uint64_t lo, uint64_t hi);

// The command line as typed (recorded in reports so a run can be repeated).
void setCommandLine(int argc, char* argv[]);
const std::string& commandLine();

// Checks that `folder` (given as `option`, e.g. --out) can be used as an output
// folder before anything runs: not empty, not an existing non-directory, and
// the folder or the nearest existing part of its path a writable directory.
// Errors name the option: "--out afile: exists and is not a directory".
void checkOutputFolder(const std::string& option, const std::string& folder);

// openTrace with the --width/--height options (0 = not given); a value that
// differs from the size the trace itself gives is an error naming the option.
std::unique_ptr<FragmentSource> openTraceWithSize(const std::string& path, uint32_t width, uint32_t height);

}  // namespace oit::cli
