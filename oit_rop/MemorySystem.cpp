// Reservation-style DRAM model; formulas and address mapping in MEMORY.md.
#include "oit_rop/MemorySystem.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace oit::rop {

namespace {

// Converts a non-negative amount of core cycles to ticks, rounding up so that a
// latency or transfer time is never shorter than configured. Values within
// 1e-9 (relative) of an integer tick count are taken as that integer: 5.75
// cycles must not become 5.75 cycles + 1 tick through floating-point noise.
uint64_t cyclesToTicks(double cycles, unsigned shift) {
  const double t = std::ldexp(cycles, static_cast<int>(shift));
  const double r = std::round(t);
  if (std::fabs(t - r) <= 1e-9 * std::max(1.0, r)) return static_cast<uint64_t>(r);
  return static_cast<uint64_t>(std::ceil(t));
}

void require(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("DramConfig: ") + what);
}

}  // namespace

uint64_t MemoryStats::readBytes() const {
  uint64_t n = 0;
  for (uint64_t b : read_bytes) n += b;
  return n;
}

uint64_t MemoryStats::writeBytes() const {
  uint64_t n = 0;
  for (uint64_t b : write_bytes) n += b;
  return n;
}

void MemorySystem::Divisor::set(uint64_t v) {
  d = v;
  shift = -1;
  if (v != 0 && (v & (v - 1)) == 0) {
    shift = 0;
    while ((uint64_t(1) << shift) != v) ++shift;
  }
}

MemorySystem::MemorySystem(const DramConfig& cfg, double core_mhz) : cfg_(cfg), core_mhz_(core_mhz) {
  require(core_mhz > 0, "core_mhz must be > 0");
  require(cfg.channels >= 1, "channels must be >= 1");
  require(cfg.banks >= 1, "banks must be >= 1");
  require(cfg.channel_gbps > 0, "channel_gbps must be > 0");
  require(cfg.tck_ns > 0, "tck_ns must be > 0");
  require(cfg.controller_ns >= 0, "controller_ns must be >= 0");
  require(cfg.burst_bytes >= 1, "burst_bytes must be >= 1");
  // A burst must stay inside one channel and one row.
  require(cfg.interleave_bytes >= cfg.burst_bytes && cfg.interleave_bytes % cfg.burst_bytes == 0,
          "interleave_bytes must be a multiple of burst_bytes");
  require(cfg.row_bytes >= cfg.burst_bytes && cfg.row_bytes % cfg.burst_bytes == 0,
          "row_bytes must be a multiple of burst_bytes");

  const double cycles_per_ns = core_mhz / 1000.0;
  ctrl_ticks_ = cyclesToTicks(cfg.controller_ns * cycles_per_ns, kTickShift);
  cl_ticks_ = cyclesToTicks(cfg.cl * cfg.tck_ns * cycles_per_ns, kTickShift);
  trcd_ticks_ = cyclesToTicks(cfg.trcd * cfg.tck_ns * cycles_per_ns, kTickShift);
  trp_ticks_ = cyclesToTicks(cfg.trp * cfg.tck_ns * cycles_per_ns, kTickShift);
  burst_ticks_ = cyclesToTicks(cfg.burst_bytes / bytesPerCyclePerChannel(), kTickShift);
  require(burst_ticks_ >= 1, "bandwidth too high for the tick resolution");

  burst_div_.set(cfg.burst_bytes);
  interleave_div_.set(cfg.interleave_bytes);
  channel_div_.set(cfg.channels);
  row_div_.set(cfg.row_bytes);
  bank_div_.set(cfg.banks);

  bus_free_.assign(cfg.channels, 0);
  busy_ticks_.assign(cfg.channels, 0);
  banks_.assign(size_t(cfg.channels) * cfg.banks, Bank{});
  stats_.channel_busy.assign(cfg.channels, 0);
}

double MemorySystem::bytesPerCyclePerChannel() const {
  // GB/s / (cycles/s): channel_gbps * 1e9 / (core_mhz * 1e6)
  return cfg_.channel_gbps * 1000.0 / core_mhz_;
}

double MemorySystem::peakBytesPerCycle() const { return bytesPerCyclePerChannel() * cfg_.channels; }

double MemorySystem::controllerCycles() const { return std::ldexp(double(ctrl_ticks_), -int(kTickShift)); }
double MemorySystem::clCycles() const { return std::ldexp(double(cl_ticks_), -int(kTickShift)); }
double MemorySystem::trcdCycles() const { return std::ldexp(double(trcd_ticks_), -int(kTickShift)); }
double MemorySystem::trpCycles() const { return std::ldexp(double(trp_ticks_), -int(kTickShift)); }
double MemorySystem::burstCycles() const { return std::ldexp(double(burst_ticks_), -int(kTickShift)); }

