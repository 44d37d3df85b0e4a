// The DRAM controller behind every ROP partition: channels with bandwidth,
// latency and banks, open-row or closed-page policy, read/write turnaround,
// posted writes drained in batches, refresh (parameters: DramConfig, from the
// presets; what is modelled and what is approximated: MEMORY.md).
//
// Reservation style, no event queue: access() books the request at the
// requested cycle and returns at once the cycle its data is delivered (read)
// or the cycle the controller accepted it (write: posted into the channel's
// write queue, written later in a batch; drainWrites() at the end of the
// frame writes what is left). Requests must arrive with non-decreasing `now`
// per caller; different callers (partitions running ahead within a SystemC
// quantum) may interleave slightly out of order, which the model tolerates. A
// booking is never moved once its cycle was returned.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "oit_rop/config/RopConfig.hpp"
#include "oit_rop/memory/DramActivateWindow.hpp"
#include "oit_rop/memory/DramAddressMap.hpp"
#include "oit_rop/memory/DramBusGaps.hpp"
#include "oit_rop/memory/DramTimings.hpp"
#include "oit_rop/memory/DramWriteQueue.hpp"
#include "oit_rop/RootCause.hpp"
#include "oit_rop/Types.hpp"

namespace oit::rop {

struct MemoryStats {
  std::array<uint64_t, kSurfaceCount> read_bytes{};
  std::array<uint64_t, kSurfaceCount> write_bytes{};
  uint64_t requests = 0;
  uint64_t row_hits = 0, row_misses = 0;
  std::vector<Cycle> channel_busy;  // core cycles each channel's data bus was busy
  Cycle last_completion = 0;
  // Bytes the data buses moved (whole bursts), bucketed by the cycle each burst
  // started on its bus, per setSampleInterval() interval. Bucketing by bus time,
  // not by request time, keeps every interval within the channels' bandwidth
  // (up to one burst per channel at the boundary) even when partitions book
  // requests ahead of each other inside a SystemC quantum.
  std::vector<uint64_t> bus_bytes_per_interval;
  uint64_t readBytes() const;
  uint64_t writeBytes() const;
};

class MemorySystem {
 public:
  MemorySystem(const DramConfig& cfg, double core_mhz);
  // Books a transfer of `bytes` at `addr` (split into bursts, interleaved over
  // channels by interleave_bytes). Returns the cycle a read's data is
  // delivered, or the cycle a write was accepted into the write queues
  // (>= now + controller latency).
  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s);
  // Writes every write still waiting in the write queues (booked from `now`,
  // the end of a partition's frame) and returns the cycle by which every write
  // accepted so far has its data in DRAM (>= now).
  Cycle drainWrites(Cycle now);
  const MemoryStats& stats() const;
  // Enables MemoryStats::bus_bytes_per_interval (0 disables it).
  void setSampleInterval(Cycle interval_cycles);
  // Doubles the sample interval: bus_bytes_per_interval[i] becomes the sum of
  // the old [2i] and [2i + 1], as if sampled at twice the interval all along.
  void coarsenSamples();
  // Peak bytes per core cycle the channels can move together.
  double peakBytesPerCycle() const;
  // Root-cause split of a wait (RootCause.hpp): the request completing last
  // since resetProbe(), with its latency: the cycles an idle controller takes
  // to its first data (a read: controller + tRCD + CL + one burst, the bank
  // precharged; a posted write: the controller accepting it), and the
  // transfer of its further bursts on its busiest channel at the bus's rate.
  // The rest of a wait is queueing. Queueing and transfer are bandwidth (the
  // same bytes on a wider or idle bus take less), the first data latency.
  void resetProbe() { probe_ = DramProbe{}; }
  const DramProbe& probe() const { return probe_; }
  Cycle unloadedCycles(bool write) const;
  // The share of the channels' data-bus time busy over [from, to) (0 to 1),
  // from a record of the bus time booked per block of kBusyBlock cycles: the
  // part of a wait's unloaded access during which the buses moved other data
  // is bandwidth, not latency (RootCause.hpp). Bookings still to come for the
  // span (a partition a quantum behind) are not in it yet.
  double busShare(Cycle from, Cycle to) const;
  static constexpr unsigned kBusyBlockShift = 8;  // 256 cycles
  Cycle transferCycles(uint64_t bursts) const;  // bursts - 1 beyond the first, rounded up

