// The validation rules of trace format v1, shared by every reader and writer
// (binary and CSV) so that a writer can never produce what a reader rejects.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "traces/Fragment.hpp"
#include "traces/TraceFormat.hpp"

namespace oit::detail {

// Membership test for draw ids, fast enough for the per-record loop.
class DrawSet {
 public:
  DrawSet() = default;
  explicit DrawSet(const std::vector<DrawInfo>& draws);

  bool contains(uint32_t id) const {
    if (dense_) return known_[std::min<uint32_t>(id, limit_)] != 0;
    return std::binary_search(sorted_.begin(), sorted_.end(), id);
  }
  bool dense() const { return dense_; }
  // Dense form only: known()[min(id, limit())] != 0 iff id is in the set.
  const uint8_t* known() const { return known_.data(); }
  uint32_t limit() const { return limit_; }
  // A draw of the table whose fragments are not recorded (format v2, not modelled).
  bool unrecorded(uint32_t id) const { return std::binary_search(unrecorded_.begin(), unrecorded_.end(), id); }

 private:
  bool dense_ = true;
  // Dense: one byte per id up to the largest, plus a trailing 0 that every
  // larger id is clamped to (no branch in the loop).
  std::vector<uint8_t> known_ = {0};
  uint32_t limit_ = 0;
  std::vector<uint32_t> sorted_;  // sparse form: ids too large for a table
  std::vector<uint32_t> unrecorded_;
};

struct RecordRules {
  uint32_t width = 0;
  uint32_t height = 0;
  DrawSet draws;
};

// Index of the first record that breaks a rule, or fs.size() if all are valid.
size_t firstInvalid(std::span<const Fragment> fs, const RecordRules& rules);

// Decodes n unorm8 records (format_v1 section 4.2) from src into dst, checking
// them on the way; returns the index of the first invalid record, or n.
size_t decodeUnorm8(const unsigned char* src, Fragment* dst, size_t n, const RecordRules& rules);

struct Violation {
  format_v1::Field field;
  std::string message;  // what is wrong and what was expected
};
// The first broken rule of f (in field order), or nullopt.
std::optional<Violation> checkRecord(const Fragment& f, const RecordRules& rules);

// Messages shared with the CSV parser (it checks x/y before narrowing to u16).
std::string coordMessage(format_v1::Field f, uint64_t value, uint32_t limit);
// nullopt when v is finite and in [0,1].
std::optional<std::string> unitMessage(format_v1::Field f, float v);

// Validates a header given to a writer; throws TraceError naming `file`, the
// binary byte offset of the field and the field. Returns h, so that a writer
// checks its header before it creates its temporary file.
const TraceHeader& checkHeaderForWrite(const std::string& file, const TraceHeader& h);
// Checks a draw name (length, no control bytes, valid UTF-8); returns the problem or nullopt.
std::optional<std::string> drawNameProblem(const std::string& name);
// Index of the first byte of s that does not start a well-formed UTF-8
// character (no overlong forms, surrogates or code points above U+10FFFF), or nullopt.
std::optional<size_t> invalidUtf8At(std::string_view s);
// Length of the well-formed UTF-8 character at s[i] (1 for ASCII), 0 if none starts there.
size_t utf8CharBytes(std::string_view s, size_t i);
// Checks camera planes; returns the problem or nullopt.
std::optional<std::string> cameraProblem(float near_plane, float far_plane);

// unorm8 colour: byte b decodes to exactly b / 255.0f; encoding rounds to nearest,
// so encode(decode(b)) == b and the CSV form of an unorm8 trace is lossless.
extern const std::array<float, 256> kUnorm8ToFloat;
inline uint8_t encodeUnorm8(float v) {  // v in [0,1]
  // In double the product is exact, so this is true round-to-nearest (ties up).
  return static_cast<uint8_t>(static_cast<double>(v) * 255.0 + 0.5);
}
inline float quantizeUnorm8(float v) { return kUnorm8ToFloat[encodeUnorm8(v)]; }

}  // namespace oit::detail
