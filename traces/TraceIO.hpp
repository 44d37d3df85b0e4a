// Streaming readers and writers of trace format v1 (binary, see FORMAT.md) and
// of its CSV form. Every reader validates every record it hands out.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

#include "traces/Fragment.hpp"

namespace oit {

// A bad trace: names the file, the byte offset (and, for CSV, the line), the
// record index and the field, and what was expected.
class TraceError : public std::runtime_error {
 public:
  TraceError(std::string file, uint64_t byte_offset, std::optional<uint64_t> record,
             std::string field, const std::string& what);
  // An error about the file as a whole (cannot open, create, write, rename):
  // no position, byteOffset() is 0 and field() is empty.
  TraceError(std::string file, const std::string& what);
  // A CSV error: also names the 1-based line; field is the column name (or the
  // metadata keyword for a comment-header line).
  static TraceError inCsv(std::string file, uint64_t line, uint64_t byte_offset,
                          std::optional<uint64_t> record, std::string field,
                          const std::string& what);
  const std::string& file() const { return file_; }
  uint64_t byteOffset() const { return byte_offset_; }
  std::optional<uint64_t> record() const { return record_; }
  const std::string& field() const { return field_; }
  std::optional<uint64_t> line() const { return line_; }

 private:
  TraceError(std::string file, std::optional<uint64_t> line, std::optional<uint64_t> byte_offset,
             std::optional<uint64_t> record, std::string field, const std::string& what);
  std::string file_;
  uint64_t byte_offset_;
  std::optional<uint64_t> record_;
  std::string field_;
  std::optional<uint64_t> line_;
};

struct OpenOptions {
  // Frame size of a CSV trace when it carries none in its comment header;
  // ignored for binary traces (their header has it).
  uint32_t width = 0;
  uint32_t height = 0;
  // Records handed out per next() call; bounds the reader's own memory.
  size_t batch_records = 1u << 16;
};

// A validated stream of fragments in submission order.
class FragmentSource {
 public:
  virtual ~FragmentSource() = default;
  virtual const TraceHeader& header() const = 0;
  virtual const std::string& path() const = 0;
  // The next batch of validated fragments; empty at the end of the trace.
  // The span stays valid until the next call. Throws TraceError.
  virtual std::span<const Fragment> next() = 0;
  // Records handed out so far.
  virtual uint64_t position() const = 0;
  // Start again from the first record (multi-pass algorithms replay the trace).
  virtual void rewind() = 0;
};

// Opens a binary trace (by magic) or a CSV trace (by the .csv extension, any case).
std::unique_ptr<FragmentSource> openTrace(const std::string& path, const OpenOptions& opts = {});
// Whether openTrace / createTraceWriter treat `path` as CSV (".csv", any case).
bool isCsvTracePath(const std::string& path);

// Receives fragments in submission order and validates them as the reader would.
class FragmentSink {
 public:
  virtual ~FragmentSink() = default;
  virtual void write(const Fragment& f) = 0;
  virtual void write(std::span<const Fragment> fs) {
    for (const Fragment& f : fs) write(f);
  }
  // Makes the file appear at its path (written to a temporary file, then renamed).
  // Without commit() the destructor removes the temporary: no half-written trace.
  virtual void commit() = 0;
  virtual uint64_t written() const = 0;
};

// Creates a binary writer, or a CSV writer for a path ending in .csv.
// header.fragment_count is ignored: the writer counts.
std::unique_ptr<FragmentSink> createTraceWriter(const std::string& path, const TraceHeader& header);

}  // namespace oit
