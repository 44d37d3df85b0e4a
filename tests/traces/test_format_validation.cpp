// Binary trace validation: every rule of FORMAT.md on a corrupted copy of a
// valid trace, asserting the byte offset, record and field in the message.
// Expected offsets come from the format: header_bytes = 64 + 64 x draws = 192
// here; record i starts at 192 + i x 32 (fp32) or 192 + i x 20 (unorm8).
#include <gtest/gtest.h>

#include <limits>

#include "test_format_helpers.hpp"
#include "traces/TraceIO.hpp"

namespace oit::test {
namespace {

constexpr uint32_t kW = 64, kH = 32;
constexpr size_t kHeaderBytes = 192;
constexpr size_t kCount = 10;

class FormatValidation : public ::testing::Test {
 protected:
  // Writes a valid trace and returns its bytes for corruption.
  std::string validBytes(ColourEncoding enc = ColourEncoding::Fp32, size_t count = kCount) {
    const auto h = makeHeader(kW, kH, enc,
                              {{0, DrawClass::Opaque, "floor"}, {1, DrawClass::Transparent, "glass"}},
                              CameraPlanes{0.5f, 50.0f});
    writeTrace(path_, h, makeFragments(count, kW, kH, {0, 1}));
    return readFile(path_);
  }
  // Opens (and reads through) the corrupted bytes; returns the error message.
  std::string errorFor(const std::string& bytes, size_t batch = 4) {
    writeFile(path_, bytes);
    return traceErrorOf([&] { readAll(path_, {.batch_records = batch}); });
  }
  std::string errorAtOpen(const std::string& bytes) {
    writeFile(path_, bytes);
    return traceErrorOf([&] { openTrace(path_); });
  }

  TempDir dir_;
  std::string path_ = dir_.path("p.oitt");
};

TEST_F(FormatValidation, ValidTraceReads) {
  writeFile(path_, validBytes());
  const auto r = readAll(path_);
  EXPECT_EQ(r.fragments.size(), kCount);
  EXPECT_EQ(r.header.draws.size(), 2u);
}

TEST_F(FormatValidation, BadMagic) {
  std::string b = validBytes();
  b[3] = 'X';
  EXPECT_TRUE(contains(errorAtOpen(b), {path_ + ": byte offset 0, field magic: bad magic: expected "
                                                "89 4F 49 54 54 0D 0A 1A, found 89 4F 49 58"}));
  EXPECT_TRUE(contains(errorAtOpen("# oitsim-trace v1\n# width 4\n"),
                       {"byte offset 0", "field magic", "looks like a CSV trace"}));
}

TEST_F(FormatValidation, EmptyAndShortFiles) {
  EXPECT_TRUE(contains(errorAtOpen(""), {path_ + ": byte offset 0, field header: truncated header"}));
  EXPECT_TRUE(contains(errorAtOpen(validBytes().substr(0, 40)),
                       {"byte offset 40, field header: truncated header: the file ends at byte "
                        "offset 40, the fixed header needs 64 bytes"}));
}

TEST_F(FormatValidation, TruncatedDrawTable) {
  EXPECT_TRUE(contains(errorAtOpen(validBytes().substr(0, 150)),
                       {"byte offset 150, field header", "inside draw table entry 1",
                        "header_bytes is 192"}));
}

TEST_F(FormatValidation, UnsupportedVersion) {
  std::string b = validBytes();
  poke<uint32_t>(b, 8, 3);
  EXPECT_TRUE(contains(errorAtOpen(b), {path_ + ": byte offset 8, field version: unsupported "
                                                "version 3: this build reads versions 1 and 2"}));
}

TEST_F(FormatValidation, ZeroOrOversizedFrame) {
  std::string b = validBytes();
  poke<uint32_t>(b, 16, 0);
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 16, field width: width is 0"}));
  b = validBytes();
  poke<uint32_t>(b, 20, 0);
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 20, field height: height is 0"}));
  b = validBytes();
  poke<uint32_t>(b, 16, 65536);
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 16, field width: width 65536 exceeds 65535"}));
}

TEST_F(FormatValidation, BadEncodingAndRecordBytes) {
  std::string b = validBytes();
  poke<uint32_t>(b, 32, 2);
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 32, field encoding: bad encoding 2"}));
  b = validBytes();
  poke<uint32_t>(b, 36, 20);
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 36, field record_bytes: record_bytes 20 does "
                                        "not match encoding fp32 (expected 32)"}));
}

