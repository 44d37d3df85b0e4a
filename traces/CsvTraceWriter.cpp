// CSV form of trace format v1 (FORMAT.md, "CSV form"): the buffered writer.
// Floats are written in shortest round-trip form. The reader is CsvTraceReader.cpp.
#include <fmt/format.h>

#include <algorithm>
#include <memory>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "traces/AtomicFile.hpp"
#include "traces/CsvTokens.hpp"
#include "traces/DrawStateTable.hpp"
#include "traces/TraceBackends.hpp"
#include "traces/TraceFormat.hpp"
#include "traces/TraceRules.hpp"

namespace oit::detail {

namespace fv = format_v1;

namespace {

// Quotes a draw name: backslash and double quote are escaped (names hold no
// control bytes, so nothing else needs it).
std::string quoteName(const std::string& name) {
  std::string q = "\"";
  for (char c : name) {
    if (c == '"' || c == '\\') q += '\\';
    q += c;
  }
  return q + '"';
}

class CsvWriter final : public FragmentSink {
 public:
  CsvWriter(const std::string& path, const TraceHeader& header);
  void write(const Fragment& f) override { write(std::span<const Fragment>(&f, 1)); }
  void write(std::span<const Fragment> fs) override;
  void commit() override { file_.commit(); }
  uint64_t written() const override { return written_; }

 private:
  TraceHeader header_;
  RecordRules rules_;
  std::unordered_map<uint32_t, DrawClass> classes_;
  AtomicFile file_;
  uint64_t first_record_line_ = 0;
  uint64_t written_ = 0;
  fmt::memory_buffer row_;
};

CsvWriter::CsvWriter(const std::string& path, const TraceHeader& header)
    : header_(checkHeaderForWrite(path, header)), file_(path) {
  rules_.width = header_.width;
  rules_.height = header_.height;
  rules_.draws = DrawSet(header_.draws);
  for (const DrawInfo& d : header_.draws) classes_[d.id] = d.cls;
  fmt::memory_buffer m;
  auto out = std::back_inserter(m);
  fmt::format_to(out, "# oitsim-trace v{}\n# width {}\n# height {}\n", header_.version, header_.width,
                 header_.height);
  if (header_.camera)
    fmt::format_to(out, "# camera {} {}\n", header_.camera->near_plane, header_.camera->far_plane);
  fmt::format_to(out, "# encoding {}\n", toString(header_.encoding));
  for (const DrawInfo& d : header_.draws) {
    fmt::format_to(out, "# draw {} {} {}\n", d.id, toString(d.cls), quoteName(d.name));
    if (d.state) fmt::format_to(out, "# draw-state {}\n", drawStateCsv(d));
  }
  fmt::format_to(out, "{}\n", kCsvColumnLine);
  first_record_line_ = static_cast<uint64_t>(std::count(m.begin(), m.end(), '\n')) + 1;
  file_.append(m.data(), m.size());
}

void CsvWriter::write(std::span<const Fragment> fs) {
  if (file_.committed()) throw std::logic_error("FragmentSink::write after commit()");
  const size_t bad = firstInvalid(fs, rules_);
  const bool unorm8 = header_.encoding == ColourEncoding::Unorm8;
  for (const Fragment& f0 : fs.first(bad)) {
    Fragment f = f0;
    if (unorm8) {
      f.r = quantizeUnorm8(f.r);
      f.g = quantizeUnorm8(f.g);
      f.b = quantizeUnorm8(f.b);
      f.a = quantizeUnorm8(f.a);
    }
    const int opaque = classes_.find(f.draw)->second == DrawClass::Opaque ? 1 : 0;
    row_.clear();
    fmt::format_to(std::back_inserter(row_), "{},{},{},{},{},{},{},{},{},{}\n", f.draw, f.prim, f.x,
                   f.y, f.z, f.r, f.g, f.b, f.a, opaque);
    file_.append(row_.data(), row_.size());
    ++written_;
  }
  if (bad < fs.size()) {
    const Violation v = *checkRecord(fs[bad], rules_);
    throw TraceError::inCsv(file_.path(), first_record_line_ + written_, file_.size(), written_,
                            fv::fieldName(v.field), v.message);
  }
}

}  // namespace

std::unique_ptr<FragmentSink> createCsvWriter(const std::string& path, const TraceHeader& header) {
  return std::make_unique<CsvWriter>(path, header);
}

}  // namespace oit::detail
