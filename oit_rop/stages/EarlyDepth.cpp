#include "oit_rop/stages/EarlyDepth.hpp"

#include <algorithm>
#include <utility>

namespace oit::rop {

EarlyDepth::EarlyDepth(const EarlyDepthConfig& cfg, double per_clock, uint32_t tile_bytes, uint64_t depth_base,
                       MemoryPort& mem, unsigned depth_tiles, std::vector<uint32_t> slot_index)
    : cfg_(cfg),
      rate_(per_clock),
      tile_bytes_(tile_bytes),
      depth_base_(depth_base),
      mem_(mem),
      tag_(std::max(1u, depth_tiles), 0),
      slot_index_(std::move(slot_index)),
      tag_ready_(std::max(1u, depth_tiles), 0),
      q_(256) {}

Cycle EarlyDepth::depthTile(Cycle now, uint32_t tile) {
  const size_t slot = (slot_index_.empty() ? tile : slot_index_[tile]) % tag_.size();
  if (tag_[slot] == tile + 1) {
    ++stats_.depth_buffer_hits;
  } else {
    // The read starts when the fragment enters; its latency overlaps the stage's.
    ++stats_.depth_reads;
    tag_[slot] = tile + 1;
    tag_ready_[slot] = mem_.access(now, depth_base_ + uint64_t(tile) * tile_bytes_, tile_bytes_, false, Surface::Depth);
  }
  return tag_ready_[slot];
}

}  // namespace oit::rop
