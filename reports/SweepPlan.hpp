// The plan of a sweep: its traces and points (the product of the spec's axes),
// with the points that differ only in settings their algorithm ignores planned
// once; and the plan's files, DIR/plan.json and DIR/commands.txt.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "reports/SweepSpec.hpp"

namespace oit::sweep {

struct TraceEntry {
  size_t index = 0;  // in the spec's traces list
  std::string name, path;
  std::vector<std::string> gen_args;  // `oitsim gen ...` arguments; empty for an existing trace
};

struct Point {
  std::string id, trace;  // id: NNNN-<trace>-<axis labels>
  ojson axes = ojson::object();  // axis -> label
  std::vector<std::string> args;  // `oitsim run ...` arguments (after the executable)
};

// A combination of axis values that is the same run as a planned point: it
// differs from it only in settings the point's algorithm (or mode) ignores.
struct Duplicate {
  std::string labels;             // <trace>-<axis labels> of the combination
  std::string same_as;            // the planned point's id
  std::vector<std::string> ignored;  // the settings it differs in ("layers", "cache.ways", ...)
};

struct Plan {
  std::string spec;        // absolute path of the spec
  std::filesystem::path out;  // absolute sweep folder
  std::string executable;  // absolute path of oitsim
  std::vector<TraceEntry> traces;
  std::vector<Point> points;
  std::vector<Duplicate> duplicates;
  size_t combinations = 0;  // traces x axis values, before deduplication
};

// Checks the whole spec (every setting, each point's ROP configuration, axes
// that no point uses) and expands it. Throws std::invalid_argument naming the
// spec file and key. Nothing is created.
Plan planSweep(const ojson& spec, const std::string& spec_path, const std::filesystem::path& out,
               const std::string& executable);

// "24 of 108 combinations differ only in settings their algorithm ignores
// (layers: abuffer, wboit) and are planned once", or "" when none.
std::string duplicatesLine(const Plan& plan);

// The shell line that runs point `p` alone, from any directory.
std::string commandLine(const Plan& plan, const Point& p);

// plan.json (schema oitsim-sweep-plan/1) and commands.txt (line i runs point i), whole or not at all.
void writePlanFiles(const Plan& plan);

// The points and traces of DIR/plan.json as written by writePlanFiles.
// Throws std::invalid_argument naming the file when there is none or it does not parse.
Plan readPlan(const std::filesystem::path& dir);

// What tells whether a trace file is still the one a plan's points ran on: a
// generated trace's generator arguments, an existing file's size and time.
std::string currentTraceStamp(const TraceEntry& t);
// The stamps DIR/plan.json recorded, by trace name (empty without a plan).
std::map<std::string, std::string> readTraceStamps(const std::filesystem::path& dir);

}  // namespace oit::sweep
