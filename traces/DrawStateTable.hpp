// The draw state table of trace format v2 (FORMAT.md section 3.1): reading,
// checking and writing it, for the binary reader and writer and the CSV form.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "traces/Fragment.hpp"

namespace oit::detail {

struct TableProblem {
  uint64_t offset = 0;  // byte offset in the binary file
  std::string field;    // "draw[3].state.blend"
  std::string message;
};

// What is wrong with draw i's state (value ranges, and the class it implies:
// blending off = opaque, anything else = transparent), or nullopt.
std::optional<TableProblem> drawStateProblem(const DrawInfo& d, size_t i);

// Reads the table (the bytes at drawStateTableOffset(draws.size())) into each
// draw's state; the first problem, or nullopt.
std::optional<TableProblem> readDrawStates(const unsigned char* table, std::vector<DrawInfo>& draws);

// For writers: a v2 header needs a state on every draw, a v1 header none.
std::optional<TableProblem> headerStatesProblem(const TraceHeader& h);

void writeDrawStates(unsigned char* table, const std::vector<DrawInfo>& draws);

}  // namespace oit::detail

namespace oit::detail {

// CSV form (FORMAT.md section 8.1): "ID BLEND DEPTH FUNC EQ SRC DST EQA SRCA DSTA FRAGMENTS"
// after "# draw-state ", e.g. "3 over test 0x0201 0x8006 0x0302 0x0303 0x8006 0x0001 0x0303 1200".
std::string drawStateCsv(const DrawInfo& d);
// Parses the fields after the id; the problem, or nullopt.
std::optional<std::string> parseDrawStateCsv(std::string_view fields, DrawState& out);

}  // namespace oit::detail
