// PixelLock: the ordered pixel interlock (ROV / fragment_shader_interlock) as
// a scoreboard. Every fragment takes an entry when it is issued to the shader
// (in submission order) and frees it at release (end of blend, or end of
// shader + lock.shader_tail). A fragment that reached the lock may enter its
// critical section (the blending-array read-modify-write) only when
//  - ordered:   every older fragment of the same lock address has released
//               (strict submission order per address);
//  - unordered: no other fragment of the address is inside (mutual exclusion);
//  - none:      at once (no interlock: the read-modify-writes may overlap).
// Entering while an older fragment of the address is still in flight is
// counted as an out-of-order entry (unordered and none).
// The lock address names the pixel, its 2x2 quad or its tile (lock.granularity),
// numbered among the partition's own (FrameGeometry::lockAddress).
// Every fragment has an owner: at quad or tile granularity with
// lock.per_primitive, the first trace index of its primitive's run (the
// fragments of one primitive cover each pixel once, never overlap each other,
// and hardware shades a primitive's quad as one unit), so they hold the lock
// together: "older fragment of the address" above reads "older fragment of
// the address and of another owner". Otherwise every fragment owns itself.
// Per-address in-flight lists hang off a direct-mapped table indexed by the
// address (8 B per address, 8 B more when unordered): no hashing, probing or
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

#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/config/RopConfig.hpp"

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
  // token id (< capacity), which names the fragment until release. `owner`:
  // the first trace index of the fragment's primitive run (used when grouped()).
  uint32_t allocate(uint32_t address, uint32_t owner);
  // Fragments of one owner share the lock (quad/tile granularity, per_primitive).
  bool grouped() const { return grouped_; }
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
    uint32_t owner = 0;            // primitive run (grouped) or the token's own id
    Cycle arrived = 0;
    State state = State::Free;
    bool front = false;  // every older fragment of the address in flight has this owner
  };
  // An address's in-flight list; all-zero = no fragment of the address in
  // flight (so a calloc'd table starts empty).
  struct Slot {
    uint32_t head = 0, tail = 0;  // oldest / newest token + 1 (0 = none)
  };
  // Unordered interlock: fragments of the address admitted or inside, all of one owner.
  struct Busy {
    uint32_t count = 0, owner = 0;
  };
  struct FreeDeleter {
    void operator()(void* p) const { std::free(p); }
  };
  // Makes the table cover `address` (cold: only when a larger address appears).
  void grow(uint32_t address);
  // Removes the token from its address list and marks the fragments that are
  // now at the front of their address (ordered: admits those that wait).
  void unlink(Cycle now, uint32_t token);
  void admit(Cycle now, uint32_t token);
  void wakeUnordered(Cycle now, uint32_t address);  // the address's last admitted fragment left

  LockConfig cfg_;
  uint32_t capacity_;
  std::vector<Token> tok_;
  std::vector<uint32_t> free_;  // free token ids, a stack of free_count_ (sized to the capacity: no push_back check)
  uint32_t free_count_ = 0;
  std::unique_ptr<Slot[], FreeDeleter> slots_;       // per address
  std::unique_ptr<Busy[], FreeDeleter> busy_;        // unordered, per address
  size_t slot_count_ = 0;
  Fifo<uint32_t> ready_;
  uint32_t waiting_ = 0;
  bool grouped_ = false;
  bool ordered_, unordered_, unlocked_;  // lock.mode: ordered, unordered, none
  LockStats stats_;
};