TEST_F(FormatValidation, FlagsCameraAndReserved) {
  std::string b = validBytes();
  poke<uint32_t>(b, 40, 3);
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 40, field flags: unknown flag bits 0x00000002"}));
  b = validBytes();
  poke<uint32_t>(b, 40, 0);  // planes still set
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 44, field camera", "flag"}));
  b = validBytes();
  poke<float>(b, 48, 0.25f);  // far < near
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 44, field camera: camera near 0.5 far 0.25"}));
  b = validBytes();
  poke<float>(b, 44, std::numeric_limits<float>::quiet_NaN());
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 44, field camera: camera near NaN"}));
  b = validBytes();
  b[61] = 1;
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 61, field reserved"}));
}

TEST_F(FormatValidation, BadHeaderBytesAndDrawCount) {
  std::string b = validBytes();
  poke<uint32_t>(b, 12, 128);  // too small for 2 draws
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 12, field header_bytes: header_bytes 128: "
                                        "expected a multiple of 64 and at least 192"}));
  b = validBytes();
  poke<uint32_t>(b, 12, 200);  // not a multiple of 64
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 12, field header_bytes"}));
  b = validBytes();
  poke<uint32_t>(b, 52, 2000000);
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 52, field draw_count"}));
}

TEST_F(FormatValidation, DrawTableErrors) {
  std::string b = validBytes();
  poke<uint32_t>(b, 128, 0);  // draw[1].id = draw[0].id
  EXPECT_TRUE(contains(errorAtOpen(b), {path_ + ": byte offset 128, field draw[1].id: duplicate "
                                                "draw id 0 (also draw table entry 0 at byte offset 64)"}));
  b = validBytes();
  poke<uint32_t>(b, 132, 2);
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 132, field draw[1].class: bad draw class 2"}));
  b = validBytes();
  std::fill(b.begin() + 72, b.begin() + 128, 'a');
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 72, field draw[0].name: name is not NUL-terminated"}));
  b = validBytes();
  b[72 + 10] = 'z';  // after "floor\0"
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 82, field draw[0].name", "NUL padding"}));
  b = validBytes();
  b[73] = '\t';
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 72, field draw[0].name: name contains control byte 0x09"}));
}

// Names are UTF-8 (FORMAT.md section 3): a reader that passed other bytes on
// made JSON writers (info --json, run's report) fail with no file named.
TEST_F(FormatValidation, DrawNameMustBeUtf8) {
  std::string b = validBytes();
  b[72] = '\xFF';  // "floor" -> "\xFFloor"
  EXPECT_TRUE(contains(errorAtOpen(b), {path_ + ": byte offset 72, field draw[0].name: name is not valid UTF-8: "
                                                "byte 0xFF at index 0 does not begin a well-formed character"}));
  // Every kind of ill-formed sequence (as "glass" at 136, draw[1]).
  for (const std::string bad : {"\xC3\x28", "\xC3", "\xC0\x80", "\xE0\x80\x80", "\xED\xA0\x80",
                                "\xF4\x90\x80\x80", "\xF8\x88\x80\x80\x80", "\x80", "ok\xE2\x82"}) {
    SCOPED_TRACE(testing::PrintToString(bad));
    b = validBytes();
    std::fill(b.begin() + 136, b.begin() + 192, '\0');
    std::copy(bad.begin(), bad.end(), b.begin() + 136);
    EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 136, field draw[1].name: name is not valid UTF-8"}));
  }
  // Well-formed multi-byte names read back unchanged.
  const std::string good = "caf\xC3\xA9 \xE2\x9C\x93 \xF0\x9F\xA6\x8A \xF4\x8F\xBF\xBF";
  b = validBytes();
  std::fill(b.begin() + 136, b.begin() + 192, '\0');
  std::copy(good.begin(), good.end(), b.begin() + 136);
  writeFile(path_, b);
  EXPECT_EQ(openTrace(path_)->header().draws[1].name, good);
}

