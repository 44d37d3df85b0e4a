// Binary trace format v1: layout, round trips, batches, rewind, writer behaviour.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>

#include "test_format_helpers.hpp"
#include "traces/TraceIO.hpp"

namespace oit::test {
namespace {

const std::vector<DrawInfo> kDraws = {
    {0, DrawClass::Opaque, "floor"},
    {7, DrawClass::Transparent, "glass \"pane\" \\ 1"},
    {3, DrawClass::Transparent, std::string(55, 'n')},  // longest name allowed
    {9, DrawClass::Opaque, ""},
};
const std::vector<uint32_t> kIds = {0, 7, 3, 9};

void expectSameHeader(const TraceHeader& a, const TraceHeader& b) {
  EXPECT_EQ(a.version, b.version);
  EXPECT_EQ(a.width, b.width);
  EXPECT_EQ(a.height, b.height);
  EXPECT_EQ(a.encoding, b.encoding);
  ASSERT_EQ(a.camera.has_value(), b.camera.has_value());
  if (a.camera) {
    EXPECT_EQ(std::bit_cast<uint32_t>(a.camera->near_plane), std::bit_cast<uint32_t>(b.camera->near_plane));
    EXPECT_EQ(std::bit_cast<uint32_t>(a.camera->far_plane), std::bit_cast<uint32_t>(b.camera->far_plane));
  }
  ASSERT_EQ(a.draws.size(), b.draws.size());
  for (size_t i = 0; i < a.draws.size(); ++i) {
    EXPECT_EQ(a.draws[i].id, b.draws[i].id) << i;
    EXPECT_EQ(a.draws[i].cls, b.draws[i].cls) << i;
    EXPECT_EQ(a.draws[i].name, b.draws[i].name) << i;
  }
}

TEST(FormatBinary, ByteLayoutMatchesSpec) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  const TraceHeader h = makeHeader(1280, 720, ColourEncoding::Fp32,
                                   {{5, DrawClass::Opaque, "ab"}, {6, DrawClass::Transparent, "c"}},
                                   CameraPlanes{0.25f, 100.0f});
  Fragment f{17, 42, 0.5f, 0.25f, 0.125f, 1.0f, 0.0f, 99, 6};
  writeTrace(p, h, {f, f});
  const std::string b = readFile(p);
  ASSERT_EQ(b.size(), 64u + 2 * 64 + 2 * 32);
  EXPECT_EQ(b.substr(0, 8), std::string("\x89OITT\r\n\x1A", 8));
  EXPECT_EQ(peek<uint32_t>(b, 8), 1u);      // version
  EXPECT_EQ(peek<uint32_t>(b, 12), 192u);   // header_bytes
  EXPECT_EQ(peek<uint32_t>(b, 16), 1280u);  // width
  EXPECT_EQ(peek<uint32_t>(b, 20), 720u);   // height
  EXPECT_EQ(peek<uint64_t>(b, 24), 2u);     // fragment_count
  EXPECT_EQ(peek<uint32_t>(b, 32), 0u);     // encoding fp32
  EXPECT_EQ(peek<uint32_t>(b, 36), 32u);    // record_bytes
  EXPECT_EQ(peek<uint32_t>(b, 40), 1u);     // flags: camera
  EXPECT_EQ(peek<float>(b, 44), 0.25f);
  EXPECT_EQ(peek<float>(b, 48), 100.0f);
  EXPECT_EQ(peek<uint32_t>(b, 52), 2u);     // draw_count
  EXPECT_EQ(peek<uint64_t>(b, 56), 0u);     // reserved
  EXPECT_EQ(peek<uint32_t>(b, 64), 5u);     // draw[0].id
  EXPECT_EQ(peek<uint32_t>(b, 68), 0u);     // draw[0].class opaque
  EXPECT_EQ(b.substr(72, 56), std::string("ab") + std::string(54, '\0'));
  EXPECT_EQ(peek<uint32_t>(b, 128), 6u);
  EXPECT_EQ(peek<uint32_t>(b, 132), 1u);
  EXPECT_EQ(b.substr(136, 56), std::string("c") + std::string(55, '\0'));
  // Record 1, fp32: u16 x, u16 y, f32 z, r, g, b, a, u32 prim, u32 draw.
  EXPECT_EQ(peek<uint16_t>(b, 224), 17u);
  EXPECT_EQ(peek<uint16_t>(b, 226), 42u);
  EXPECT_EQ(peek<float>(b, 228), 0.5f);
  EXPECT_EQ(peek<float>(b, 232), 0.25f);
  EXPECT_EQ(peek<float>(b, 236), 0.125f);
  EXPECT_EQ(peek<float>(b, 240), 1.0f);
  EXPECT_EQ(peek<float>(b, 244), 0.0f);
  EXPECT_EQ(peek<uint32_t>(b, 248), 99u);
  EXPECT_EQ(peek<uint32_t>(b, 252), 6u);
}

TEST(FormatBinary, Unorm8ByteLayoutMatchesSpec) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  const TraceHeader h = makeHeader(8, 8, ColourEncoding::Unorm8, {{2, DrawClass::Transparent, "g"}});
  // 0.5 * 255 = 127.5 rounds to 128; 0.2 * 255 = 51.
  writeTrace(p, h, {Fragment{3, 4, 0.75f, 1.0f, 0.5f, 0.2f, 0.0f, 12345, 2}});
  const std::string b = readFile(p);
  ASSERT_EQ(b.size(), 64u + 64 + 20);
  EXPECT_EQ(peek<uint32_t>(b, 32), 1u);   // encoding unorm8
  EXPECT_EQ(peek<uint32_t>(b, 36), 20u);  // record_bytes
  EXPECT_EQ(peek<uint32_t>(b, 40), 0u);   // no camera
  EXPECT_EQ(peek<uint64_t>(b, 44), 0u);   // camera planes zero when absent
  EXPECT_EQ(peek<uint16_t>(b, 128), 3u);
  EXPECT_EQ(peek<uint16_t>(b, 130), 4u);
  EXPECT_EQ(peek<float>(b, 132), 0.75f);
  EXPECT_EQ(static_cast<uint8_t>(b[136]), 255u);
  EXPECT_EQ(static_cast<uint8_t>(b[137]), 128u);
  EXPECT_EQ(static_cast<uint8_t>(b[138]), 51u);
  EXPECT_EQ(static_cast<uint8_t>(b[139]), 0u);
  EXPECT_EQ(peek<uint32_t>(b, 140), 12345u);
  EXPECT_EQ(peek<uint32_t>(b, 144), 2u);
}

