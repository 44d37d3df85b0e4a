// One DRAM channel's write queue. Writes are posted: the controller accepts a
// write into this queue (the requester may go on) and reads go to the bus
// first. When the waiting bursts reach the high watermark (dram.write_high),
// the controller drains whole rows of the oldest writes until at most the low
// watermark (dram.write_low) wait, as one batch: one read-to-write and one
// write-to-read turnaround per batch instead of one per write. A burst holds
// its entry (dram.write_queue entries in all) from its acceptance until its
// data is on the bus, so a full queue makes the next write wait: the queue
// pushes back on its requesters. Time is in DRAM ticks (DramTimings).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace oit::rop {

class DramWriteQueue {
 public:
  // A run of bursts of one request in one bank and row.
  struct Run {
    unsigned bank;
    uint64_t row;
    uint64_t bursts;
    uint64_t accepted;  // tick it entered the queue: not written before it
  };

  // capacity >= high >= 1, high > low (ConfigTree checks the configuration).
  DramWriteQueue(unsigned capacity, unsigned high, unsigned low);

  uint64_t pendingBursts() const { return pending_; }
  bool empty() const { return runs_.empty(); }
  // Would `bursts` more not fit beside the waiting ones? (The controller
  // drains first: a full queue forces a batch.)
  bool wouldOverflow(uint64_t bursts) const { return pending_ + bursts > capacity_; }
  // The first tick >= `arrive` at which `bursts` more fit beside the waiting
  // bursts and those drained whose data is not yet on the bus (a run larger
  // than the whole queue waits until it is empty), and not before an earlier
  // write that had to wait for room was accepted (writes enter in order).
  // Forgets the drained bursts whose data ended by then.
  uint64_t roomAt(uint64_t arrive, uint64_t bursts);
  void add(const Run& r);
  bool atHighWatermark() const { return pending_ >= high_; }
  // Takes the next batch out of the queue, in booking order: the oldest
  // waiting write with the later waiting writes of its row (merged into one
  // run: one activate; accepted = the latest of theirs), then the oldest
  // write left and its row, ... whole runs, until at most the low watermark
  // waits (`all`: until none does).
  const std::vector<Run>& takeBatch(bool all);
  // A drained run's data ends at `end`; its entries are free from then on.
  // Drained runs come in bus order, so their ends never decrease.
  void drained(uint64_t end, uint64_t bursts);

 private:
  struct InFlight {
    uint64_t end, bursts;
  };
  uint64_t capacity_, high_, low_;
  std::vector<Run> runs_;  // waiting, oldest first
  uint64_t pending_ = 0;   // their bursts
  std::vector<InFlight> in_flight_;  // drained, data not known to be over; from head_ on
  size_t head_ = 0;
  uint64_t in_flight_bursts_ = 0;
  uint64_t waited_until_ = 0;  // acceptance of the last write that waited for room
  std::vector<Run> batch_;
  std::vector<bool> taken_;
};

}  // namespace oit::rop
