// Idle stretches of one DRAM channel's data bus before its latest booking.
// The controller books requests as they come (reservation style) and never
// moves a booking once its completion was returned; a gap is left where a
// request's data had to wait for its bank (precharge, activate) or for a
// turnaround while the bus was free. A later request whose data fits whole
// into such a gap may take it, as a reordering scheduler would have issued it
// there:
// - FR-FCFS (dram.scheduler = frfcfs): a request booked within queue_depth
//   bursts of the one that left the gap (it would have been in the
//   controller's window together with it);
// - FCFS and FR-FCFS: a request that arrived before the one that left the gap
//   (booked later only because its partition runs behind inside the SystemC
//   quantum), since first come is first served.
// Only reads take gaps (writes drain in batches at the bus's end). Time is in
// DRAM ticks (DramTimings).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace oit::rop {

class DramBusGaps {
 public:
  struct Gap {
    uint64_t begin, end;      // the idle bus time [begin, end)
    uint64_t seq;             // the channel's booked bursts when the gap was left
    uint64_t creator_arrive;  // arrival of the request that left it
    bool write_before, write_after;  // the transfers at its ends are writes (turnarounds)
  };
  // Gaps kept per channel: the oldest is forgotten beyond this (a search is
  // O(kMaxGaps) and runs only when the bus would delay a request).
  static constexpr size_t kMaxGaps = 8;

  // Who may take a gap: window = queue_depth with FR-FCFS, 0 with FCFS.
  struct Asker {
    uint64_t arrive;  // the request's arrival
    uint64_t seq;     // the channel's booked bursts now
    uint64_t window;
    bool mayUse(const Gap& g) const { return arrive < g.creator_arrive || seq - g.seq < window; }
  };

  bool empty() const { return gaps_.empty(); }
  // The latest end of any gap (0: none): a request whose data cannot start
  // and end before it needs no search.
  uint64_t latestEnd() const { return latest_end_; }
  size_t size() const { return gaps_.size(); }
  const Gap& operator[](size_t i) const { return gaps_[i]; }

  // Adds a gap after every kept one (gaps are left in bus order).
  void add(const Gap& g);
  // The read data that may start at `from` and lasts `len` ticks: the start of
  // the earliest gap `asker` may take that holds it whole, with tWTR + CL
  // (`after_write`) after a write at its beginning and tRTW (`before_write`)
  // before a write at its end; kNone if none does. `index` names the gap.
  static constexpr uint64_t kNone = ~uint64_t(0);
  uint64_t find(const Asker& asker, uint64_t from, uint64_t len, uint64_t after_write, uint64_t before_write,
                size_t& index) const;
  // Books [start, start + len) of read data inside gap `index` (as found):
  // what stays idle on either side remains a gap if it can hold a burst.
  void take(size_t index, uint64_t start, uint64_t len, uint64_t min_len);

 private:
  std::vector<Gap> gaps_;
  uint64_t latest_end_ = 0;
};

}  // namespace oit::rop
