#include "oit_rop/PixelLock.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

namespace oit::rop {

PixelLock::PixelLock(const LockConfig& cfg, uint32_t frame_width)
    : cfg_(cfg), capacity_(cfg.capacity), frame_width_(frame_width), ready_(64) {
  if (capacity_ == 0 || capacity_ > (1u << 24)) throw std::invalid_argument("lock.capacity must be in [1, 2^24]");
  tok_.resize(capacity_);
  free_.reserve(capacity_);
  // Lowest ids on top of the stack: token ids are deterministic.
  for (uint32_t i = capacity_; i-- > 0;) free_.push_back(i);
  // At most `capacity` addresses are in flight: a map 4x that (load <= 1/4)
  // keeps linear probing chains and the backward-shift erase short; 2x for
  // huge scoreboards.
  const size_t factor = capacity_ <= (1u << 16) ? 4 : 2;
  map_.resize(std::max<size_t>(16, std::bit_ceil(size_t(capacity_) * factor)));
  mask_ = map_.size() - 1;
}

uint32_t PixelLock::address(uint32_t x, uint32_t y, uint32_t tile_w, uint32_t tile_h) const {
  switch (cfg_.granularity) {
    case LockGranularity::Pixel: return y * frame_width_ + x;
    case LockGranularity::Quad: return (y / 2) * ((frame_width_ + 1) / 2) + x / 2;
    case LockGranularity::Tile: return (y / tile_h) * ((frame_width_ + tile_w - 1) / tile_w) + x / tile_w;
  }
  return 0;
}

void PixelLock::eraseSlot(size_t i) {
  // Backward-shift deletion keeps every probe chain intact without tombstones.
  size_t j = i;
  for (;;) {
    j = (j + 1) & mask_;
    if (map_[j].head < 0) break;
    const size_t k = hashOf(map_[j].address) & mask_;
    // Movable unless its home k lies cyclically in (i, j]: compared as probe
    // distances to j, and moved by selects (which way is random: no branch).
    const bool movable = ((j - k) & mask_) >= ((j - i) & mask_);
    const size_t from = movable ? j : i;
    map_[i] = map_[from];  // a self-copy when not movable
    i = from;
  }
  map_[i] = Slot{};
}

}  // namespace oit::rop
