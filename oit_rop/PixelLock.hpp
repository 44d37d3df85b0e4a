// PixelLock: the ordered pixel interlock (ROV / fragment_shader_interlock) as
// a scoreboard. Every fragment takes an entry when it is issued to the shader
// (in submission order) and frees it at release (end of blend, or end of
// shader + lock.shader_tail). A fragment that reached the lock may enter its
// critical section (the blending-array read-modify-write) only when
//  - ordered:   every older fragment of the same lock address has released
//               (strict submission order per address);
//  - unordered: no other fragment of the address is inside (mutual exclusion);
//               entering while an older one is still in flight is counted as
//               an out-of-order entry.
// The lock address is the pixel, its 2x2 quad or its tile (lock.granularity).
// Per-address in-flight lists live in an open-addressing hash map sized from
// the capacity (O(1), no allocation after construction).
#pragma once

#include <algorithm>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "oit_rop/PipelineQueues.hpp"
#include "oit_rop/RopConfig.hpp"

namespace oit::rop {

struct LockStats {
  uint64_t arrivals = 0;
  uint64_t conflicts = 0;      // arrivals that had to wait for the lock
  uint64_t wait_cycles = 0;    // sum over fragments of cycles waiting for the lock
  uint64_t longest_wait = 0;
  uint64_t out_of_order_entries = 0;
  uint64_t entries = 0;        // critical sections entered
  uint32_t peak_occupancy = 0; // scoreboard entries in use
};

class PixelLock {
 public:
  PixelLock(const LockConfig& cfg, uint32_t frame_width);

  // Lock address of pixel (x, y) under the configured granularity; tiles are
  // tile_w x tile_h (the blending-array cache line).
  uint32_t address(uint32_t x, uint32_t y, uint32_t tile_w, uint32_t tile_h) const;

  bool full() const { return free_.empty(); }
  uint32_t occupancy() const { return capacity_ - uint32_t(free_.size()); }
  uint32_t capacity() const { return capacity_; }
  // Takes a free entry for a fragment issued now (submission order); returns the
  // token id (< capacity), which names the fragment until release.
  uint32_t allocate(uint32_t address);
  // The fragment reached the lock (after the shader and early depth).
  void arrive(Cycle now, uint32_t token);
  // The fragment leaves without entering (culled by early depth).
  void drop(Cycle now, uint32_t token);
  // Fragments allowed in, oldest-eligible first; the consumer pops after it
  // accepted one into the critical section.
  bool hasReady() const { return !ready_.empty(); }
  uint32_t frontReady() const { return ready_.front(); }
  void enterFront(Cycle now);
  // End of the critical section (or of the shader): frees the entry.
  void release(Cycle now, uint32_t token);

  uint32_t waiting() const { return waiting_; }  // arrived, not yet allowed in
  const LockStats& stats() const { return stats_; }

 private:
  enum class State : uint8_t { Free, Issued, Waiting, Ready, Inside };
  struct Token {
    uint32_t address = 0;
    int32_t prev = -1, next = -1;  // same-address list, oldest first
    Cycle arrived = 0;
    State state = State::Free;
  };
  struct Slot {
    uint32_t address = 0;
    int32_t head = -1, tail = -1;  // -1 head = empty slot
    bool busy = false;             // unordered: a fragment is inside or admitted
  };
  static constexpr size_t kNpos = ~size_t(0);
  static size_t hashOf(uint32_t a) { return size_t((uint64_t(a) * 0x9E3779B97F4A7C15ull) >> 32); }
  size_t find(uint32_t address) const;  // slot index holding address, or npos
  size_t findOrInsert(uint32_t address);
  void eraseSlot(size_t i);
  // Removes the token from its address list (erasing the slot when it empties).
  // Returns the slot when t was its list's head or tail and the list is not
  // empty now, else npos.
  size_t unlink(uint32_t token);
  void admit(Cycle now, uint32_t token);
  void wakeNext(Cycle now, size_t slot);

  LockConfig cfg_;
  uint32_t capacity_, frame_width_;
  std::vector<Token> tok_;
  std::vector<uint32_t> free_;
  std::vector<Slot> map_;
  size_t mask_;
  Fifo<uint32_t> ready_;
  uint32_t waiting_ = 0;
  LockStats stats_;
};

// The per-fragment operations are inline: the partition calls them for every
// fragment (allocate, arrive, enter, release).
inline size_t PixelLock::find(uint32_t address) const {
  for (size_t i = hashOf(address) & mask_;; i = (i + 1) & mask_) {
    const Slot& s = map_[i];
    if (s.head < 0) return kNpos;
    if (s.address == address) return i;
  }
}

inline size_t PixelLock::findOrInsert(uint32_t address) {
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

inline uint32_t PixelLock::allocate(uint32_t address) {
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

inline void PixelLock::admit(Cycle now, uint32_t t) {
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

inline void PixelLock::arrive(Cycle now, uint32_t t) {
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

inline void PixelLock::enterFront(Cycle now) {
  (void)now;
  const uint32_t t = ready_.front();
  ready_.pop();
  Token& k = tok_[t];
  k.state = State::Inside;
  ++stats_.entries;
  // Unordered interlock: an older fragment of this address is still in flight.
  if (k.prev >= 0) ++stats_.out_of_order_entries;
}

inline size_t PixelLock::unlink(uint32_t t) {
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

inline void PixelLock::wakeNext(Cycle now, size_t si) {
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

inline void PixelLock::drop(Cycle now, uint32_t t) {
  const bool was_head = tok_[t].prev < 0;
  const size_t si = unlink(t);
  // Ordered: the dropped fragment may have been the one blocking the next.
  // (Only a dropped head unblocks anyone: a head is never left waiting.)
  if (cfg_.ordered && was_head && si != kNpos) wakeNext(now, si);
}

inline void PixelLock::release(Cycle now, uint32_t t) {
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
