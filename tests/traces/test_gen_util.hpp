// In-memory fragment sinks for the rasterizer and generator tests (no files, so
// these tests do not depend on the trace writer).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "Fnv1a.hpp"
#include "traces/TraceIO.hpp"

namespace oit::test {

// Keeps every fragment.
class VectorSink : public FragmentSink {
 public:
  std::vector<Fragment> fragments;
  bool committed = false;

  void write(const Fragment& f) override { fragments.push_back(f); }
  void write(std::span<const Fragment> fs) override {
    fragments.insert(fragments.end(), fs.begin(), fs.end());
  }
  void commit() override { committed = true; }
  uint64_t written() const override { return fragments.size(); }
};

// Keeps a FNV-1a hash of the byte stream and per-pixel counts, for big scenes.
class HashSink : public FragmentSink {
 public:
  HashSink(uint32_t width, uint32_t height)
      : width_(width), height_(height), counts_(size_t{width} * height) {}

  void write(const Fragment& f) override {
    hash_ = fnv1a64(&f, sizeof f, hash_);
    if (f.x < width_ && f.y < height_) ++counts_[size_t{f.y} * width_ + f.x];
    else ++outside_;
    ++n_;
  }
  void commit() override {}
  uint64_t written() const override { return n_; }

  uint64_t hash() const { return hash_; }
  uint64_t outsideFrame() const { return outside_; }
  uint32_t maxDepthComplexity() const {
    uint32_t m = 0;
    for (uint32_t c : counts_) m = c > m ? c : m;
    return m;
  }

 private:
  uint32_t width_, height_;
  uint64_t outside_ = 0;
  std::vector<uint32_t> counts_;
  uint64_t hash_ = kFnv1aOffset;
  uint64_t n_ = 0;
};

}  // namespace oit::test
