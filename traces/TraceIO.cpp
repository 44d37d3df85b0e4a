#include "traces/TraceIO.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "traces/TraceBackends.hpp"

namespace oit {

namespace {

std::string composeMessage(const std::string& file, std::optional<uint64_t> line,
                           std::optional<uint64_t> byte_offset, std::optional<uint64_t> record,
                           const std::string& field, const std::string& what) {
  std::string m = file + ": ";
  if (line) m += fmt::format("line {}, ", *line);
  if (byte_offset) m += fmt::format("byte offset {}, ", *byte_offset);
  if (record) m += fmt::format("record {}, ", *record);
  // A CSV record's field is a column; elsewhere (binary, CSV metadata) a field.
  if (!field.empty()) m += fmt::format("{} {}, ", line && record ? "column" : "field", field);
  if (m.ends_with(", ")) m.replace(m.size() - 2, 2, ": ");
  return m + what;
}

}  // namespace

TraceError::TraceError(std::string file, std::optional<uint64_t> line,
                       std::optional<uint64_t> byte_offset, std::optional<uint64_t> record,
                       std::string field, const std::string& what)
    : std::runtime_error(composeMessage(file, line, byte_offset, record, field, what)),
      file_(std::move(file)),
      byte_offset_(byte_offset.value_or(0)),
      record_(record),
      field_(std::move(field)),
      line_(line) {}

TraceError::TraceError(std::string file, uint64_t byte_offset, std::optional<uint64_t> record,
                       std::string field, const std::string& what)
    : TraceError(std::move(file), std::nullopt, byte_offset, record, std::move(field), what) {}

TraceError::TraceError(std::string file, const std::string& what)
    : TraceError(std::move(file), std::nullopt, std::nullopt, std::nullopt, std::string(), what) {}

TraceError TraceError::inCsv(std::string file, uint64_t line, uint64_t byte_offset,
                             std::optional<uint64_t> record, std::string field,
                             const std::string& what) {
  return TraceError(std::move(file), line, byte_offset, record, std::move(field), what);
}

namespace detail {

bool isCsvPath(const std::string& path) {
  if (path.size() < 4) return false;
  std::string ext = path.substr(path.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return ext == ".csv";
}

}  // namespace detail

bool isCsvTracePath(const std::string& path) { return detail::isCsvPath(path); }

std::unique_ptr<FragmentSource> openTrace(const std::string& path, const OpenOptions& opts) {
  if (opts.batch_records == 0) throw std::invalid_argument("OpenOptions.batch_records must be > 0");
  if (path.empty()) throw TraceError("''", "expected a trace file, got an empty path");
  return detail::isCsvPath(path) ? detail::openCsvTrace(path, opts)
                                 : detail::openBinaryTrace(path, opts);
}

std::unique_ptr<FragmentSink> createTraceWriter(const std::string& path, const TraceHeader& header) {
  return detail::isCsvPath(path) ? detail::createCsvWriter(path, header)
                                 : detail::createBinaryWriter(path, header);
}

}  // namespace oit