TEST(FormatBinary, Fp32RoundTripIsBitExact) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  const TraceHeader h = makeHeader(1920, 1080, ColourEncoding::Fp32, kDraws, CameraPlanes{0.1f, 1000.0f});
  const auto fs = makeFragments(5000, 1920, 1080, kIds);
  writeTrace(p, h, fs);
  EXPECT_EQ(std::filesystem::file_size(p), 64u + 4 * 64 + 5000 * 32);
  const ReadResult r = readAll(p, {.batch_records = 1024});
  expectSameHeader(r.header, h);
  EXPECT_EQ(r.header.fragment_count, 5000u);
  EXPECT_TRUE(bitEqual(r.fragments, fs));
}

TEST(FormatBinary, Unorm8RoundTripQuantizesToNearestAndIsExactOnUnormValues) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  const TraceHeader h = makeHeader(65535, 65535, ColourEncoding::Unorm8, kDraws);
  auto fs = makeFragments(3000, 65535, 65535, kIds);
  writeTrace(p, h, fs);
  EXPECT_EQ(std::filesystem::file_size(p), 64u + 4 * 64 + 3000 * 20);
  const ReadResult r = readAll(p, {.batch_records = 1000});
  expectSameHeader(r.header, h);
  EXPECT_FALSE(r.header.camera.has_value());
  ASSERT_EQ(r.fragments.size(), fs.size());
  auto q = [](float v) { return static_cast<float>(std::lround(v * 255.0)) / 255.0f; };
  for (Fragment& f : fs) f = {f.x, f.y, f.z, q(f.r), q(f.g), q(f.b), q(f.a), f.prim, f.draw};
  EXPECT_TRUE(bitEqual(r.fragments, fs));  // depth stays fp32, colours are k/255

  // Already-quantized colours survive a second trip unchanged (bit-exact).
  const std::string p2 = dir.path("t2.oitt");
  writeTrace(p2, h, r.fragments);
  EXPECT_TRUE(bitEqual(readAll(p2).fragments, r.fragments));
  EXPECT_EQ(readFile(p2), readFile(p));
}

