#include "oit_rop/PixelLock.hpp"

#include <algorithm>
#include <bit>
#include <stdexcept>

namespace oit::rop {

namespace {
constexpr size_t kNpos = ~size_t(0);
inline size_t hashOf(uint32_t a) { return size_t((uint64_t(a) * 0x9E3779B97F4A7C15ull) >> 32); }
}  // namespace

PixelLock::PixelLock(const LockConfig& cfg, uint32_t frame_width)
    : cfg_(cfg), capacity_(cfg.capacity), frame_width_(frame_width), ready_(64) {
  if (capacity_ == 0 || capacity_ > (1u << 24)) throw std::invalid_argument("lock.capacity must be in [1, 2^24]");
  tok_.resize(capacity_);
  free_.reserve(capacity_);
  // Lowest ids on top of the stack: token ids are deterministic.
  for (uint32_t i = capacity_; i-- > 0;) free_.push_back(i);
  map_.resize(std::max<size_t>(16, std::bit_ceil(size_t(capacity_) * 2)));
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

size_t PixelLock::find(uint32_t address) const {
  for (size_t i = hashOf(address) & mask_;; i = (i + 1) & mask_) {
    const Slot& s = map_[i];
    if (s.head < 0) return kNpos;
    if (s.address == address) return i;
  }
}

size_t PixelLock::findOrInsert(uint32_t address) {
  for (size_t i = hashOf(address) & mask_;; i = (i + 1) & mask_) {
    Slot& s = map_[i];
    if (s.head < 0) {
      s.address = address;
      s.busy = false;
      return i;  // the caller links a token (head becomes >= 0)
    }
    if (s.address == address) return i;
  }
}

void PixelLock::eraseSlot(size_t i) {
  // Backward-shift deletion keeps every probe chain intact without tombstones.
  size_t j = i;
  for (;;) {
    j = (j + 1) & mask_;
    if (map_[j].head < 0) break;
    const size_t k = hashOf(map_[j].address) & mask_;
    const bool movable = (i <= j) ? (k <= i || k > j) : (k <= i && k > j);
    if (movable) {
      map_[i] = map_[j];
      i = j;
    }
  }
  map_[i] = Slot{};
}

uint32_t PixelLock::allocate(uint32_t address) {
  if (free_.empty()) throw std::logic_error("PixelLock::allocate: scoreboard full");
  const uint32_t t = free_.back();
  free_.pop_back();
  Token& k = tok_[t];
  k.address = address;
  k.state = State::Issued;
  k.next = -1;
  Slot& s = map_[findOrInsert(address)];
  k.prev = s.tail;
  if (s.tail >= 0)
    tok_[size_t(s.tail)].next = int32_t(t);
  else
    s.head = int32_t(t);
  s.tail = int32_t(t);
  stats_.peak_occupancy = std::max(stats_.peak_occupancy, occupancy());
  return t;
}

void PixelLock::admit(Cycle now, uint32_t t) {
  Token& k = tok_[t];
  if (k.state == State::Waiting) {
    const uint64_t w = now - k.arrived;
    stats_.wait_cycles += w;
    stats_.longest_wait = std::max(stats_.longest_wait, w);
    --waiting_;
  }
  k.state = State::Ready;
  ready_.push(t);
}

void PixelLock::arrive(Cycle now, uint32_t t) {
  Token& k = tok_[t];
  ++stats_.arrivals;
  k.arrived = now;
  // Ordered: the head of the address's list is the token with no older one
  // (prev < 0), so no map lookup is needed.
  bool eligible;
  if (cfg_.ordered) {
    eligible = k.prev < 0;
  } else {
    Slot& s = map_[find(k.address)];
    eligible = !s.busy;
    if (eligible) s.busy = true;
  }
  if (eligible) {
    admit(now, t);
  } else {
    k.state = State::Waiting;
    ++waiting_;
    ++stats_.conflicts;
  }
}

void PixelLock::enterFront(Cycle now) {
  (void)now;
  const uint32_t t = ready_.front();
  ready_.pop();
  Token& k = tok_[t];
  k.state = State::Inside;
  ++stats_.entries;
  // Unordered interlock: an older fragment of this address is still in flight.
  if (k.prev >= 0) ++stats_.out_of_order_entries;
}

size_t PixelLock::unlink(uint32_t t) {
  Token& k = tok_[t];
  // The address's slot changes only when t is its oldest or newest token.
  size_t si = kNpos;
  if (k.prev >= 0) {
    tok_[size_t(k.prev)].next = k.next;
  } else {
    si = find(k.address);
    map_[si].head = k.next;
  }
  if (k.next >= 0) {
    tok_[size_t(k.next)].prev = k.prev;
  } else {
    if (si == kNpos) si = find(k.address);
    map_[si].tail = k.prev;
  }
  k.prev = k.next = -1;
  k.state = State::Free;
  free_.push_back(t);
  if (si != kNpos && map_[si].head < 0) {
    eraseSlot(si);
    return kNpos;  // no fragment of the address left in flight
  }
  return si;  // kNpos also when t sat in the middle of its list (slot unchanged)
}

void PixelLock::wakeNext(Cycle now, size_t si) {
  Slot& s = map_[si];
  if (cfg_.ordered) {
    const uint32_t h = uint32_t(s.head);
    if (tok_[h].state == State::Waiting) admit(now, h);
    return;
  }
  if (s.busy) return;
  for (int32_t i = s.head; i >= 0; i = tok_[size_t(i)].next)
    if (tok_[size_t(i)].state == State::Waiting) {
      s.busy = true;
      admit(now, uint32_t(i));
      return;
    }
}

void PixelLock::drop(Cycle now, uint32_t t) {
  const bool was_head = tok_[t].prev < 0;
  const size_t si = unlink(t);
  // Ordered: the dropped fragment may have been the one blocking the next.
  // (Only a dropped head unblocks anyone: a head is never left waiting.)
  if (cfg_.ordered && was_head && si != kNpos) wakeNext(now, si);
}

void PixelLock::release(Cycle now, uint32_t t) {
  const uint32_t a = tok_[t].address;
  const size_t si = unlink(t);
  if (si == kNpos && !cfg_.ordered) {
    // Unordered: a released fragment in the middle of its list still frees the address.
    const size_t sj = find(a);
    if (sj == kNpos) return;
    map_[sj].busy = false;
    wakeNext(now, sj);
    return;
  }
  if (si == kNpos) return;  // ordered: a middle token never holds the lock
  if (!cfg_.ordered) map_[si].busy = false;
  wakeNext(now, si);
}

}  // namespace oit::rop
