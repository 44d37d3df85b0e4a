// Shared helpers of the trace format tests (binary, CSV, memory).
#pragma once

#include <gtest/gtest.h>
#include <stdlib.h>

#include <bit>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <iterator>
#include <string>
#include <string_view>
#include <vector>

#include "traces/TraceIO.hpp"

namespace oit::test {

// A fresh directory under $TMPDIR (or /tmp), removed with its contents.
class TempDir {
 public:
  TempDir() {
    const char* base = std::getenv("TMPDIR");
    std::string tmpl = std::string(base && *base ? base : "/tmp") + "/oitsim-test-XXXXXX";
    if (!::mkdtemp(tmpl.data())) throw std::runtime_error("mkdtemp failed");
    dir_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::vector<std::string> entries() const {
    std::vector<std::string> names;
    for (const auto& e : std::filesystem::directory_iterator(dir_))
      names.push_back(e.path().filename().string());
    return names;
  }

 private:
  std::filesystem::path dir_;
};

inline TraceHeader makeHeader(uint32_t w, uint32_t h, ColourEncoding enc,
                              std::vector<DrawInfo> draws,
                              std::optional<CameraPlanes> camera = std::nullopt) {
  TraceHeader hd;
  hd.width = w;
  hd.height = h;
  hd.encoding = enc;
  hd.draws = std::move(draws);
  hd.camera = camera;
  return hd;
}

// Deterministic pseudo-random valid fragments: coordinates over the whole
// frame, floats spread over [0,1] by random mantissas and exponents (so
// shortest-form printing is exercised), plus the exact ends 0 and 1.
inline std::vector<Fragment> makeFragments(size_t n, uint32_t w, uint32_t h,
                                           const std::vector<uint32_t>& draw_ids,
                                           uint64_t seed = 1) {
  uint64_t s = seed * 0x9E3779B97F4A7C15ull + 1;
  auto rnd = [&s] {
    s ^= s << 13;
    s ^= s >> 7;
    s ^= s << 17;
    return s;
  };
  auto unit = [&]() -> float {
    const uint64_t r = rnd();
    switch (r % 16) {
      case 0: return 0.0f;
      case 1: return 1.0f;
      case 2: return std::bit_cast<float>(static_cast<uint32_t>(r >> 40) & 0x7FFFFFu);  // subnormal
      default: {
        // exponent in [2^-40, 2^-1], any mantissa: always < 1
        const uint32_t exp = 127 - 1 - static_cast<uint32_t>((r >> 8) % 40);
        return std::bit_cast<float>((exp << 23) | (static_cast<uint32_t>(r >> 32) & 0x7FFFFFu));
      }
    }
  };
  std::vector<Fragment> fs(n);
  for (size_t i = 0; i < n; ++i) {
    Fragment& f = fs[i];
    f.x = static_cast<uint16_t>(rnd() % w);
    f.y = static_cast<uint16_t>(rnd() % h);
    f.z = unit();
    f.r = unit();
    f.g = unit();
    f.b = unit();
    f.a = unit();
    f.prim = static_cast<uint32_t>(rnd());
    f.draw = draw_ids[(i / 7) % draw_ids.size()];  // runs of one draw, like real traces
  }
  return fs;
}

inline void writeTrace(const std::string& path, const TraceHeader& h,
                       const std::vector<Fragment>& fs) {
  auto w = createTraceWriter(path, h);
  w->write(fs);
  w->commit();
}

struct ReadResult {
  TraceHeader header;
  std::vector<Fragment> fragments;
  std::vector<size_t> batch_sizes;
};

inline ReadResult readAll(const std::string& path, OpenOptions opts = {}) {
  auto src = openTrace(path, opts);
  ReadResult r;
  r.header = src->header();
  for (auto b = src->next(); !b.empty(); b = src->next()) {
    r.batch_sizes.push_back(b.size());
    r.fragments.insert(r.fragments.end(), b.begin(), b.end());
  }
  return r;
}

inline bool bitEqual(const std::vector<Fragment>& a, const std::vector<Fragment>& b) {
  return a.size() == b.size() &&
         (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(Fragment)) == 0);
}

inline std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline void writeFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

template <class T>
void poke(std::string& bytes, size_t offset, T v) {
  std::memcpy(bytes.data() + offset, &v, sizeof v);
}

template <class T>
T peek(const std::string& bytes, size_t offset) {
  T v;
  std::memcpy(&v, bytes.data() + offset, sizeof v);
  return v;
}

// Runs f, which must throw TraceError; returns its message (empty, with a
// test failure, when it does not throw).
template <class F>
std::string traceErrorOf(F&& f) {
  try {
    f();
  } catch (const TraceError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected a TraceError";
  return {};
}

// Passes when msg contains every part; the failure shows the message.
inline ::testing::AssertionResult contains(const std::string& msg,
                                           std::initializer_list<std::string_view> parts) {
  for (std::string_view p : parts)
    if (msg.find(p) == std::string::npos)
      return ::testing::AssertionFailure() << "'" << msg << "' lacks '" << p << "'";
  return ::testing::AssertionSuccess();
}

}  // namespace oit::test