TEST(FormatBinary, AllUnorm8LevelsRoundTrip) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  std::vector<Fragment> fs;
  for (int k = 0; k < 256; ++k) {
    const float v = static_cast<float>(k) / 255.0f;
    fs.push_back({0, 0, v, v, v, v, v, static_cast<uint32_t>(k), 1});
  }
  writeTrace(p, makeHeader(1, 1, ColourEncoding::Unorm8, {{1, DrawClass::Transparent, "d"}}), fs);
  const std::string b = readFile(p);
  for (int k = 0; k < 256; ++k) EXPECT_EQ(static_cast<uint8_t>(b[128 + k * 20 + 8]), k);
  EXPECT_TRUE(bitEqual(readAll(p).fragments, fs));
}

TEST(FormatBinary, CameraAbsentStaysAbsent) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  writeTrace(p, makeHeader(4, 4, ColourEncoding::Fp32, kDraws), makeFragments(10, 4, 4, kIds));
  const ReadResult r = readAll(p);
  EXPECT_FALSE(r.header.camera.has_value());
  EXPECT_EQ(r.fragments.size(), 10u);
}

TEST(FormatBinary, ZeroFragmentTrace) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  writeTrace(p, makeHeader(4, 4, ColourEncoding::Fp32, {}), {});
  EXPECT_EQ(std::filesystem::file_size(p), 64u);
  auto src = openTrace(p);
  EXPECT_EQ(src->header().fragment_count, 0u);
  EXPECT_TRUE(src->header().draws.empty());
  EXPECT_TRUE(src->next().empty());
  EXPECT_EQ(src->position(), 0u);
  src->rewind();
  EXPECT_TRUE(src->next().empty());
}

TEST(FormatBinary, BatchesCoverEveryRecordWhenCountIsNotAMultiple) {
  for (ColourEncoding enc : {ColourEncoding::Fp32, ColourEncoding::Unorm8}) {
    TempDir dir;
    const std::string p = dir.path("t.oitt");
    auto fs = makeFragments(10007, 64, 64, kIds);
    writeTrace(p, makeHeader(64, 64, enc, kDraws), fs);
    auto src = openTrace(p, {.batch_records = 1000});
    std::vector<Fragment> got;
    std::vector<size_t> sizes;
    for (auto b = src->next(); !b.empty(); b = src->next()) {
      sizes.push_back(b.size());
      got.insert(got.end(), b.begin(), b.end());
      EXPECT_EQ(src->position(), got.size());
    }
    ASSERT_EQ(sizes.size(), 11u);
    for (size_t i = 0; i < 10; ++i) EXPECT_EQ(sizes[i], 1000u);
    EXPECT_EQ(sizes[10], 7u);
    EXPECT_TRUE(src->next().empty());  // stays at the end
    EXPECT_EQ(src->position(), 10007u);
    if (enc == ColourEncoding::Fp32) {
      EXPECT_TRUE(bitEqual(got, fs));
    } else {
      EXPECT_EQ(got.size(), fs.size());
    }
  }
}

TEST(FormatBinary, RewindRestartsFromTheFirstRecord) {
  for (ColourEncoding enc : {ColourEncoding::Fp32, ColourEncoding::Unorm8}) {
    TempDir dir;
    const std::string p = dir.path("t.oitt");
    writeTrace(p, makeHeader(64, 64, enc, kDraws), makeFragments(2500, 64, 64, kIds));
    const auto all = readAll(p).fragments;
    auto src = openTrace(p, {.batch_records = 1000});
    src->next();
    src->next();
    EXPECT_EQ(src->position(), 2000u);
    src->rewind();
    EXPECT_EQ(src->position(), 0u);
    std::vector<Fragment> again;
    for (auto b = src->next(); !b.empty(); b = src->next()) again.insert(again.end(), b.begin(), b.end());
    EXPECT_TRUE(bitEqual(again, all));
  }
}

TEST(FormatBinary, SparseDrawIdsAreValidated) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  const std::vector<DrawInfo> draws = {{4000000000u, DrawClass::Opaque, "far"},
                                       {5, DrawClass::Transparent, "near"},
                                       {UINT32_MAX, DrawClass::Transparent, "max"}};
  const auto fs = makeFragments(100, 8, 8, {4000000000u, 5, UINT32_MAX});
  writeTrace(p, makeHeader(8, 8, ColourEncoding::Fp32, draws), fs);
  EXPECT_TRUE(bitEqual(readAll(p).fragments, fs));
  auto w = createTraceWriter(dir.path("u.oitt"), makeHeader(8, 8, ColourEncoding::Fp32, draws));
  const std::string msg = traceErrorOf([&] { w->write(Fragment{1, 1, 0, 0, 0, 0, 0, 0, 6}); });
  EXPECT_TRUE(contains(msg, {"record 0", "field draw", "unknown draw id 6"}));
}

