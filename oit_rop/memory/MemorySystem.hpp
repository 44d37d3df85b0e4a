// The DRAM behind every ROP partition: channels with bandwidth, latency, banks
// and an open-row policy (parameters: DramConfig, from the presets).
//
// Reservation style, no event queue: access() books the request on its channel
// and bank at the requested cycle and returns the cycle its data is delivered
// (read) or written (write). Requests must arrive with non-decreasing `now` per
// caller; different callers (partitions running ahead within a SystemC quantum)
// may interleave slightly out of order, which the model tolerates.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "oit_rop/config/RopConfig.hpp"
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
  // channels by interleave_bytes). Returns the completion cycle (>= now + latency).
  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s);
  const MemoryStats& stats() const;
  // Enables MemoryStats::bus_bytes_per_interval (0 disables it).
  void setSampleInterval(Cycle interval_cycles);
  // Doubles the sample interval: bus_bytes_per_interval[i] becomes the sum of
  // the old [2i] and [2i + 1], as if sampled at twice the interval all along.
  void coarsenSamples();
  // Peak bytes per core cycle the channels can move together.
  double peakBytesPerCycle() const;
  // "" when dram.trefi_ns / trfc_ns are usable at core_mhz, else what is wrong
  // (the time between two refreshes must hold one row's transfer, MEMORY.md).
  static std::string refreshProblem(const DramConfig& cfg, double core_mhz);

  // Added accessors (derived timing, for tests, reports and callers that
  // want the unloaded latency). Cycles are the exact fractional values the
  // model books with (sub-cycle fixed point, see MEMORY.md).
  unsigned channels() const { return static_cast<unsigned>(bus_free_.size()); }
  double bytesPerCyclePerChannel() const;
  double controllerCycles() const;
  double clCycles() const;
  double trcdCycles() const;
  double trpCycles() const;
  double trasCycles() const;
  double burstCycles() const;  // data-bus time of one burst
  // Address mapping (MEMORY.md): channel, bank and row of a byte address.
  unsigned channelOf(uint64_t addr) const;
  unsigned bankOf(uint64_t addr) const;
  uint64_t rowOf(uint64_t addr) const;

 private:
  Cycle sample_interval_ = 0;
  size_t last_bucket_ = 0;  // bus_bytes_per_interval index of [bucket_begin_, + sample_interval_)
  static constexpr Cycle kNoBucket = ~Cycle(0);
  Cycle bucket_begin_ = kNoBucket;
  // Time inside the model is kept in ticks: 1 core cycle = 2^kTickShift ticks,
  // so fractional DRAM timings and bandwidths do not accumulate rounding.
  static constexpr unsigned kTickShift = 16;
  static constexpr uint64_t kNoRow = ~uint64_t(0);

  // Division by a configuration constant; a shift/mask when it is a power of two.
  struct Divisor {
    uint64_t d = 1;
    uint64_t mask = 0;  // d - 1
    int shift = 0;      // -1: not a power of two
    void set(uint64_t v);
    uint64_t div(uint64_t x) const { return shift >= 0 ? x >> shift : x / d; }
    uint64_t mod(uint64_t x) const { return shift >= 0 ? x & mask : x % d; }
    // Pow2: the caller knows d is a power of two (no test per operation).
    template <bool Pow2>
    uint64_t div(uint64_t x) const { return Pow2 ? x >> shift : div(x); }
    template <bool Pow2>
    uint64_t mod(uint64_t x) const { return Pow2 ? x & mask : mod(x); }
  };

  struct Bank {
    uint64_t open_row = kNoRow;  // open-row policy only
    uint64_t row_ready = 0;      // ticks: the open row accepts column commands
    uint64_t last_end = 0;       // ticks: end of the last data transfer of this bank
    uint64_t act_ready = 0;      // ticks: closed-row policy, precharged and ready to activate
    uint64_t act = 0;            // ticks: the last activate (tRAS counts from it)
  };

  struct Location {
    unsigned channel;
    unsigned bank;
    uint64_t row;
  };
  Location locate(uint64_t addr) const;
  // The address map's constants.
  struct AddressMap {
    Divisor burst, interleave, channel, row, bank;
    // In bursts: an interleave chunk, a row (access() works on burst numbers).
    Divisor chunk_bursts, row_bursts;
    bool multi_channel = false;  // chunks rotate over several channels
    bool hash = false;           // DramConfig::bank_hash and more than one bank
    bool pow2 = false;           // burst, chunk, channels, row and banks all powers of two
    Location locate(uint64_t addr) const;
  };
  // Bank (hashed when `hash`, dram.bank_hash) and row of a channel's row line
  // (its local address / row_bytes); the channel is the caller's.
  template <bool Pow2>
  static void bankRow(const Divisor& bank, bool hash, uint64_t row_line, unsigned& bank_out, uint64_t& row_out);
  // access() after its checks and byte counts; Pow2 = map_.pow2.
  template <bool Pow2>
  Cycle book(Cycle now, uint64_t addr, uint32_t bytes);
  // Refresh (dram.trefi_ns > 0): channel c refreshes all its banks in the
  // windows [w, w + rfc) at w = off_c + k * period, k >= 1, off_c = c * period /
  // channels (staggered). Start of the latest window at or before t (0: none);
  // end of the first window meeting [from, end) (0: none).
  uint64_t lastRefreshStart(unsigned ch, uint64_t t) const {
    const uint64_t off = refresh_off_[ch];
    if (t < off + refresh_period_) return 0;
    return off + (t - off) / refresh_period_ * refresh_period_;
  }
  uint64_t refreshOverlapEnd(unsigned ch, uint64_t from, uint64_t end) const {
    const uint64_t off = refresh_off_[ch];
    uint64_t w = off + std::max<uint64_t>(1, from > off ? (from - off) / refresh_period_ : 0) * refresh_period_;
    if (w + refresh_rfc_ <= from) w += refresh_period_;
    return w < end ? w + refresh_rfc_ : 0;
  }
  // Adds `n` bursts starting on the bus at ticks xfer, xfer + step, ... to
  // bus_bytes_per_interval (bucket of each burst's start cycle).
  void sampleBursts(uint64_t xfer, uint64_t n, uint64_t step);

  DramConfig cfg_;
  double core_mhz_ = 0;
  uint64_t ctrl_ticks_ = 0, cl_ticks_ = 0, trcd_ticks_ = 0, trp_ticks_ = 0, tras_ticks_ = 0, burst_ticks_ = 0;
  uint64_t act_step_ticks_ = 0;  // closed row: max(tRCD + CL + burst, tRAS) + tRP
  uint64_t refresh_period_ = 0, refresh_rfc_ = 0;  // ticks; period 0: no refresh
  std::vector<uint64_t> refresh_off_;              // ticks, per channel
  AddressMap map_;
  std::vector<uint64_t> bus_free_;    // ticks, per channel
  std::vector<uint64_t> busy_ticks_;  // ticks, per channel
  std::vector<Bank> banks_;           // channel-major: channel * banks + bank
  MemoryStats stats_;
};

}  // namespace oit::rop