  // Added accessors (derived timing, for tests, reports and callers that
  // want the unloaded latency). Cycles are the exact fractional values the
  // model books with (sub-cycle fixed point, see MEMORY.md).
  unsigned channels() const { return static_cast<unsigned>(channels_.size()); }
  double bytesPerCyclePerChannel() const;
  double controllerCycles() const;
  double clCycles() const;
  double trcdCycles() const;
  double trpCycles() const;
  double trasCycles() const;
  double trrdCycles() const;   // activate to activate, different banks (0: no limit)
  double tfawCycles() const;   // four-activate window (0: none)
  double burstCycles() const;  // data-bus time of one burst
  double twtrCycles() const;   // end of write data to a read command
  double trtwCycles() const;   // idle bus between read data and write data
  // Bank groups (MEMORY.md "Bank groups"): the spacing of data starts on the
  // channel (max(burst, tCCD_S)) and in one group (max of that and tCCD_L),
  // and the in-group activate and write-to-read spacings.
  unsigned bankGroups() const { return t_.bank_groups; }
  double ccdSCycles() const;
  double ccdLCycles() const;
  double trrdLCycles() const;
  double twtrLCycles() const;
  // Write bursts waiting in channel c's queue (not yet booked on the bus).
  uint64_t pendingWriteBursts(unsigned c) const { return channels_[c].writes.pendingBursts(); }
  // Address mapping (MEMORY.md): channel, bank and row of a byte address.
  unsigned channelOf(uint64_t addr) const;
  unsigned bankOf(uint64_t addr) const;
  uint64_t rowOf(uint64_t addr) const;
  unsigned bankGroupOf(uint64_t addr) const { return bankOf(addr) % t_.bank_groups; }

 private:
  Cycle sample_interval_ = 0;
  size_t last_bucket_ = 0;  // bus_bytes_per_interval index of [bucket_begin_, + sample_interval_)
  static constexpr Cycle kNoBucket = ~Cycle(0);
  Cycle bucket_begin_ = kNoBucket;
  // Time inside the model is kept in ticks (DramTimings): fractional DRAM
  // timings and bandwidths do not accumulate rounding.
  static constexpr unsigned kTickShift = DramTimings::kTickShift;
  static constexpr uint64_t kNoRow = ~uint64_t(0);

  struct Bank {
    uint64_t open_row = kNoRow;  // open-row policy only
    uint64_t row_ready = 0;      // ticks: the open row accepts column commands
    uint64_t last_end = 0;       // ticks: end of the last data transfer of this bank
    uint64_t act_ready = 0;      // ticks: closed-row policy, precharged and ready to activate
    uint64_t act = 0;            // ticks: the last activate (tRAS counts from it)
  };

