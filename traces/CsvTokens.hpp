// What the CSV form's reader (CsvTraceReader.cpp), its writer (CsvTraceWriter.cpp)
// and the draw-state line parser (DrawStateTable.cpp) share: the column line and
// the tokenizer of comment lines.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace oit::detail {

inline constexpr std::string_view kCsvColumnLine = "draw,prim,x,y,z,r,g,b,a,opaque";

inline bool isCsvBlank(char c) { return c == ' ' || c == '\t'; }

// Tokens of a comment line, with their byte offsets in the file.
class CsvTokens {
 public:
  CsvTokens(std::string_view line, uint64_t line_offset) : s_(line), base_(line_offset) {}
  // Next whitespace-separated token; empty at end of line.
  std::string_view next() {
    while (i_ < s_.size() && isCsvBlank(s_[i_])) ++i_;
    start_ = i_;
    while (i_ < s_.size() && !isCsvBlank(s_[i_])) ++i_;
    return s_.substr(start_, i_ - start_);
  }
  uint64_t offset() const { return base_ + start_; }  // of the last token
  // Skips blanks; the offset and remaining text.
  std::string_view rest() {
    while (i_ < s_.size() && isCsvBlank(s_[i_])) ++i_;
    start_ = i_;
    return s_.substr(i_);
  }

 private:
  std::string_view s_;
  uint64_t base_;
  size_t i_ = 0, start_ = 0;
};

}  // namespace oit::detail