TEST_F(FormatValidation, TruncatedRecordsDetectedAtOpen) {
  const std::string b = validBytes();
  const size_t end = kHeaderBytes + 3 * 32 + 10;
  EXPECT_TRUE(contains(errorAtOpen(b.substr(0, end)),
                       {path_ + ": byte offset 298, record 3: truncated: the file ends at byte "
                                "offset 298, inside record 3 (which starts at byte offset 288); "
                                "the header declares 10 records of 32 bytes, so the file should "
                                "be 512 bytes"}));
  // Cut on a record boundary: the first missing record is named.
  EXPECT_TRUE(contains(errorAtOpen(b.substr(0, kHeaderBytes + 7 * 32)), {"byte offset 416, record 7"}));
  EXPECT_TRUE(contains(errorAtOpen(b.substr(0, kHeaderBytes)), {"byte offset 192, record 0"}));
  const std::string u = validBytes(ColourEncoding::Unorm8);
  EXPECT_TRUE(contains(errorAtOpen(u.substr(0, kHeaderBytes + 5 * 20 + 19)),
                       {"byte offset 311, record 5: truncated", "records of 20 bytes"}));
}

TEST_F(FormatValidation, FileLongerThanHeaderSays) {
  std::string b = validBytes() + std::string(64, '\0');
  EXPECT_TRUE(contains(errorAtOpen(b), {path_ + ": byte offset 512, record 10, field fragment_count: "
                                                "count mismatch: the header declares 10 records but "
                                                "64 more bytes follow the last one, 2 whole records"}));
  b = validBytes();
  poke<uint64_t>(b, 24, 1ull << 62);  // absurd count: reported as truncation, no overflow
  EXPECT_TRUE(contains(errorAtOpen(b), {"byte offset 512, record 10: truncated"}));
}

TEST_F(FormatValidation, UnfinishedWriterSentinel) {
  std::string b = validBytes();
  poke<uint64_t>(b, 24, UINT64_MAX);
  EXPECT_TRUE(contains(errorAtOpen(b), {path_ + ": byte offset 24, field fragment_count: "
                                                "fragment_count is the unfinished-writer sentinel",
                                        "never committed"}));
}

struct RecordCase {
  const char* field;
  size_t fp32_offset, unorm8_offset;
  void (*corrupt)(std::string& b, size_t at);  // at = the field's byte offset
  const char* message;
};

const float kNaN = std::numeric_limits<float>::quiet_NaN();
const float kInf = std::numeric_limits<float>::infinity();

const RecordCase kRecordCases[] = {
    {"x", 0, 0, [](std::string& b, size_t at) { poke<uint16_t>(b, at, 64); },
     "x 64 outside the frame, expected 0 <= x < 64 (the width)"},
    {"y", 2, 2, [](std::string& b, size_t at) { poke<uint16_t>(b, at, 65535); },
     "y 65535 outside the frame, expected 0 <= y < 32 (the height)"},
    {"z", 4, 4, [](std::string& b, size_t at) { poke<float>(b, at, 1.5f); }, "depth 1.5 outside [0,1]"},
    {"z", 4, 4, [](std::string& b, size_t at) { poke<float>(b, at, kNaN); },
     "depth is NaN, expected a finite value in [0,1]"},
    {"z", 4, 4, [](std::string& b, size_t at) { poke<float>(b, at, kInf); }, "depth is +Inf"},
    {"z", 4, 4, [](std::string& b, size_t at) { poke<float>(b, at, -1e-30f); }, "depth -1e-30 outside [0,1]"},
    {"draw", 28, 16, [](std::string& b, size_t at) { poke<uint32_t>(b, at, 9); },
     "unknown draw id 9: not in the header's draw table"},
};

