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

#include <cstdint>
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

}  // namespace oit::rop
