#include "oit_rop/memory/DramBusGaps.hpp"

#include <algorithm>

namespace oit::rop {

void DramBusGaps::add(const Gap& g) {
  if (gaps_.size() == kMaxGaps) gaps_.erase(gaps_.begin());
  gaps_.push_back(g);
  latest_end_ = std::max(latest_end_, g.end);
}

uint64_t DramBusGaps::find(const Asker& asker, uint64_t from, uint64_t len, uint64_t after_write,
                           uint64_t before_write, size_t& index) const {
  for (size_t i = 0; i < gaps_.size(); ++i) {
    const Gap& g = gaps_[i];
    if (!asker.mayUse(g)) continue;
    const uint64_t start = std::max(from, g.begin + (g.write_before ? after_write : 0));
    const uint64_t limit = g.end - (g.write_after ? std::min(before_write, g.end) : 0);
    if (start + len <= limit) {
      index = i;
      return start;
    }
  }
  return kNone;
}

void DramBusGaps::take(size_t index, uint64_t start, uint64_t len, uint64_t min_len) {
  const Gap g = gaps_[index];
  Gap before = g, after = g;
  before.end = start;
  before.write_after = false;  // a read follows it now
  after.begin = start + len;
  after.write_before = false;  // a read precedes it now
  gaps_.erase(gaps_.begin() + std::ptrdiff_t(index));
  size_t at = index;
  if (before.end - before.begin >= min_len) gaps_.insert(gaps_.begin() + std::ptrdiff_t(at++), before);
  if (after.end - after.begin >= min_len) gaps_.insert(gaps_.begin() + std::ptrdiff_t(at), after);
  if (gaps_.size() > kMaxGaps) gaps_.erase(gaps_.begin());
  latest_end_ = 0;
  for (const Gap& k : gaps_) latest_end_ = std::max(latest_end_, k.end);
}

}  // namespace oit::rop