TEST(FormatBinary, WriterWithoutCommitLeavesNothing) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  {
    auto w = createTraceWriter(p, makeHeader(8, 8, ColourEncoding::Fp32, kDraws));
    w->write(makeFragments(100000, 8, 8, kIds));  // more than the 1 MiB buffer: data hit the disk
    EXPECT_EQ(w->written(), 100000u);
    EXPECT_FALSE(std::filesystem::exists(p));  // only the temporary exists while writing
    const auto names = dir.entries();
    ASSERT_EQ(names.size(), 1u);
    EXPECT_EQ(names[0].rfind("t.oitt.tmp.", 0), 0u) << names[0];
    // An unfinished temporary carries the sentinel count and is refused by name.
    const std::string tmp = dir.path(names[0]);
    EXPECT_TRUE(contains(traceErrorOf([&] { openTrace(tmp); }),
                         {tmp, "byte offset 24", "field fragment_count", "never committed"}));
  }
  EXPECT_TRUE(dir.entries().empty());
}

TEST(FormatBinary, CommitMakesTheFileAppearAndReplacesAnOldOne) {
  TempDir dir;
  const std::string p = dir.path("t.oitt");
  writeFile(p, "old contents");
  auto w = createTraceWriter(p, makeHeader(8, 8, ColourEncoding::Fp32, kDraws));
  w->write(makeFragments(10, 8, 8, kIds));
  EXPECT_EQ(readFile(p), "old contents");  // untouched until commit
  w->commit();
  w->commit();  // a second commit does nothing
  EXPECT_EQ(dir.entries(), std::vector<std::string>{"t.oitt"});
  EXPECT_EQ(readAll(p).fragments.size(), 10u);
  EXPECT_THROW(w->write(Fragment{0, 0, 0, 0, 0, 0, 0, 0, 0}), std::logic_error);
  w.reset();
  EXPECT_TRUE(std::filesystem::exists(p));  // destructor after commit keeps the file
}

struct BadFragmentCase {
  const char* field;
  uint32_t offset_in_record;
  Fragment f;
  const char* message;
};

TEST(FormatBinary, WriterRejectsBadFragmentsNamingRecordAndField) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  const BadFragmentCase cases[] = {
      {"x", 0, {8, 0, 0.5f, 0, 0, 0, 0, 0, 0}, "x 8 outside the frame, expected 0 <= x < 8"},
      {"y", 2, {0, 9, 0.5f, 0, 0, 0, 0, 0, 0}, "y 9 outside the frame, expected 0 <= y < 8"},
      {"z", 4, {0, 0, 1.5f, 0, 0, 0, 0, 0, 0}, "depth 1.5 outside [0,1]"},
      {"z", 4, {0, 0, nan, 0, 0, 0, 0, 0, 0}, "depth is NaN"},
      {"z", 4, {0, 0, -0.25f, 0, 0, 0, 0, 0, 0}, "depth -0.25 outside [0,1]"},
      {"r", 8, {0, 0, 0, -inf, 0, 0, 0, 0, 0}, "colour r is -Inf"},
      {"g", 12, {0, 0, 0, 0, 2.0f, 0, 0, 0, 0}, "colour g 2 outside [0,1]"},
      {"b", 16, {0, 0, 0, 0, 0, nan, 0, 0, 0}, "colour b is NaN"},
      {"a", 20, {0, 0, 0, 0, 0, 0, inf, 0, 0}, "colour a is +Inf"},
      {"draw", 28, {0, 0, 0, 0, 0, 0, 0, 0, 4}, "unknown draw id 4"},
  };
  for (ColourEncoding enc : {ColourEncoding::Fp32, ColourEncoding::Unorm8}) {
    for (const BadFragmentCase& c : cases) {
      SCOPED_TRACE(std::string(c.field) + " " + toString(enc));
      TempDir dir;
      const std::string p = dir.path("t.oitt");
      auto w = createTraceWriter(p, makeHeader(8, 8, enc, kDraws));
      const auto good = makeFragments(5, 8, 8, kIds);
      w->write(good);
      std::vector<Fragment> batch = {good[0], good[1], c.f, good[2]};
      const std::string msg = traceErrorOf([&] { w->write(batch); });
      // Header 64 + 4 draws x 64 = 320; the bad one is record 7.
      const uint32_t rb = enc == ColourEncoding::Fp32 ? 32 : 20;
      const uint32_t unorm_offsets[] = {0, 2, 4, 8, 9, 10, 11, 16};
      const char* fields[] = {"x", "y", "z", "r", "g", "b", "a", "draw"};
      uint32_t off = c.offset_in_record;
      if (enc == ColourEncoding::Unorm8)
        for (size_t k = 0; k < 8; ++k)
          if (std::string(fields[k]) == c.field) off = unorm_offsets[k];
      EXPECT_TRUE(contains(msg, {p + ": byte offset " + std::to_string(320 + 7 * rb + off) +
                                     ", record 7, field " + c.field + ": ",
                                 c.message}));
      EXPECT_EQ(w->written(), 7u);  // the valid records before the bad one were kept
      w->write(good[3]);            // and the writer goes on
      w->commit();
      EXPECT_EQ(readAll(p).fragments.size(), 8u);
    }
  }
}