  // One channel: its data bus, its turnaround state, the idle stretches a
  // later read may take (DramBusGaps), its write queue and its activates
  // (tRRD, tFAW: the model has one rank per channel).
  struct Channel {
    uint64_t bus_free = 0;  // ticks: end of the latest data on the bus
    uint64_t busy = 0;      // ticks of data moved
    uint64_t last_read_end = 0, last_write_end = 0;  // ticks (turnarounds)
    bool last_was_write = false;  // the data ending at bus_free is a write's
    uint64_t booked = 0;          // bursts booked so far (the scheduler window's clock)
    DramBusGaps gaps;
    DramWriteQueue writes;
    DramQueueParts drain_queue;  // what the latest drained batch waited for (a full write queue's wait)
    // Ticks the bus idled per 2^kBusyBlockShift cycles because the run after
    // it waited for its bank, a turnaround, a refresh (queueParts).
    std::array<std::vector<uint64_t>, 3> idle_blocks;
    DramActivateWindow activates;
    // Per bank group (dram.bank_groups > 1, else empty): the earliest data
    // start tCCD_L allows after the group's latest burst, and the end of the
    // group's latest write data (tWTR_L; 0: none yet).
    std::vector<uint64_t> group_next, group_write_end;
    Channel(const DramConfig& c, const DramTimings& t)
        : writes(c.write_queue, c.write_high, c.write_low),
          activates(t.trrd, t.tfaw, t.trrd_l),
          group_next(t.bank_groups > 1 ? t.bank_groups : 0, 0),
          group_write_end(t.bank_groups > 1 ? t.bank_groups : 0, 0) {}
  };

  // access() after its checks and byte counts; Pow2 = map_.pow2.
  template <bool Pow2>
  Cycle book(Cycle now, uint64_t addr, uint32_t bytes, bool write);
  // Books a run (n bursts on channel ch, bank, row; no command before
  // `earliest`, the request's arrival) on the bus and returns the end of its
  // data (ticks). A read may take a gap the bus left idle (DramBusGaps).
  template <bool Write>
  uint64_t bookRun(unsigned ch, unsigned bank_no, uint64_t row, uint64_t n, uint64_t earliest);
  // Where a run was placed for its queueing by cause: from `earliest`, its
  // column command at `column`, data at `xfer`; `refresh_wait` ticks the
  // refresh moved it by, the bus idle for it over [refresh_from, refresh_to)
  // (refresh_to 0: up to where the run could start).
  struct RunPlace {
    uint64_t earliest = 0, column = 0, xfer = 0;
    uint64_t hold = 0;        // the activate limits' (tRRD, tFAW) hold on its activate
    bool after_data = false;  // its first command waited for its bank's last data (a bus-delayed transfer)
    uint64_t refresh_wait = 0, refresh_from = 0, refresh_to = 0;
    bool refreshed = false;  // a refresh moved it or closed its row
  };
  // The queueing of a run placed as `at` (its data at `xfer` in the end) by
  // cause (RootCause.hpp, DramQueueParts); records the bus's idle stretch
  // before it. Called before the channel's state is updated for the run.
  DramQueueParts queueParts(Channel& c, const RunPlace& at, uint64_t xfer, bool in_gap);
  // Queues a write run arriving at `arrive`; returns the tick it is accepted.
  uint64_t postWrite(unsigned ch, unsigned bank_no, uint64_t row, uint64_t n, uint64_t arrive);
  // Books channel ch's next batch of writes from `at` (`all`: every waiting one).
  void drainBatch(unsigned ch, uint64_t at, bool all);
  // Adds `n` bursts starting on the bus at ticks xfer, xfer + step, ... to
  // bus_bytes_per_interval (bucket of each burst's start cycle).
  void sampleBursts(uint64_t xfer, uint64_t n, uint64_t step);

  DramConfig cfg_;  // first: checked before the map and the timings are built from it
  DramAddressMap map_;
  DramTimings t_;
  std::vector<Channel> channels_;
  std::vector<Bank> banks_;  // channel-major: channel * banks + bank
  uint64_t hits_ = 0, misses_ = 0;  // row hits and misses of the runs booked (added to stats_)
  uint64_t window_ = 0;  // DramBusGaps::Asker::window: queue_depth with FR-FCFS, 0 with FCFS
  MemoryStats stats_;
  DramProbe probe_;
  DramQueueParts run_queue_;  // the latest bookRun's queueing by cause
  std::vector<uint64_t> busy_blocks_;  // bus ticks booked per 2^kBusyBlockShift cycles, all channels
  void addBusy(uint64_t from_tick, uint64_t len);
};

}  // namespace oit::rop
