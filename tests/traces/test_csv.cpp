// CSV form of trace format v1: lossless round trips with the binary form,
// metadata, and every CSV error naming file, line, byte offset, record, column.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <limits>

#include "test_format_helpers.hpp"
#include "traces/TraceIO.hpp"

namespace oit::test {
namespace {

// Canonical (as the writer prints it): shortest round-trip floats, e.g.
// 0.33333334 is 1/3 in fp32, 1e-45 the smallest subnormal, 0.99999994 the
// largest float below 1.
const std::string kCanonicalFp32 =
    "# oitsim-trace v1\n"
    "# width 16\n"
    "# height 8\n"
    "# camera 0.1 100\n"
    "# encoding fp32\n"
    "# draw 2 opaque \"wall\"\n"
    "# draw 5 transparent \"say \\\"hi\\\" \\\\ ok\"\n"
    "# draw 9 transparent \"unused\"\n"
    "draw,prim,x,y,z,r,g,b,a,opaque\n"
    "2,0,0,0,0.5,1,0,0,1,1\n"
    "2,1,15,7,1,0.1,0.2,0.3,1,1\n"
    "5,0,3,4,0.33333334,0.5,0.25,1e-07,0.75,0\n"
    "5,4294967295,3,4,1e-45,0,1,0.99999994,0.5,0\n";

class Csv : public ::testing::Test {
 protected:
  std::string csvError(const std::string& text, OpenOptions opts = {}) {
    writeFile(csv_, text);
    return traceErrorOf([&] { readAll(csv_, opts); });
  }
  TempDir dir_;
  std::string csv_ = dir_.path("t.csv");
  std::string bin_ = dir_.path("t.oitt");
};

// Copies any trace to any path through the public API (like `oitsim convert`).
void convert(const std::string& in, const std::string& out, OpenOptions opts = {}) {
  auto src = openTrace(in, opts);
  auto sink = createTraceWriter(out, src->header());
  for (auto b = src->next(); !b.empty(); b = src->next()) sink->write(b);
  sink->commit();
}

TEST_F(Csv, CanonicalFp32IsReadAsWritten) {
  writeFile(csv_, kCanonicalFp32);
  const ReadResult r = readAll(csv_);
  EXPECT_EQ(r.header.width, 16u);
  EXPECT_EQ(r.header.height, 8u);
  ASSERT_TRUE(r.header.camera.has_value());
  EXPECT_EQ(r.header.camera->near_plane, 0.1f);
  EXPECT_EQ(r.header.camera->far_plane, 100.0f);
  EXPECT_EQ(r.header.encoding, ColourEncoding::Fp32);
  EXPECT_EQ(r.header.fragment_count, 4u);
  ASSERT_EQ(r.header.draws.size(), 3u);
  EXPECT_EQ(r.header.draws[1].id, 5u);
  EXPECT_EQ(r.header.draws[1].cls, DrawClass::Transparent);
  EXPECT_EQ(r.header.draws[1].name, "say \"hi\" \\ ok");
  EXPECT_EQ(r.header.draws[2].name, "unused");  // declared draws without rows are kept
  const std::vector<Fragment> expected = {
      {0, 0, 0.5f, 1, 0, 0, 1, 0, 2},
      {15, 7, 1, 0.1f, 0.2f, 0.3f, 1, 1, 2},
      {3, 4, 1.0f / 3.0f, 0.5f, 0.25f, 1e-7f, 0.75f, 0, 5},
      {3, 4, std::numeric_limits<float>::denorm_min(), 0, 1, std::nextafter(1.0f, 0.0f), 0.5f,
       UINT32_MAX, 5},
  };
  EXPECT_TRUE(bitEqual(r.fragments, expected));
}

TEST_F(Csv, CsvToBinaryToCsvIsByteIdentical) {
  writeFile(csv_, kCanonicalFp32);
  convert(csv_, bin_);
  const std::string back = dir_.path("back.csv");
  convert(bin_, back);
  EXPECT_EQ(readFile(back), kCanonicalFp32);
}

TEST_F(Csv, Unorm8CsvToBinaryToCsvIsByteIdentical) {
  std::string text =
      "# oitsim-trace v1\n# width 300\n# height 2\n# encoding unorm8\n"
      "# draw 0 transparent \"levels\"\ndraw,prim,x,y,z,r,g,b,a,opaque\n";
  for (int k = 0; k < 256; ++k) {
    const float v = static_cast<float>(k) / 255.0f;
    const float w = static_cast<float>(255 - k) / 255.0f;
    text += fmt::format("0,{},{},1,{},{},{},{},{},0\n", k, k, v * 0.5f, v, w, v, w);
  }
  writeFile(csv_, text);
  convert(csv_, bin_);
  EXPECT_EQ(std::filesystem::file_size(bin_), 128u + 256 * 20);
  const std::string back = dir_.path("back.csv");
  convert(bin_, back);
  EXPECT_EQ(readFile(back), text);
}

TEST_F(Csv, BinaryToCsvToBinaryIsBitIdentical) {
  for (ColourEncoding enc : {ColourEncoding::Fp32, ColourEncoding::Unorm8}) {
    for (bool camera : {true, false}) {
      SCOPED_TRACE(std::string(toString(enc)) + (camera ? " camera" : " no camera"));
      const std::vector<DrawInfo> draws = {{3, DrawClass::Transparent, "glass, \"tinted\""},
                                           {1, DrawClass::Opaque, "floor"},
                                           {4000000000u, DrawClass::Transparent, std::string(55, 'q')}};
      std::optional<CameraPlanes> cam;
      if (camera) cam = CameraPlanes{0.013f, 1234.5679f};
      const auto h = makeHeader(1280, 720, enc, draws, cam);
      writeTrace(bin_, h, makeFragments(20000, 1280, 720, {3, 1, 4000000000u}, 7));
      convert(bin_, csv_);
      const std::string bin2 = dir_.path("t2.oitt");
      convert(csv_, bin2);
      EXPECT_EQ(readFile(bin2), readFile(bin_));  // header, draw table and records
      EXPECT_TRUE(bitEqual(readAll(bin2).fragments, readAll(bin_).fragments));
    }
  }
}

TEST_F(Csv, Unorm8CsvValuesAreQuantizedOnRead) {
  // A hand-written unorm8 CSV reads as its binary form would: colours k/255.
  writeFile(csv_, "# width 2\n# height 2\n# encoding unorm8\ndraw,prim,x,y,z,r,g,b,a,opaque\n"
                  "0,0,1,1,0.3,0.3,0.5,0.002,1,0\n");
  const auto r = readAll(csv_);
  ASSERT_EQ(r.fragments.size(), 1u);
  EXPECT_EQ(r.fragments[0].z, 0.3f);  // depth stays fp32
  EXPECT_EQ(r.fragments[0].r, 77.0f / 255.0f);
  EXPECT_EQ(r.fragments[0].g, 128.0f / 255.0f);
  EXPECT_EQ(r.fragments[0].b, 1.0f / 255.0f);
  EXPECT_EQ(r.fragments[0].a, 1.0f);
}

TEST_F(Csv, FrameSizeFromOptionsWhenTheCsvHasNone) {
  const std::string text = "draw,prim,x,y,z,r,g,b,a,opaque\n4,0,99,49,0.5,1,1,1,1,1\n";
  writeFile(csv_, text);
  const auto r = readAll(csv_, {.width = 100, .height = 50});
  EXPECT_EQ(r.header.width, 100u);
  EXPECT_EQ(r.header.height, 50u);
  EXPECT_EQ(r.header.encoding, ColourEncoding::Fp32);
  EXPECT_FALSE(r.header.camera.has_value());
  ASSERT_EQ(r.header.draws.size(), 1u);
  EXPECT_EQ(r.header.draws[0].name, "draw4");  // undeclared: named by id, class from column
  EXPECT_EQ(r.header.draws[0].cls, DrawClass::Opaque);
  EXPECT_TRUE(contains(csvError(text), {csv_ + ": line 1, byte offset 0, field width: no frame size",
                                        "pass --width and --height"}));
  // The comment header wins over the options.
  writeFile(csv_, "# width 8\n# height 4\n" + text);
  EXPECT_TRUE(contains(traceErrorOf([&] { readAll(csv_, {.width = 100, .height = 50}); }),
                       {"line 4", "record 0, column x: x 99 outside the frame, expected 0 <= x < 8"}));
}

TEST_F(Csv, UndeclaredDrawsFollowDeclaredOnesInFirstAppearanceOrder) {
  writeFile(csv_, "# width 4\n# height 4\n# draw 8 opaque \"wall\"\n"
                  "draw,prim,x,y,z,r,g,b,a,opaque\n"
                  "6,0,0,0,0,0,0,0,0,0\n8,0,0,0,0,0,0,0,0,1\n2,0,0,0,0,0,0,0,0,1\n6,1,0,0,0,0,0,0,0,0\n");
  const auto r = readAll(csv_);
  ASSERT_EQ(r.header.draws.size(), 3u);
  EXPECT_EQ(r.header.draws[0].id, 8u);
  EXPECT_EQ(r.header.draws[1].id, 6u);
  EXPECT_EQ(r.header.draws[1].cls, DrawClass::Transparent);
  EXPECT_EQ(r.header.draws[2].name, "draw2");
  EXPECT_EQ(r.header.draws[2].cls, DrawClass::Opaque);
}

TEST_F(Csv, CommentsBlankLinesCrlfAndBomAreAccepted) {
  writeFile(csv_, "\xEF\xBB\xBF# a free comment\r\n# width 4\r\n\r\n# height 4\r\ndraw,prim,x,y,z,r,g,b,a,opaque\r\n"
                  "1,0,1,1,0.5,0.5,0.5,0.5,0.5,0\r\n# between rows\r\n\r\n 1 , 1 ,2,2,0.5,0.5,0.5,0.5,0.5,0");
  const auto r = readAll(csv_);
  ASSERT_EQ(r.fragments.size(), 2u);
  EXPECT_EQ(r.fragments[1].prim, 1u);
  EXPECT_EQ(r.fragments[1].x, 2u);
}

TEST_F(Csv, BatchesAndRewind) {
  std::string text = "# width 4\n# height 4\ndraw,prim,x,y,z,r,g,b,a,opaque\n";
  for (int i = 0; i < 10; ++i) text += fmt::format("0,{},1,1,0.5,0.5,0.5,0.5,0.5,0\n", i);
  writeFile(csv_, text);
  auto src = openTrace(csv_, {.batch_records = 3});
  EXPECT_EQ(src->header().fragment_count, 10u);
  std::vector<uint32_t> prims;
  std::vector<size_t> sizes;
  for (auto b = src->next(); !b.empty(); b = src->next()) {
    sizes.push_back(b.size());
    for (const Fragment& f : b) prims.push_back(f.prim);
  }
  EXPECT_EQ(sizes, (std::vector<size_t>{3, 3, 3, 1}));
  EXPECT_EQ(prims, (std::vector<uint32_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
  src->rewind();
  EXPECT_EQ(src->position(), 0u);
  EXPECT_EQ(src->next()[0].prim, 0u);
  EXPECT_EQ(src->position(), 3u);
}

TEST_F(Csv, ZeroFragmentCsv) {
  writeFile(csv_, "# width 4\n# height 4\n# draw 1 opaque \"x\"\ndraw,prim,x,y,z,r,g,b,a,opaque\n");
  auto src = openTrace(csv_);
  EXPECT_EQ(src->header().fragment_count, 0u);
  EXPECT_EQ(src->header().draws.size(), 1u);
  EXPECT_TRUE(src->next().empty());
}

// Error at `needle` (first occurrence at or after the start of line `line`).
struct Where {
  uint64_t line, offset;
};
Where locate(const std::string& text, uint64_t line, const std::string& needle) {
  size_t pos = 0;
  for (uint64_t l = 1; l < line; ++l) pos = text.find('\n', pos) + 1;
  return {line, text.find(needle, pos)};
}

const std::string kHead = "# oitsim-trace v1\n# width 16\n# height 8\n# draw 1 transparent \"g\"\n"
                          "draw,prim,x,y,z,r,g,b,a,opaque\n";  // rows start at line 6

struct RowCase {
  std::string row;     // record 1, line 7
  std::string needle;  // where the error points, within the row
  std::string column, message;
};

TEST_F(Csv, RowErrorsNameLineByteOffsetRecordAndColumn) {
  const RowCase cases[] = {
      {"1,0,1,1,1.5,0,0,0,0,0", "1.5", "z", "depth 1.5 outside [0,1]"},
      {"1,0,1,1,nan,0,0,0,0,0", "nan", "z", "depth is NaN, expected a finite value in [0,1]"},
      {"1,0,1,1,0,inf,0,0,0,0", "inf", "r", "colour r is +Inf"},
      {"1,0,1,1,0,0,-0.5,0,0,0", "-0.5", "g", "colour g -0.5 outside [0,1]"},
      {"1,0,1,1,0,0,0,2,0,0", "2,0,0", "b", "colour b 2 outside [0,1]"},
      {"1,0,1,1,0,0,0,0,1e40,0", "1e40", "a", "'1e40' is not representable as fp32"},
      {"1,0,1,1,0.5x,0,0,0,0,0", "0.5x", "z", "'0.5x' is not a decimal number"},
      {"1,0,16,1,0,0,0,0,0,0", "16", "x", "x 16 outside the frame, expected 0 <= x < 16 (the width)"},
      {"1,0,1,99999,0,0,0,0,0,0", "99999", "y", "y 99999 outside the frame, expected 0 <= y < 8"},
      {"1,-3,1,1,0,0,0,0,0,0", "-3", "prim", "'-3' is not an unsigned decimal integer"},
      {"1,4294967296,1,1,0,0,0,0,0,0", "4294967296", "prim", "4294967296 is out of range (at most 4294967295)"},
      {"x1,0,1,1,0,0,0,0,0,0", "x1", "draw", "'x1' is not an unsigned decimal integer"},
      {"1,0,,1,0,0,0,0,0,0", ",,1", "x", "empty field"},
      {"1,0,1,1,0,0,0,0,0,2", "2", "opaque", "'2': expected 0 or 1"},
      {"1,0,1,1,0,0,0,0,0,1", "1\n", "opaque", "opaque 1 but draw 1 is transparent (declared by the comment header at line 4)"},
      {"3,0,1,1,0,0,0,0,0,1", "1\n", "opaque", "opaque 1 but draw 3 is transparent (its first row is at line 6)"},
  };
  for (const RowCase& c : cases) {
    SCOPED_TRACE(c.row);
    const std::string text = kHead + "3,0,0,0,0,0,0,0,0,0\n" + c.row + "\n1,0,0,0,0,0,0,0,0,0\n";
    Where w = locate(text, 7, c.needle);
    if (c.needle == ",,1") w.offset += 1;  // the empty field starts after the first comma
    EXPECT_TRUE(contains(csvError(text), {fmt::format("{}: line 7, byte offset {}, record 1, column {}: {}",
                                                      csv_, w.offset, c.column, c.message)}));
  }
}

// A control byte in a field is shown escaped: what() is printed as a C string,
// so a raw NUL would cut the message off after the field's first bytes.
TEST_F(Csv, ControlBytesInAFieldAreEscapedAndTheMessageIsWhole) {
  const std::string row = std::string("1,0,1,1,0.5\0,0,0,0,0.5,0", 24);
  const std::string text = kHead + row + "\n";
  const std::string e = csvError(text);
  EXPECT_EQ(e.find('\0'), std::string::npos);
  EXPECT_EQ(e, fmt::format("{}: line 6, byte offset {}, record 0, column z: '0.5\\x00' is not a decimal number", csv_,
                           kHead.size() + 8))
      << e;
  const std::string tab = kHead + "1,0,1,1,0.5,0\x01,0,0,0.5,0\n";
  EXPECT_NE(csvError(tab).find("column r: '0\\x01' is not a decimal number"), std::string::npos) << csvError(tab);
}

// Bytes >= 0x80 that are not well-formed UTF-8 text are shown as \xNN too (a
// binary file read as CSV printed its raw bytes); UTF-8 text stays as it is.
TEST_F(Csv, NonTextBytesAreEscapedAndBinaryFormsAreNamed) {
  const std::string cols = "draw,prim,x,y,z,r,g,b,a,opaque";
  const std::string bad = csvError("\xFF\xFE" "d\xC2\x85\n");
  EXPECT_EQ(bad, fmt::format("{}: line 1, byte offset 0, field header: expected the column line '{}', found "
                             "'\\xff\\xfed\\xc2\\x85'",
                             csv_, cols));
  EXPECT_EQ(std::count_if(bad.begin(), bad.end(), [](char c) { return static_cast<unsigned char>(c) >= 0x80; }), 0);
  EXPECT_EQ(csvError("caf\xC3\xA9\n"),
            fmt::format("{}: line 1, byte offset 0, field header: expected the column line '{}', found 'caf\xC3\xA9'",
                        csv_, cols));
  // A binary trace named .csv, and a gzipped CSV, say what they are.
  writeTrace(bin_, makeHeader(4, 4, ColourEncoding::Fp32, {{1, DrawClass::Opaque, "o"}}), {});
  writeFile(csv_, readFile(bin_));
  EXPECT_EQ(traceErrorOf([&] { openTrace(csv_); }),
            csv_ + ": line 1, byte offset 0, field header: found 89 4F 49 54 54 0D 0A 1A, the magic of a binary "
                   "trace: this looks like a binary .oitt trace (the .csv extension makes it read as CSV; rename it "
                   "or convert it)");
  writeFile(csv_, std::string("\x1F\x8B\x08\x00\x00\x00\x00\x00\x00\x03\xED\xC1", 12));
  EXPECT_EQ(traceErrorOf([&] { openTrace(csv_); }),
            csv_ + ": line 1, byte offset 0, field header: found 1F 8B 08 00 00 00 00 00: the file is "
                   "gzip-compressed: decompress first (gunzip)");
}

TEST_F(Csv, WrongColumnCounts) {
  const std::string short_row = kHead + "1,0,1,1,0,0,0,0,0\n";
  EXPECT_TRUE(contains(csvError(short_row),
                       {fmt::format("line 6, byte offset {}, record 0, column opaque: row has 9 "
                                    "columns, expected 10",
                                    short_row.size() - 1)}));
  const std::string long_row = kHead + "1,0,1,1,0,0,0,0,0,0,7\n";
  EXPECT_TRUE(contains(csvError(long_row),
                       {fmt::format("line 6, byte offset {}, record 0, column opaque: row has more "
                                    "than 10 columns",
                                    long_row.size() - 3)}));
}

TEST_F(Csv, HeaderAndMetadataErrors) {
  struct Case {
    std::string text;
    uint64_t line;
    std::string needle, field, message;
  };
  const std::string cols = "draw,prim,x,y,z,r,g,b,a,opaque\n";
  const Case cases[] = {
      {"# width 4\n# height 4\ndraw,prim,x,y,z,r,g,b,a\n", 3, "draw", "header",
       "expected the column line 'draw,prim,x,y,z,r,g,b,a,opaque', found 'draw,prim,x,y,z,r,g,b,a'"},
      {"# oitsim-trace v3\n" + cols, 1, "v3", "oitsim-trace", "unsupported version 'v3': this build reads v1 and v2"},
      {"# width 0\n" + cols, 1, "0", "width", "width '0': expected an integer in 1..65535"},
      {"# width 4\n# height 70000\n" + cols, 2, "70000", "height", "expected an integer in 1..65535"},
      {"# width 4\n# width 5\n" + cols, 2, "width", "width", "duplicate '# width' line"},
      {"# encoding rgb565\n" + cols, 1, "rgb565", "encoding", "bad encoding 'rgb565': expected fp32 or unorm8"},
      {"# camera 5 1\n" + cols, 1, "1\n", "camera", "camera near 5 far 1: expected finite planes"},
      {"# draw 1 opaque \"a\"\n# draw 1 transparent \"b\"\n" + cols, 2, "1 t", "draw",
       "duplicate draw id 1 (also declared at line 1)"},
      {"# draw 1 glassy \"a\"\n" + cols, 1, "glassy", "draw", "bad draw class 'glassy'"},
      {"# draw 1 opaque a\n" + cols, 1, "a\n", "draw", "expected the draw name in double quotes"},
      {"# draw 1 opaque \"a\\n\"\n" + cols, 1, "\"a", "draw", "bad escape in the draw name"},
      {"# draw 1 opaque \"" + std::string(56, 'n') + "\"\n" + cols, 1, "\"n", "draw", "name is 56 bytes long"},
      {"# draw 1 transparent \"\xC3\x28\"\n" + cols, 1, "\"\xC3", "draw",
       "name is not valid UTF-8: byte 0xC3 at index 0 does not begin a well-formed character"},
      {"# width 4\n# height 4\n" + cols + "# width 5\n", 4, "width", "width",
       "'# width' metadata must come before the column line"},
      {"# width 4\n", 1, "", "header", "no column line"},
      {"", 1, "", "header", "no column line 'draw,prim,x,y,z,r,g,b,a,opaque' (empty file or only comments)"},
      {"\n\n", 2, "", "header", "no column line"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.text);
    const uint64_t offset = c.needle.empty() ? c.text.size() : locate(c.text, c.line, c.needle).offset;
    EXPECT_TRUE(contains(csvError(c.text, {.width = 4, .height = 4}),
                         {fmt::format("{}: line {}, byte offset {}, field {}: ", csv_, c.line, offset, c.field),
                          c.message}));
  }
}

// The draw table holds at most 1048576 draws (draw_count): the CSV reader
// refuses the row or '# draw' line that would add one more, where it is (it
// accepted such a CSV, and converting it failed blaming the output file).
TEST_F(Csv, AtMost1048576DistinctDraws) {
  constexpr uint32_t kMax = 1u << 20;
  std::string text = "# width 1\n# height 1\ndraw,prim,x,y,z,r,g,b,a,opaque\n";
  for (uint32_t i = 0; i < kMax; ++i) fmt::format_to(std::back_inserter(text), "{},0,0,0,0,0,0,0,0,0\n", i);
  text += "7,1,0,0,0,0,0,0,0,0\n";  // record 1048576: a known draw again
  writeFile(csv_, text);
  EXPECT_EQ(openTrace(csv_)->header().draws.size(), kMax);  // the limit itself is fine
  const size_t offset = text.size();
  text += "4000000000,0,0,0,0,0,0,0,0,0\n";  // record 1048577, line 3 + 1048578
  EXPECT_EQ(csvError(text), fmt::format("{}: line 1048581, byte offset {}, record 1048577, column draw: draw 4000000000 "
                                        "would be draw number 1048577 of the trace: at most 1048576 distinct draws "
                                        "allowed (draw_count, FORMAT.md section 2.1)",
                                        csv_, offset));
  // The same for declared draws, at the '# draw' line's id.
  std::string declared;
  for (uint32_t i = 0; i <= kMax; ++i) fmt::format_to(std::back_inserter(declared), "# draw {} opaque \"\"\n", i);
  const size_t last_line = declared.rfind("# draw");
  declared += "draw,prim,x,y,z,r,g,b,a,opaque\n";
  EXPECT_TRUE(contains(csvError(declared, {.width = 1, .height = 1}),
                       {fmt::format("{}: line 1048577, byte offset {}, field draw: draw 1048576 would be draw number "
                                    "1048577 of the trace: at most 1048576",
                                    csv_, last_line + 7)}));
}

TEST_F(Csv, ErrorAccessorsCarryLineAndColumn) {
  writeFile(csv_, kHead + "1,0,1,1,0.5,0,0,0,9,0\n");
  try {
    readAll(csv_);
    ADD_FAILURE() << "expected a TraceError";
  } catch (const TraceError& e) {
    EXPECT_EQ(e.file(), csv_);
    EXPECT_EQ(e.line(), std::optional<uint64_t>(6));
    EXPECT_EQ(e.byteOffset(), kHead.size() + 18);
    EXPECT_EQ(e.record(), std::optional<uint64_t>(0));
    EXPECT_EQ(e.field(), "a");
  }
}

TEST_F(Csv, WriterRejectsBadFragmentsAndRemovesItsTemporary) {
  {
    auto w = createTraceWriter(csv_, makeHeader(4, 4, ColourEncoding::Fp32, {{1, DrawClass::Opaque, "o"}}));
    w->write(Fragment{0, 0, 0.5f, 0, 0, 0, 0, 0, 1});
    // Header: 5 comment lines + column line; record 1 is line 8.
    const std::string expected_prefix = fmt::format(
        "{}: line 8, byte offset {}, record 1, column z: depth 2 outside [0,1]", csv_,
        std::string("# oitsim-trace v1\n# width 4\n# height 4\n# encoding fp32\n# draw 1 opaque \"o\"\n"
                    "draw,prim,x,y,z,r,g,b,a,opaque\n1,0,0,0,0.5,0,0,0,0,1\n").size());
    EXPECT_TRUE(contains(traceErrorOf([&] { w->write(Fragment{0, 0, 2.0f, 0, 0, 0, 0, 0, 1}); }),
                         {expected_prefix}));
    EXPECT_EQ(w->written(), 1u);
    EXPECT_EQ(dir_.entries().size(), 1u);
    EXPECT_FALSE(std::filesystem::exists(csv_));
  }
  EXPECT_TRUE(dir_.entries().empty());
}

TEST_F(Csv, WriterOutputIsCanonical) {
  auto w = createTraceWriter(csv_, makeHeader(16, 8, ColourEncoding::Fp32,
                                              {{2, DrawClass::Opaque, "wall"}},
                                              CameraPlanes{0.1f, 100.0f}));
  w->write(Fragment{15, 7, 1.0f / 3.0f, 0.1f, 0.0f, 1.0f, 0.5f, 3, 2});
  w->commit();
  EXPECT_EQ(readFile(csv_),
            "# oitsim-trace v1\n# width 16\n# height 8\n# camera 0.1 100\n# encoding fp32\n"
            "# draw 2 opaque \"wall\"\ndraw,prim,x,y,z,r,g,b,a,opaque\n"
            "2,3,15,7,0.33333334,0.1,0,1,0.5,1\n");
}

TEST_F(Csv, OpenPicksCsvByExtension) {
  const std::string upper = dir_.path("T.CSV");
  writeFile(upper, kCanonicalFp32);
  EXPECT_EQ(readAll(upper).fragments.size(), 4u);
  EXPECT_TRUE(contains(traceErrorOf([&] { openTrace(dir_.path("none.csv")); }), {"cannot open"}));
}

}  // namespace
}  // namespace oit::test