TEST(FormatBinary, WriterRejectsBadHeadersAndCreatesNoFile) {
  struct Case {
    TraceHeader h;
    const char* expected;
  };
  auto hd = [](auto mutate) {
    TraceHeader h = makeHeader(8, 8, ColourEncoding::Fp32, kDraws);
    mutate(h);
    return h;
  };
  const Case cases[] = {
      {hd([](TraceHeader& h) { h.width = 0; }), "byte offset 16, field width: width is 0"},
      {hd([](TraceHeader& h) { h.height = 65536; }), "byte offset 20, field height: height 65536 exceeds 65535"},
      {hd([](TraceHeader& h) { h.version = 3; }), "byte offset 8, field version"},
      {hd([](TraceHeader& h) { h.encoding = static_cast<ColourEncoding>(5); }), "byte offset 32, field encoding"},
      {hd([](TraceHeader& h) { h.camera = CameraPlanes{10.0f, 1.0f}; }), "byte offset 44, field camera"},
      {hd([](TraceHeader& h) { h.draws[2].id = 7; }), "byte offset 192, field draw[2].id: duplicate draw id 7 (also draw table entry 1)"},
      {hd([](TraceHeader& h) { h.draws[1].cls = static_cast<DrawClass>(3); }), "byte offset 132, field draw[1].class"},
      {hd([](TraceHeader& h) { h.draws[0].name = std::string(56, 'x'); }), "byte offset 72, field draw[0].name: name is 56 bytes long"},
      {hd([](TraceHeader& h) { h.draws[3].name = "a\nb"; }), "byte offset 264, field draw[3].name: name contains control byte 0x0A"},
      {hd([](TraceHeader& h) { h.draws[0].name = "caf\xC3"; }),
       "byte offset 72, field draw[0].name: name is not valid UTF-8: byte 0xC3 at index 3"},
  };
  for (const Case& c : cases) {
    TempDir dir;
    const std::string p = dir.path("t.oitt");
    EXPECT_TRUE(contains(traceErrorOf([&] { createTraceWriter(p, c.h); }), {p, c.expected}));
    EXPECT_TRUE(dir.entries().empty());
  }
}

TEST(FormatBinary, OpenErrorsNameTheFile) {
  TempDir dir;
  const std::string missing = dir.path("missing.oitt");
  EXPECT_TRUE(contains(traceErrorOf([&] { openTrace(missing); }),
                       {missing, "cannot open: No such file or directory"}));
  EXPECT_TRUE(contains(traceErrorOf([&] { openTrace(dir.path("")); }), {"not a regular file"}));
  const std::string nodir = dir.path("no/such/dir/t.oitt");
  EXPECT_TRUE(contains(traceErrorOf([&] { createTraceWriter(nodir, makeHeader(1, 1, ColourEncoding::Fp32, {})); }),
                       {nodir, "cannot create temporary file"}));
  EXPECT_THROW(openTrace(missing, {.batch_records = 0}), std::invalid_argument);
}

}  // namespace
}  // namespace oit::test
