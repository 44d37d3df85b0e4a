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
// The lock address names the pixel, its 2x2 quad or its tile (lock.granularity),
// numbered among the partition's own (FrameGeometry::lockAddress).
// Per-address in-flight lists hang off a direct-mapped table indexed by the
// address (8 B per address, 1 B more when unordered): no hashing, probing or
// erase per fragment (the open-addressing hash map with backward-shift erase
// it replaced cost 4 % more instructions of the whole timing run). The table
// grows to cover the largest address seen (calloc: pages of addresses never
// used are never touched); addresses are dense among the partition's own
// (FrameGeometry::lockAddress: about pixels / partitions of them), so once the
// first fragments spread over the frame it no longer allocates.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <memory>
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
  explicit PixelLock(const LockConfig& cfg);

  bool full() const { return free_count_ == 0; }
  uint32_t occupancy() const { return capacity_ - free_count_; }
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
  // An address's in-flight list; all-zero = no fragment of the address in
  // flight (so a calloc'd table starts empty).
  struct Slot {
    uint32_t head = 0, tail = 0;  // oldest / newest token + 1 (0 = none)
  };
  struct FreeDeleter {
    void operator()(void* p) const { std::free(p); }
  };
  // Makes the table cover `address` (cold: only when a larger address appears).
  void grow(uint32_t address);
  // Removes the token from its address list; returns whether it was the head
  // (the address's oldest fragment in flight).
  bool unlink(uint32_t token);
  void admit(Cycle now, uint32_t token);
  void wakeNext(Cycle now, uint32_t address);  // the address has fragments in flight

  LockConfig cfg_;
  uint32_t capacity_;
  std::vector<Token> tok_;
  std::vector<uint32_t> free_;  // free token ids, a stack of free_count_ (sized to the capacity: no push_back check)
  uint32_t free_count_ = 0;
  std::unique_ptr<Slot[], FreeDeleter> slots_;       // per address
  std::unique_ptr<uint8_t[], FreeDeleter> busy_;     // unordered: a fragment of the address is admitted or inside
  size_t slot_count_ = 0;
  Fifo<uint32_t> ready_;
  uint32_t waiting_ = 0;
  LockStats stats_;
};

// The per-fragment operations are inline: the partition calls them for every
// fragment (allocate, arrive, enter, release).
inline uint32_t PixelLock::allocate(uint32_t address) {
  if (free_count_ == 0) throw std::logic_error("PixelLock::allocate: scoreboard full");
  const uint32_t t = free_[--free_count_];
  Token& k = tok_[t];
  k.address = address;
  k.state = State::Issued;
  k.next = -1;
  if (address >= slot_count_) grow(address);
  Slot& s = slots_[address];
  k.prev = int32_t(s.tail) - 1;
  if (s.tail)
    tok_[s.tail - 1].next = int32_t(t);
  else
    s.head = t + 1;
  s.tail = t + 1;
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
    uint8_t& busy = busy_[k.address];
    eligible = !busy;
    busy = 1;
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

inline bool PixelLock::unlink(uint32_t t) {
  Token& k = tok_[t];
  Slot& s = slots_[k.address];
  const bool head = k.prev < 0;
  if (!head)
    tok_[size_t(k.prev)].next = k.next;
  else
    s.head = uint32_t(k.next + 1);
  if (k.next >= 0)
    tok_[size_t(k.next)].prev = k.prev;
  else
    s.tail = uint32_t(k.prev + 1);
  k.state = State::Free;  // (prev and next are dead until allocate() sets them)
  free_[free_count_++] = t;
  return head;
}

inline void PixelLock::wakeNext(Cycle now, uint32_t a) {
  const Slot& s = slots_[a];
  if (cfg_.ordered) {
    const uint32_t h = s.head - 1;
    if (tok_[h].state == State::Waiting) admit(now, h);
    return;
  }
  if (busy_[a]) return;
  for (int32_t i = int32_t(s.head) - 1; i >= 0; i = tok_[size_t(i)].next)
    if (tok_[size_t(i)].state == State::Waiting) {
      busy_[a] = 1;
      admit(now, uint32_t(i));
      return;
    }
}

inline void PixelLock::drop(Cycle now, uint32_t t) {
  const uint32_t a = tok_[t].address;
  const bool was_head = unlink(t);
  // Ordered: the dropped fragment may have been the one blocking the next.
  // (Only a dropped head unblocks anyone: a head is never left waiting.)
  if (cfg_.ordered && was_head && slots_[a].head) wakeNext(now, a);
}

inline void PixelLock::release(Cycle now, uint32_t t) {
  const uint32_t a = tok_[t].address;
  const bool was_head = unlink(t);
  // Unordered: the released fragment (wherever it sits in its list) frees the
  // address. Ordered: only the head holds the lock (a fragment enters only as
  // its address's oldest in flight and stays the head until it leaves).
  if (!cfg_.ordered) busy_[a] = 0;
  else if (!was_head) return;
  if (slots_[a].head) wakeNext(now, a);
}

}  // namespace oit::rop
