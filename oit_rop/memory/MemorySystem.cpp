// Reservation-style DRAM model; formulas and address mapping in MEMORY.md.
#include "oit_rop/memory/MemorySystem.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <stdexcept>
#include <string>

namespace oit::rop {

namespace {

// The geometry the address map needs (a burst never straddles a channel or a
// row), checked before the map is built from it.
const DramConfig& checkedGeometry(const DramConfig& cfg) {
  requireDramConfig(cfg.channels >= 1, "channels must be >= 1");
  requireDramConfig(cfg.banks >= 1, "banks must be >= 1");
  requireDramConfig(cfg.burst_bytes >= 1, "burst_bytes must be >= 1");
  requireDramConfig(cfg.interleave_bytes >= cfg.burst_bytes && cfg.interleave_bytes % cfg.burst_bytes == 0,
          "interleave_bytes must be a multiple of burst_bytes");
  requireDramConfig(cfg.row_bytes >= cfg.burst_bytes && cfg.row_bytes % cfg.burst_bytes == 0,
          "row_bytes must be a multiple of burst_bytes");
  return cfg;
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

MemorySystem::MemorySystem(const DramConfig& cfg, double core_mhz)
    : cfg_(checkedGeometry(cfg)), map_(cfg_), t_(cfg_, core_mhz) {
  requireDramConfig(cfg.write_queue >= 1 && cfg.write_high >= 1 && cfg.write_high <= cfg.write_queue &&
              cfg.write_low < cfg.write_high,
          "write watermarks must satisfy write_low < write_high <= write_queue");
  channels_.assign(cfg.channels, Channel(cfg));
  window_ = cfg.scheduler == DramScheduler::FrFcfs ? cfg.queue_depth : 0;
  banks_.assign(size_t(cfg.channels) * cfg.banks, Bank{});
  stats_.channel_busy.assign(cfg.channels, 0);
}

double MemorySystem::bytesPerCyclePerChannel() const { return t_.bytes_per_cycle; }
double MemorySystem::peakBytesPerCycle() const { return t_.bytes_per_cycle * cfg_.channels; }

double MemorySystem::controllerCycles() const { return DramTimings::cycles(t_.ctrl); }
double MemorySystem::clCycles() const { return DramTimings::cycles(t_.cl); }
double MemorySystem::trcdCycles() const { return DramTimings::cycles(t_.trcd); }
double MemorySystem::trpCycles() const { return DramTimings::cycles(t_.trp); }
double MemorySystem::trasCycles() const { return DramTimings::cycles(t_.tras); }
double MemorySystem::burstCycles() const { return DramTimings::cycles(t_.burst); }
double MemorySystem::twtrCycles() const { return DramTimings::cycles(t_.twtr); }
double MemorySystem::trtwCycles() const { return DramTimings::cycles(t_.trtw); }

const MemoryStats& MemorySystem::stats() const { return stats_; }

unsigned MemorySystem::channelOf(uint64_t addr) const { return map_.locate(addr).channel; }
unsigned MemorySystem::bankOf(uint64_t addr) const { return map_.locate(addr).bank; }
uint64_t MemorySystem::rowOf(uint64_t addr) const { return map_.locate(addr).row; }

void MemorySystem::setSampleInterval(Cycle interval_cycles) {
  sample_interval_ = interval_cycles;
  bucket_begin_ = kNoBucket;  // the next burst computes its bucket
}

void MemorySystem::coarsenSamples() {
  std::vector<uint64_t>& b = stats_.bus_bytes_per_interval;
  for (size_t i = 0; 2 * i < b.size(); ++i) b[i] = b[2 * i] + (2 * i + 1 < b.size() ? b[2 * i + 1] : 0);
  b.resize((b.size() + 1) / 2);
  sample_interval_ *= 2;
  bucket_begin_ = kNoBucket;  // the next burst computes its bucket
}

void MemorySystem::sampleBursts(uint64_t xfer, uint64_t n, uint64_t step) {
  // access() handles a run that starts wholly in the current bucket itself.
  for (;;) {
    // Bursts come in bus order per channel, so the last bucket usually
    // matches: skip the division then.
    const Cycle c = xfer >> kTickShift;
    if (c < bucket_begin_ || c - bucket_begin_ >= sample_interval_) {
      last_bucket_ = size_t(c / sample_interval_);
      bucket_begin_ = Cycle(last_bucket_) * sample_interval_;
      if (last_bucket_ >= stats_.bus_bytes_per_interval.size())
        stats_.bus_bytes_per_interval.resize(last_bucket_ + 1, 0);
    }
    // Start cycles grow along the run: if the last burst lands in this bucket,
    // so do all before it (the usual case); else book one and look again.
    const Cycle last = (xfer + (n - 1) * step) >> kTickShift;
    if (last - bucket_begin_ < sample_interval_) {
      stats_.bus_bytes_per_interval[last_bucket_] += n * cfg_.burst_bytes;
      return;
    }
    stats_.bus_bytes_per_interval[last_bucket_] += cfg_.burst_bytes;
    xfer += step;
    --n;
  }
}

Cycle MemorySystem::access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) {
  if (bytes == 0) return now;  // nothing to move; not counted as a request
  // Ticks must not overflow: 2^48 cycles is far beyond any frame.
  if (now >= (Cycle(1) << (64 - kTickShift - 1)))
    throw std::out_of_range("MemorySystem::access: cycle out of range");

  const unsigned si = static_cast<unsigned>(s);
  (write ? stats_.write_bytes : stats_.read_bytes)[si] += bytes;
  ++stats_.requests;
  return map_.pow2 ? book<true>(now, addr, bytes, write) : book<false>(now, addr, bytes, write);
}

template <bool Pow2>
Cycle MemorySystem::book(Cycle now, uint64_t addr, uint32_t bytes, bool write) {
  const DramDivisor &chunk_div = map_.chunk_bursts, &channel_div = map_.channel;
  const DramDivisor& row_div = map_.row_bursts;
  const uint64_t arrive = (uint64_t(now) << kTickShift) + t_.ctrl;
  uint64_t done = arrive;
  const uint64_t first = map_.burst.div<Pow2>(addr);
  const uint64_t last = map_.burst.div<Pow2>(addr + bytes - 1);
  // A channel's chunks follow each other in its local address space, so the
  // request's bursts on one channel are one range of local bursts. It is booked
  // channel by channel, in address order inside a channel, a run of bursts
  // sharing bank and row (up to the row's end) at a time: channels share no
  // state but sums and maxima, so the order across channels changes nothing.
  // (Booked per interleave chunk, a 2 KiB line on the presets was 8 runs; now 2.)
  const uint64_t chunk_bursts = chunk_div.d, row_bursts = row_div.d, channels = channel_div.d;
  const uint64_t k0 = chunk_div.div<Pow2>(first), k1 = chunk_div.div<Pow2>(last);  // first and last chunk
  const uint64_t touched_channels = map_.multi_channel ? std::min(channels, k1 - k0 + 1) : 1;
  uint64_t most_bursts = 0;  // on one channel (the probe's transfer)
  for (uint64_t j = 0; j < touched_channels; ++j) {
    unsigned ch = 0;
    uint64_t lb = first, hi = last;  // the channel's local bursts [lb, hi]; one channel: local = global
    if (map_.multi_channel) {
      const uint64_t k = k0 + j;                                       // the channel's first chunk
      const uint64_t kl = k + channel_div.div<Pow2>(k1 - k) * channels;  // and its last
      ch = static_cast<unsigned>(channel_div.mod<Pow2>(k));
      const uint64_t b_first = j == 0 ? first : k * chunk_bursts;
      const uint64_t b_last = kl == k1 ? last : kl * chunk_bursts + chunk_bursts - 1;
      lb = channel_div.div<Pow2>(k) * chunk_bursts + chunk_div.mod<Pow2>(b_first);
      hi = channel_div.div<Pow2>(kl) * chunk_bursts + chunk_div.mod<Pow2>(b_last);
    }
    most_bursts = std::max(most_bursts, hi - lb + 1);
    while (lb <= hi) {
      const uint64_t n = std::min(hi - lb + 1, row_bursts - row_div.mod<Pow2>(lb));
      unsigned bank_no;
      uint64_t row;
      map_.bankRow<Pow2>(row_div.div<Pow2>(lb), bank_no, row);
      lb += n;
      done = std::max(done, write ? postWrite(ch, bank_no, row, n, arrive) : bookRun<false>(ch, bank_no, row, n, arrive));
    }
  }
  stats_.row_hits = hits_;
  stats_.row_misses = misses_;
  const Cycle completion = DramTimings::ceilCycles(done);
  stats_.last_completion = std::max(stats_.last_completion, completion);
  if (completion >= probe_.done)
    probe_ = {completion, unloadedCycles(write), write ? 0 : transferCycles(most_bursts)};
  return completion;
}

void MemorySystem::addBusy(uint64_t from_tick, uint64_t len) {
  // Split at block boundaries (a long run spans several).
  constexpr unsigned shift = kTickShift + kBusyBlockShift;
  for (uint64_t at = from_tick, end = from_tick + len; at < end;) {
    const uint64_t block = at >> shift, block_end = (block + 1) << shift;
    const uint64_t part = std::min(end, block_end) - at;
    if (block >= busy_blocks_.size()) busy_blocks_.resize(std::max<size_t>(block + 1, busy_blocks_.size() * 2), 0);
    busy_blocks_[block] += part;
    at += part;
  }
}

double MemorySystem::busShare(Cycle from, Cycle to) const {
  if (to <= from) return 0.0;
  // Whole blocks overlapping the span, weighted by the overlap.
  const uint64_t block_cycles = uint64_t(1) << kBusyBlockShift;
  double busy = 0.0;
  for (Cycle b = from >> kBusyBlockShift; b <= (to - 1) >> kBusyBlockShift; ++b) {
    const Cycle lo = std::max<Cycle>(from, b << kBusyBlockShift), hi = std::min<Cycle>(to, (b + 1) << kBusyBlockShift);
    const double ticks = b < busy_blocks_.size() ? double(busy_blocks_[b]) : 0.0;
    busy += ticks / double(uint64_t(1) << kTickShift) * double(hi - lo) / double(block_cycles);
  }
  return std::min(1.0, busy / (double(to - from) * double(channels_.size())));
}

Cycle MemorySystem::transferCycles(uint64_t bursts) const {
  return bursts > 1 ? DramTimings::ceilCycles((bursts - 1) * t_.burst) : 0;
}

Cycle MemorySystem::unloadedCycles(bool write) const {
  // Ticks, rounded up once (as a request's completion is).
  if (write) return DramTimings::ceilCycles(t_.ctrl);
  return DramTimings::ceilCycles(t_.ctrl + t_.trcd + t_.cl + t_.burst);
}

uint64_t MemorySystem::postWrite(unsigned ch, unsigned bank_no, uint64_t row, uint64_t n, uint64_t arrive) {
  DramWriteQueue& q = channels_[ch].writes;
  // A run that does not fit beside the waiting writes drains them (the
  // controller switches to writes), then waits for room: entries free as
  // drained data reaches the bus.
  if (q.wouldOverflow(n)) drainBatch(ch, arrive, true);
  const uint64_t accepted = q.roomAt(arrive, n);
  q.add({bank_no, row, n, accepted});
  if (q.atHighWatermark()) drainBatch(ch, accepted, false);
  return accepted;
}

void MemorySystem::drainBatch(unsigned ch, uint64_t at, bool all) {
  DramWriteQueue& q = channels_[ch].writes;
  // takeBatch() returns the queue's own vector: bookRun does not touch the queue.
  for (const DramWriteQueue::Run& r : q.takeBatch(all))
    q.drained(bookRun<true>(ch, r.bank, r.row, r.bursts, std::max(at, r.accepted)), r.bursts);
}

Cycle MemorySystem::drainWrites(Cycle now) {
  const uint64_t at = uint64_t(now) << kTickShift;
  uint64_t done = at;
  for (unsigned ch = 0; ch < channels_.size(); ++ch) {
    if (!channels_[ch].writes.empty()) drainBatch(ch, at, true);
    done = std::max(done, channels_[ch].last_write_end);
  }
  stats_.row_hits = hits_;
  stats_.row_misses = misses_;
  const Cycle completion = DramTimings::ceilCycles(done);
  stats_.last_completion = std::max(stats_.last_completion, completion);
  return completion;
}

template <bool Write>
uint64_t MemorySystem::bookRun(unsigned ch, unsigned bank_no, uint64_t row, uint64_t n, uint64_t earliest) {
  if (n > t_.max_run_bursts) {
    // Too long for the time between two refreshes (a very slow channel):
    // booked in parts; a later part hits the row the earlier one opened
    // unless a refresh closed it (closed page: each part activates it).
    uint64_t end = 0;
    for (uint64_t left = n; left > 0;) {
      const uint64_t k = std::min(left, t_.max_run_bursts);
      end = bookRun<Write>(ch, bank_no, row, k, earliest);
      left -= k;
    }
    return end;
  }
  Channel& c = channels_[ch];
  Bank& bank = banks_[size_t(ch) * cfg_.banks + bank_no];
  const uint64_t arrive = earliest;
  const uint64_t cl = t_.cl, burst = t_.burst, trcd = t_.trcd, trp = t_.trp, tras = t_.tras;
  const uint64_t refresh_period = t_.refresh_period;
  const bool open_row = cfg_.open_row;
  // Turnarounds: a read command waits tWTR after the last write data; write
  // data leaves tRTW of idle bus after the last read data.
  const uint64_t bus_floor = Write ? std::max(c.bus_free, c.last_read_end + t_.trtw) : c.bus_free;
  const uint64_t column_floor = Write ? 0 : c.last_write_end + t_.twtr;
  // The run's first burst hits or opens the row (closed page: activates it,
  // the bank being precharged); the others hit it and their column command
  // issues at the same tick, so each waits only for the bus, i.e. the
  // previous burst's end. A closed page auto-precharges after the run's last
  // burst. With refresh the run is placed whole between two refreshes: when it
  // would meet one, it is placed again after it, on the bank the refresh left
  // closed (b, a copy, starts from the committed state on every try; without
  // refresh b is the bank itself: one try).
  Bank copy;
  Bank& b = refresh_period ? copy : bank;
  uint64_t column;   // tick the run's first column command (read or write) issues
  uint64_t act = 0;  // closed page: the run's activate
  uint64_t xfer, run_hits;
  const uint64_t len = n * burst;
  bool refreshed = false;  // a refresh closed the bank's row
  size_t gap = 0;
  bool in_gap = false;  // the run's data goes into idle bus time before the latest booking
  for (unsigned tries = 0;; ++tries) {
    uint64_t first_cmd;  // the run's first command on the bank (precharge, activate or column)
    if (refresh_period) {
      if (tries > 64) throw std::logic_error("MemorySystem: a run does not fit between two refreshes");
      b = bank;
      // A refresh since the row was opened closed it.
      if (open_row && b.open_row != kNoRow) {
        const uint64_t w = t_.lastRefreshStart(ch, std::max(earliest, b.row_ready));
        if (w > b.act) {
          refreshed = true;
          earliest = std::max(earliest, w + t_.refresh_rfc);
        }
      }
      if (refreshed) b.open_row = kNoRow;
    }
    if (open_row) {
      if (b.open_row == row) {
        run_hits = n;
        column = std::max(earliest, b.row_ready);
        first_cmd = column;
      } else {
        run_hits = n - 1;
        // Precharge may start once the open row is active, its transfers ended
        // and it has been open tRAS.
        uint64_t start = std::max({earliest, b.row_ready, b.last_end});
        first_cmd = start;
        if (b.open_row != kNoRow) {
          first_cmd = std::max(start, b.act + tras);
          start = first_cmd + trp;
        }
        b.open_row = row;
        b.act = start;
        b.row_ready = start + trcd;
        column = b.row_ready;
      }
    } else {
      run_hits = n - 1;
      act = std::max(earliest, b.act_ready);
      column = act + trcd;
      first_cmd = act;
    }
    xfer = std::max(std::max(column, column_floor) + cl, bus_floor);  // the first burst's bus start
    // A read the bus would delay may take a gap the bus left idle before its
    // latest booking (FR-FCFS within the window, or any scheduler for a read
    // that arrived before the one that left the gap), never moving a booking.
    // Its bank timing is the same; with refresh only when no window lies
    // between its first command and its data's end.
    if (!Write && !refreshed && column + cl < xfer && c.gaps.latestEnd() >= column + cl + len) {
      const DramBusGaps::Asker asker{arrive, c.booked, window_};
      const uint64_t start = c.gaps.find(asker, column + cl, len, t_.twtr + cl, t_.trtw, gap);
      if (start != DramBusGaps::kNone && start < xfer &&
          (!refresh_period || !t_.refreshOverlapEnd(ch, first_cmd, start + len))) {
        xfer = start;
        in_gap = true;
        break;
      }
    }
    if (!refresh_period) break;
    const uint64_t after = t_.refreshOverlapEnd(ch, first_cmd, xfer + len);
    if (!after) break;
    earliest = after;
    refreshed = true;
  }
  if (refresh_period) bank = b;
  hits_ += run_hits;
  misses_ += n - run_hits;
  const uint64_t end = xfer + len;
  if (in_gap) {
    c.gaps.take(gap, xfer, len, burst);
  } else {
    // Idle bus before this run (its bank or a turnaround held it back, or it
    // came late) is a gap a later read may take.
    if (xfer >= c.bus_free + burst)
      c.gaps.add({c.bus_free, xfer, c.booked, arrive, c.last_was_write, Write});
    c.bus_free = end;
    c.last_was_write = Write;
  }
  c.booked += n;
  uint64_t& last_end = Write ? c.last_write_end : c.last_read_end;
  last_end = std::max(last_end, end);
  if (sample_interval_) {
    // Usually the whole run starts in the bucket of the previous one.
    const Cycle c_first = xfer >> kTickShift, c_last = (end - burst) >> kTickShift;
    if (c_first >= bucket_begin_ && c_last - bucket_begin_ < sample_interval_)
      stats_.bus_bytes_per_interval[last_bucket_] += n * map_.burst.d;
    else
      sampleBursts(xfer, n, burst);
  }
  bank.last_end = std::max(bank.last_end, end);
  if (!open_row) {
    // Auto-precharge after the run's data, once the row was open tRAS.
    bank.act = act;
    bank.act_ready = std::max(bank.last_end, act + tras) + trp;
  }
  c.busy += len;
  addBusy(xfer, len);
  stats_.channel_busy[ch] = DramTimings::ceilCycles(c.busy);
  return end;
}

}  // namespace oit::rop