// The per-fragment operations are inline: the partition calls them for every
// fragment (allocate, arrive, enter, release).
inline uint32_t PixelLock::allocate(uint32_t address, uint32_t owner) {
  if (free_count_ == 0) throw std::logic_error("PixelLock::allocate: scoreboard full");
  const uint32_t t = free_[--free_count_];
  Token& k = tok_[t];
  k.address = address;
  k.owner = grouped_ ? owner : t;  // token ids are distinct among the fragments in flight
  k.state = State::Issued;
  k.next = -1;
  if (address >= slot_count_) grow(address);
  Slot& s = slots_[address];
  k.prev = int32_t(s.tail) - 1;
  if (s.tail) {
    Token& p = tok_[s.tail - 1];
    p.next = int32_t(t);
    k.front = p.front & (p.owner == k.owner);
  } else {
    s.head = t + 1;
    k.front = true;
  }
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
  // Ordered: eligible when every older fragment of the address in flight has
  // its owner (front: no lookup needed).
  bool eligible;
  if (ordered_) {
    eligible = k.front;
  } else if (unlocked_) {
    eligible = true;
  } else {
    Busy& b = busy_[k.address];
    eligible = b.count == 0 || b.owner == k.owner;
    if (eligible) {
      ++b.count;
      b.owner = k.owner;
    }
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
  // Unordered interlock: an older fragment of another owner is still in flight.
  if (!k.front) ++stats_.out_of_order_entries;
}

inline void PixelLock::unlink(Cycle now, uint32_t t) {
  Token& k = tok_[t];
  Slot& s = slots_[k.address];
  const int32_t p = k.prev, n = k.next;
  if (p >= 0)
    tok_[size_t(p)].next = n;
  else
    s.head = uint32_t(n + 1);
  if (n >= 0)
    tok_[size_t(n)].prev = p;
  else
    s.tail = uint32_t(p + 1);
  k.state = State::Free;  // (prev and next are dead until allocate() sets them)
  free_[free_count_++] = t;
  // The next fragment and the rest of its owner's run reach the front when
  // nothing of another owner is older any more (p < 0: it is the head now; or
  // t stood between two fragments of one owner, the older at the front).
  if (n < 0 || tok_[size_t(n)].front) return;
  const uint32_t o = tok_[size_t(n)].owner;
  if (p >= 0) {
    // Bitwise & on purpose (no branch between two fields of one token, as in
    // allocate()); through a reference, not tok_[p] twice, whose call clang
    // takes for a side effect that && would skip (-Wbitwise-instead-of-logical).
    const Token& older = tok_[size_t(p)];
    if (!(older.front & (older.owner == o))) return;
  }
  for (int32_t i = n; i >= 0 && tok_[size_t(i)].owner == o; i = tok_[size_t(i)].next) {
    Token& f = tok_[size_t(i)];
    f.front = true;
    if (ordered_ && f.state == State::Waiting) admit(now, uint32_t(i));
  }
}

inline void PixelLock::wakeUnordered(Cycle now, uint32_t a) {
  // The oldest waiting fragment gets the address, with every other waiting
  // fragment of its owner.
  Busy& b = busy_[a];
  int32_t i = int32_t(slots_[a].head) - 1;
  while (i >= 0 && tok_[size_t(i)].state != State::Waiting) i = tok_[size_t(i)].next;
  if (i < 0) return;
  b.owner = tok_[size_t(i)].owner;
  b.count = 1;
  admit(now, uint32_t(i));
  if (!grouped_) return;  // its own owner: nobody else to admit
  for (i = tok_[size_t(i)].next; i >= 0; i = tok_[size_t(i)].next)
    if (tok_[size_t(i)].state == State::Waiting && tok_[size_t(i)].owner == b.owner) {
      ++b.count;
      admit(now, uint32_t(i));
    }
}

inline void PixelLock::drop(Cycle now, uint32_t t) {
  // Ordered: the dropped fragment may have been the one blocking the next.
  unlink(now, t);
}

inline void PixelLock::release(Cycle now, uint32_t t) {
  const uint32_t a = tok_[t].address;
  unlink(now, t);
  // Unordered: the last admitted fragment of the address frees it.
  if (unordered_ && --busy_[a].count == 0 && slots_[a].head) wakeUnordered(now, a);
}

}  // namespace oit::rop