TEST_F(FormatValidation, RecordFieldErrorsNameOffsetRecordAndField) {
  for (ColourEncoding enc : {ColourEncoding::Fp32, ColourEncoding::Unorm8}) {
    const size_t rb = enc == ColourEncoding::Fp32 ? 32 : 20;
    for (const RecordCase& c : kRecordCases) {
      SCOPED_TRACE(std::string(c.field) + " " + toString(enc) + " " + c.message);
      std::string b = validBytes(enc);
      const size_t at = kHeaderBytes + 3 * rb + (enc == ColourEncoding::Fp32 ? c.fp32_offset : c.unorm8_offset);
      c.corrupt(b, at);
      EXPECT_TRUE(contains(errorFor(b), {path_ + ": byte offset " + std::to_string(at) +
                                             ", record 3, field " + c.field + ": " + c.message}));
    }
  }
}

TEST_F(FormatValidation, ColourErrors) {
  // fp32 only: unorm8 colours cannot leave [0,1].
  const char* names[] = {"r", "g", "b", "a"};
  const float bad[] = {kNaN, -kInf, 1.0000001f, -0.5f};
  const char* expected[] = {"is NaN", "is -Inf", "1.0000001 outside [0,1]", "-0.5 outside [0,1]"};
  for (size_t c = 0; c < 4; ++c) {
    for (size_t v = 0; v < 4; ++v) {
      std::string b = validBytes();
      const size_t at = kHeaderBytes + 6 * 32 + 8 + 4 * c;
      poke<float>(b, at, bad[v]);
      EXPECT_TRUE(contains(errorFor(b), {"byte offset " + std::to_string(at) + ", record 6, field " +
                                             names[c] + ": colour " + names[c] + " " + expected[v]}));
    }
  }
}

TEST_F(FormatValidation, ExampleMessageFromTheSpec) {
  std::string b = validBytes();
  poke<float>(b, kHeaderBytes + 3 * 32 + 4, 1.5f);
  EXPECT_EQ(errorFor(b), path_ + ": byte offset 292, record 3, field z: depth 1.5 outside [0,1]");
}

TEST_F(FormatValidation, EveryBatchIsValidatedBeforeItIsHandedOut) {
  std::string b = validBytes(ColourEncoding::Fp32, 2600);
  poke<float>(b, kHeaderBytes + 2500 * 32 + 12, 7.0f);  // record 2500, g
  writeFile(path_, b);
  auto src = openTrace(path_, {.batch_records = 1000});
  EXPECT_EQ(src->next().size(), 1000u);
  EXPECT_EQ(src->next().size(), 1000u);
  EXPECT_TRUE(contains(traceErrorOf([&] { src->next(); }),
                       {"byte offset " + std::to_string(kHeaderBytes + 2500 * 32 + 12),
                        "record 2500, field g: colour g 7 outside [0,1]"}));
  EXPECT_EQ(src->position(), 2000u);  // the bad batch was not handed out
  try {
    src->next();
    ADD_FAILURE() << "the bad batch must throw again";
  } catch (const TraceError& e) {  // accessors carry the same facts as the message
    EXPECT_EQ(e.file(), path_);
    EXPECT_EQ(e.byteOffset(), kHeaderBytes + 2500 * 32 + 12);
    EXPECT_EQ(e.record(), std::optional<uint64_t>(2500));
    EXPECT_EQ(e.field(), "g");
    EXPECT_FALSE(e.line().has_value());
  }
}

}  // namespace
}  // namespace oit::test
