// Trace format version 2 (FORMAT.md 3.1): the draw state table of captured
// applications, in binary and CSV, next to version 1 which stays as it was.
#include <gtest/gtest.h>

#include <cstring>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>

#include "traces/TraceIO.hpp"

namespace oit {
namespace {

namespace fs = std::filesystem;

// Records equal bit for bit (Fragment has no padding: 2 + 2 + 4 + 16 + 4 + 4 bytes).
bool same(const std::vector<Fragment>& a, const std::vector<Fragment>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Fragment)) == 0);
}

class DrawStateTable : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("oitsim-drawstate-" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  std::string path(const std::string& n) const { return (dir_ / n).string(); }

  // Three draws: opaque, straight over with depth test, additive (not recorded).
  static TraceHeader header() {
    TraceHeader h;
    h.version = 2;
    h.width = 8;
    h.height = 4;
    DrawState opaque;
    opaque.depth_test = opaque.depth_write = true;
    opaque.depth_func = 0x0201;
    opaque.fragments = 1;
    DrawState over{BlendMode::Over, true, false, 0x0201, 0x8006, 0x0302, 0x0303, 0x8006, 0x0001, 0x0303, 2};
    DrawState add{BlendMode::Additive, false, false, 0, 0x8006, 0x0001, 0x0001, 0x8006, 0x0001, 0x0001, 7};
    h.draws = {DrawInfo{0, DrawClass::Opaque, "glDrawArrays #0 program 3", opaque},
               DrawInfo{1, DrawClass::Transparent, "glDrawElements #1 program 4", over},
               DrawInfo{2, DrawClass::Transparent, "glDrawArrays #2 program 4", add}};
    return h;
  }
  static std::vector<Fragment> records() {
    return {{1, 1, 0.5f, 0.1f, 0.2f, 0.3f, 1.0f, 0, 0},
            {1, 1, 0.25f, 1.0f, 0.0f, 0.0f, 0.5f, 0, 1},
            {2, 3, 0.25f, 0.0f, 1.0f, 0.0f, 0.25f, 1, 1}};
  }
  void write(const std::string& p, const TraceHeader& h, const std::vector<Fragment>& f) {
    auto w = createTraceWriter(p, h);
    w->write(std::span<const Fragment>(f));
    w->commit();
  }
  static std::vector<Fragment> readAll(FragmentSource& s) {
    std::vector<Fragment> all;
    for (auto c = s.next(); !c.empty(); c = s.next()) all.insert(all.end(), c.begin(), c.end());
    return all;
  }
  static std::string errorOf(const std::function<void()>& f) {
    try {
      f();
    } catch (const std::exception& e) {
      return e.what();
    }
    return "";
  }
  fs::path dir_;
};

TEST_F(DrawStateTable, BinaryAndCsvKeepEveryState) {
  for (const char* name : {"t.oitt", "t.csv"}) {
    write(path(name), header(), records());
    auto src = openTrace(path(name));
    EXPECT_EQ(src->header().version, 2u) << name;
    ASSERT_EQ(src->header().draws.size(), 3u);
    for (size_t i = 0; i < 3; ++i) {
      EXPECT_EQ(src->header().draws[i].name, header().draws[i].name) << name;
      EXPECT_TRUE(src->header().draws[i].state == header().draws[i].state) << name << " draw " << i;
    }
    EXPECT_TRUE(same(readAll(*src), records())) << name;
  }
  // Header bytes: 64 + 3 x 64 draw entries + 3 x 32 state entries = 352, rounded up to 384.
  std::ifstream f(path("t.oitt"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(f)), {});
  uint32_t version = 0, header_bytes = 0;
  std::memcpy(&version, bytes.data() + 8, 4);
  std::memcpy(&header_bytes, bytes.data() + 12, 4);
  EXPECT_EQ(version, 2u);
  EXPECT_EQ(header_bytes, 384u);
  EXPECT_EQ(bytes.size(), 384u + 3 * 32);
  // The additive draw's entry (state table at 64 + 192 = 256, entry 2 at 320): mode 3, 7 fragments.
  EXPECT_EQ(static_cast<uint8_t>(bytes[320]), 3u);
  EXPECT_EQ(static_cast<uint8_t>(bytes[336]), 7u);
}

TEST_F(DrawStateTable, VersionOneIsUnchanged) {
  TraceHeader h = header();
  h.version = 1;
  for (DrawInfo& d : h.draws) d.state.reset();
  write(path("v1.oitt"), h, records());
  std::ifstream f(path("v1.oitt"), std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(f)), {});
  EXPECT_EQ(bytes.size(), 64u + 3 * 64 + 3 * 32);  // no state table
  auto src = openTrace(path("v1.oitt"));
  EXPECT_EQ(src->header().version, 1u);
  EXPECT_FALSE(src->header().draws[2].state);
  // A state on a version 1 header is refused, as is a version 2 draw without one.
  TraceHeader bad = header();
  bad.version = 1;
  EXPECT_NE(errorOf([&] { write(path("b.oitt"), bad, {}); }).find("only version 2 keeps them"), std::string::npos);
  bad = header();
  bad.draws[1].state.reset();
  EXPECT_NE(errorOf([&] { write(path("b.oitt"), bad, {}); }).find("version 2 needs a draw state for every draw"),
            std::string::npos);
}

TEST_F(DrawStateTable, RecordsOfUnmodelledDrawsAndBadStatesAreRefused) {
  std::vector<Fragment> f = records();
  f.push_back({0, 0, 0.5f, 1, 1, 1, 1, 0, 2});  // names the additive draw
  for (const char* name : {"a.oitt", "a.csv"}) {
    const std::string e = errorOf([&] { write(path(name), header(), f); });
    EXPECT_NE(e.find("draw 2 is not modelled"), std::string::npos) << name << ": " << e;
  }
  TraceHeader h = header();
  h.draws[0].cls = DrawClass::Transparent;  // blending off, so it must be opaque
  const std::string e = errorOf([&] { write(path("c.oitt"), h, {}); });
  EXPECT_NE(e.find("class transparent but blend mode off: expected opaque"), std::string::npos) << e;
  // Reading: the blend byte of state entry 1 (at 256 + 32) set to 9.
  write(path("d.oitt"), header(), records());
  {
    std::fstream io(path("d.oitt"), std::ios::in | std::ios::out | std::ios::binary);
    io.seekp(288);
    io.put(9);
  }
  const std::string r = errorOf([&] { openTrace(path("d.oitt")); });
  EXPECT_NE(r.find("byte offset 288, field draw[1].state.blend: bad blend mode 9"), std::string::npos) << r;
}

}  // namespace
}  // namespace oit
