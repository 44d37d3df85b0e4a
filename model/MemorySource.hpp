// A FragmentSource over fragments held in memory (tests, synthetic scenes,
// and callers that generate fragments on the fly). No validation: the
// caller's fragments are taken as they are.
#pragma once

#include <algorithm>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "traces/TraceIO.hpp"

namespace oit::model {

class MemorySource final : public FragmentSource {
 public:
  // header.fragment_count is set to fragments.size().
  MemorySource(TraceHeader header, std::vector<Fragment> fragments, size_t batch = 1u << 16)
      : header_(std::move(header)), frags_(std::move(fragments)), batch_(std::max<size_t>(batch, 1)) {
    header_.fragment_count = frags_.size();
  }
  const TraceHeader& header() const override { return header_; }
  const std::string& path() const override { return path_; }
  std::span<const Fragment> next() override {
    const size_t n = std::min(batch_, frags_.size() - pos_);
    std::span<const Fragment> s(frags_.data() + pos_, n);
    pos_ += n;
    return s;
  }
  uint64_t position() const override { return pos_; }
  void rewind() override {
    pos_ = 0;
    ++rewinds_;
  }
  unsigned rewinds() const { return rewinds_; }  // tests check multi-pass replays
  const std::vector<Fragment>& fragments() const { return frags_; }

 private:
  TraceHeader header_;
  std::vector<Fragment> frags_;
  size_t batch_;
  size_t pos_ = 0;
  unsigned rewinds_ = 0;
  std::string path_ = "<memory>";
};

}  // namespace oit::model
