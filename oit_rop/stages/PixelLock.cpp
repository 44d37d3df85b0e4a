#include "oit_rop/stages/PixelLock.hpp"

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>

namespace oit::rop {

PixelLock::PixelLock(const LockConfig& cfg)
    : cfg_(cfg),
      capacity_(cfg.capacity),
      ready_(64),
      ordered_(cfg.mode == LockMode::Ordered),
      unordered_(cfg.mode == LockMode::Unordered),
      unlocked_(cfg.mode == LockMode::None) {
  if (capacity_ == 0 || capacity_ > (1u << 24)) throw std::invalid_argument("lock.capacity must be in [1, 2^24]");
  tok_.resize(capacity_);
  free_.resize(capacity_);
  // Lowest ids on top of the stack: token ids are deterministic.
  for (uint32_t i = capacity_; i-- > 0;) free_[free_count_++] = i;
  grouped_ = cfg.per_primitive && cfg.granularity != LockGranularity::Pixel;
}

void PixelLock::grow(uint32_t address) {
  // Power-of-two sizes: a few regrowths while the first fragments spread over
  // the frame. calloc: the zero (empty) pages of unused addresses stay untouched.
  const size_t n = std::max<size_t>(1024, std::bit_ceil(size_t(address) + 1));
  auto* slots = static_cast<Slot*>(std::calloc(n, sizeof(Slot)));
  auto* busy = unordered_ ? static_cast<Busy*>(std::calloc(n, sizeof(Busy))) : nullptr;
  if (!slots || (unordered_ && !busy)) {
    std::free(slots);
    std::free(busy);
    throw std::bad_alloc();
  }
  if (slot_count_) {
    std::memcpy(slots, slots_.get(), slot_count_ * sizeof(Slot));
    if (busy) std::memcpy(busy, busy_.get(), slot_count_ * sizeof(Busy));
  }
  slots_.reset(slots);
  busy_.reset(busy);
  slot_count_ = n;
}

}  // namespace oit::rop