const MemoryStats& MemorySystem::stats() const { return stats_; }

MemorySystem::Location MemorySystem::locate(uint64_t addr) const {
  // addr = [row | bank | column-high | channel | column-low(interleave)]
  const uint64_t chunk = interleave_div_.div(addr);
  const uint64_t local = channel_div_.div(chunk) * cfg_.interleave_bytes + interleave_div_.mod(addr);
  const uint64_t row_line = row_div_.div(local);
  return Location{static_cast<unsigned>(channel_div_.mod(chunk)), static_cast<unsigned>(bank_div_.mod(row_line)),
                  bank_div_.div(row_line)};
}

unsigned MemorySystem::channelOf(uint64_t addr) const { return locate(addr).channel; }
unsigned MemorySystem::bankOf(uint64_t addr) const { return locate(addr).bank; }
uint64_t MemorySystem::rowOf(uint64_t addr) const { return locate(addr).row; }

void MemorySystem::setSampleInterval(Cycle interval_cycles) {
  sample_interval_ = interval_cycles;
  bucket_begin_ = kNoBucket;  // the next burst computes its bucket
}

Cycle MemorySystem::access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) {
  if (bytes == 0) return now;  // nothing to move; not counted as a request
  // Ticks must not overflow: 2^48 cycles is far beyond any frame.
  if (now >= (Cycle(1) << (64 - kTickShift - 1)))
    throw std::out_of_range("MemorySystem::access: cycle out of range");

  const unsigned si = static_cast<unsigned>(s);
  (write ? stats_.write_bytes : stats_.read_bytes)[si] += bytes;
  ++stats_.requests;

  const uint64_t arrive = (uint64_t(now) << kTickShift) + ctrl_ticks_;
  uint64_t done = arrive;
  const uint64_t first = burst_div_.div(addr);
  const uint64_t last = burst_div_.div(addr + bytes - 1);
  for (uint64_t b = first; b <= last; ++b) {
    const Location loc = locate(b * cfg_.burst_bytes);
    Bank& bank = banks_[size_t(loc.channel) * cfg_.banks + loc.bank];
    uint64_t column;  // tick the column command (read or write) issues
    if (cfg_.open_row) {
      if (bank.open_row == loc.row) {
        ++stats_.row_hits;
        column = std::max(arrive, bank.row_ready);
      } else {
        ++stats_.row_misses;
        // Precharge may start once the open row is active and its transfers ended.
        uint64_t start = std::max({arrive, bank.row_ready, bank.last_end});
        if (bank.open_row != kNoRow) start += trp_ticks_;
        bank.open_row = loc.row;
        bank.row_ready = start + trcd_ticks_;
        column = bank.row_ready;
      }
    } else {
      ++stats_.row_misses;  // every access activates its row
      column = std::max(arrive, bank.act_ready) + trcd_ticks_;
    }
    uint64_t& bus = bus_free_[loc.channel];
    const uint64_t xfer = std::max(column + cl_ticks_, bus);
    const uint64_t end = xfer + burst_ticks_;
    bus = end;
    if (sample_interval_) {
      // Bursts come in bus order per channel, so the last bucket usually
      // matches: skip the division then.
      const Cycle c = xfer >> kTickShift;
      if (c < bucket_begin_ || c - bucket_begin_ >= sample_interval_) {
        last_bucket_ = size_t(c / sample_interval_);
        bucket_begin_ = Cycle(last_bucket_) * sample_interval_;
        if (last_bucket_ >= stats_.bus_bytes_per_interval.size())
          stats_.bus_bytes_per_interval.resize(last_bucket_ + 1, 0);
      }
      stats_.bus_bytes_per_interval[last_bucket_] += cfg_.burst_bytes;
    }
    bank.last_end = std::max(bank.last_end, end);
    if (!cfg_.open_row) bank.act_ready = bank.last_end + trp_ticks_;  // auto-precharge after the data
    busy_ticks_[loc.channel] += burst_ticks_;
    stats_.channel_busy[loc.channel] = (busy_ticks_[loc.channel] + (uint64_t(1) << kTickShift) - 1) >> kTickShift;
    done = std::max(done, end);
  }
  const Cycle completion = (done + (uint64_t(1) << kTickShift) - 1) >> kTickShift;
  stats_.last_completion = std::max(stats_.last_completion, completion);
  return completion;
}

}  // namespace oit::rop
