// NodePool: where the A-buffer's nodes are (Yang et al. 2010). A stored
// fragment's node goes where the global node counter points: node i at the
// pool's base + i x node_bytes, so consecutive allocations are consecutive in
// memory whichever partition takes them (one pool for the whole GPU, as the
// counter is one). The L2 merges the partial node writes into whole bursts:
// the partition whose node completes a burst writes it; what is left of the
// last one is written by the next flush (a partition's resolve).
#pragma once

#include <algorithm>
#include <cstdint>

namespace oit::rop {

class NodePool {
 public:
  NodePool(uint64_t base, unsigned node_bytes, unsigned burst_bytes)
      : base_(base), node_bytes_(node_bytes), burst_(std::max(1u, burst_bytes)), end_(base), written_(base) {}
  uint64_t address(uint64_t index) const { return base_ + index * node_bytes_; }
  // Bytes [begin, end) to write now: none (begin == end) until a burst is complete.
  struct Range {
    uint64_t begin = 0, end = 0;
    uint32_t bytes() const { return uint32_t(end - begin); }
  };
  // Takes the counter's next value: the node's bytes follow the last node's.
  Range append() {
    ++nodes_;
    end_ += node_bytes_;
    const uint64_t complete = base_ + (end_ - base_) / burst_ * burst_;
    return take(std::max(written_, complete));
  }
  // Whatever is appended but not yet written.
  Range flush() { return take(end_); }
  uint64_t nodes() const { return nodes_; }

 private:
  Range take(uint64_t upto) {
    const Range r{written_, upto};
    written_ = upto;
    return r;
  }
  uint64_t base_;
  unsigned node_bytes_, burst_;
  uint64_t end_, written_;
  uint64_t nodes_ = 0;
};

}  // namespace oit::rop
