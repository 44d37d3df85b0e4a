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
  channels_.assign(cfg.channels, Channel(cfg, t_));
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
double MemorySystem::trrdCycles() const { return DramTimings::cycles(t_.trrd); }
double MemorySystem::tfawCycles() const { return DramTimings::cycles(t_.tfaw); }
double MemorySystem::burstCycles() const { return DramTimings::cycles(t_.burst); }
double MemorySystem::twtrCycles() const { return DramTimings::cycles(t_.twtr); }
double MemorySystem::trtwCycles() const { return DramTimings::cycles(t_.trtw); }
double MemorySystem::ccdSCycles() const { return DramTimings::cycles(t_.ccd_s); }
double MemorySystem::ccdLCycles() const { return DramTimings::cycles(t_.ccd_l); }
double MemorySystem::trrdLCycles() const { return DramTimings::cycles(t_.trrd_l); }
double MemorySystem::twtrLCycles() const { return DramTimings::cycles(t_.twtr_l); }

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
  DramQueueParts queue;      // the probe's: of the run that ends last
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
      const uint64_t end = write ? postWrite(ch, bank_no, row, n, arrive) : bookRun<false>(ch, bank_no, row, n, arrive);
      if (end >= done) {  // the run the request completes with says what its queueing was
        done = end;
        queue = write ? channels_[ch].drain_queue : run_queue_;
      }
    }
  }
  stats_.row_hits = hits_;
  stats_.row_misses = misses_;
  const Cycle completion = DramTimings::ceilCycles(done);
  stats_.last_completion = std::max(stats_.last_completion, completion);
  if (completion >= probe_.done)
    probe_ = {completion, unloadedCycles(write), write ? 0 : transferCycles(most_bursts), queue};
  return completion;
}

namespace {
// Adds [from, from + len) ticks to per-block totals (blocks of 2^shift ticks).
void addToBlocks(std::vector<uint64_t>& blocks, uint64_t from, uint64_t len, unsigned shift) {
  for (uint64_t at = from, end = from + len; at < end;) {
    const uint64_t block = at >> shift, block_end = (block + 1) << shift;
    const uint64_t part = std::min(end, block_end) - at;
    if (block >= blocks.size()) blocks.resize(std::max<size_t>(block + 1, blocks.size() * 2), 0);
    blocks[block] += part;
    at += part;
  }
}
// Per-block totals (blocks of 2^shift units) summed over [from, to), to >
// from, each block's total taken as spread evenly over it: a block the span
// overlaps in part counts by the overlap.
double spreadSum(const std::vector<uint64_t>& blocks, uint64_t from, uint64_t to, unsigned shift) {
  double sum = 0.0;
  const double size = double(uint64_t(1) << shift);
  for (uint64_t b = from >> shift; b <= (to - 1) >> shift && b < blocks.size(); ++b) {
    const uint64_t lo = std::max(from, b << shift), hi = std::min(to, (b + 1) << shift);
    sum += double(blocks[b]) * double(hi - lo) / size;
  }
  return sum;
}
// The ticks of per-block totals over [from, to) (ticks; to > from).
uint64_t blockTicks(const std::vector<uint64_t>& blocks, uint64_t from, uint64_t to, unsigned shift) {
  return uint64_t(spreadSum(blocks, from, to, shift) + 0.5);
}
}  // namespace

DramQueueParts MemorySystem::queueParts(Channel& c, const RunPlace& at, uint64_t xfer, bool in_gap) {
  // The run's data start beyond an idle controller's (ideal: from `at.earliest`
  // + tRCD + CL) by what held it. Before the bus was free for it (bus_free; a
  // read in a gap: the gap) the channel's bus was busy moving other data
  // (bandwidth) or idle for what the runs booked there waited for (the
  // channel's record of its idle time by cause, per 256-cycle block); after
  // that its own bank (its column command later than tRCD after it could
  // start) and then its turnaround (tWTR / tRTW). A refresh's part is what it
  // moved the run by (at.refresh_wait): counted first, the wait for a bank
  // that was busy anyway during the refresh was charged to the refresh too
  // (the Titan X point: 15.8 % of the frame, against 8.2 % saved with
  // refresh off).
  constexpr unsigned shift = kTickShift + kBusyBlockShift;
  // The activate limits' hold (the activate later than its bank allowed it,
  // tRRD / tFAW) is its bank's side, counted first like a refresh's move:
  // the channel's other activates held it, not the data the bus moved
  // meanwhile. The rest is split from where the run would have been ready
  // without the hold. (Split by the bus's record before bus_free instead, the
  // activate-bound frame of test_bounds.cpp charged the 12 % of the time the
  // bus moved data to dram_bandwidth.)
  const uint64_t cl = t_.cl, placed = at.xfer;
  const uint64_t unheld = at.earliest + t_.trcd + cl;  // an idle controller's data start
  const uint64_t ideal = std::min(placed, unheld + at.hold);
  DramQueueParts q;
  q.refresh = at.refresh_wait;
  q.bank = ideal - std::min(ideal, unheld);
  // A run its own column command placed after idle bus (not a turnaround
  // floor, not the bus), its bank not waiting for the bank's last data
  // either (its row cycle, tRAS + tRP, and the activate limits held it)
  // waited for its bank alone: it would have started no sooner on a faster
  // bus, however busy the bus was with other data meanwhile (the bank's row
  // cycle chain in the activate-bound frame: 56 of every 86 cycles).
  const bool bank_placed = !in_gap && !at.after_data && placed > c.bus_free && at.column + cl >= placed;
  const uint64_t busy_until = bank_placed ? ideal : std::min(placed, in_gap ? placed : c.bus_free);
  if (busy_until > ideal) {
    uint64_t left = busy_until - ideal;
    auto take = [&](const std::vector<uint64_t>& blocks) {
      const uint64_t v = std::min(left, blockTicks(blocks, ideal, busy_until, shift));
      left -= v;
      return v;
    };
    q.bank += take(c.idle_blocks[0]);
    q.turnaround += take(c.idle_blocks[1]);
    q.refresh += take(c.idle_blocks[2]);
    q.bus = left;
  }
  const uint64_t from = std::max(ideal, busy_until);
  uint64_t bank_end = from;
  if (placed > from) {
    bank_end = std::min(placed, std::max(from, at.column + cl));
    q.bank += bank_end - from;
    q.turnaround += placed - bank_end;  // tWTR before the column command, tRTW before write data
  }
  if (!in_gap && xfer > c.bus_free) {
    // The bus idles over [bus_free, xfer): recorded by what this run waited
    // for there (the part nobody asked for is not recorded).
    auto record = [&](unsigned k, uint64_t lo, uint64_t hi) {
      lo = std::max(lo, c.bus_free);
      if (hi > lo) addToBlocks(c.idle_blocks[k], lo, hi - lo, shift);
    };
    record(0, std::min(from, unheld), bank_end);  // the hold's idle bus too
    record(1, bank_end, placed);
    if (at.refreshed) record(2, at.refresh_from, at.refresh_to ? at.refresh_to : std::min(from, ideal));
  }
  return q;
}

void MemorySystem::addBusy(uint64_t from_tick, uint64_t len) {
  addToBlocks(busy_blocks_, from_tick, len, kTickShift + kBusyBlockShift);
}

double MemorySystem::busShare(Cycle from, Cycle to) const {
  if (to <= from) return 0.0;
  // Each block holds the bus ticks booked in its 2^kBusyBlockShift cycles:
  // spread over the span in cycles, the sum is in ticks; / 2^kTickShift, in
  // cycles (a power of two: the same double as scaling each block's part).
  const double busy = spreadSum(busy_blocks_, from, to, kBusyBlockShift) / double(uint64_t(1) << kTickShift);
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
  // A write that waits for room waits for this batch: its data on the bus
  // (bandwidth) and the idle bus its runs met (turnaround, bank, refresh).
  DramQueueParts batch;
  for (const DramWriteQueue::Run& r : q.takeBatch(all)) {
    q.drained(bookRun<true>(ch, r.bank, r.row, r.bursts, std::max(at, r.accepted)), r.bursts);
    batch.bus += r.bursts * t_.burst;
    batch.bank += run_queue_.bank;
    batch.turnaround += run_queue_.turnaround;
    batch.refresh += run_queue_.refresh;
  }
  channels_[ch].drain_queue = batch;
}

Cycle MemorySystem::drainWrites(Cycle now) {
  const uint64_t at = uint64_t(now) << kTickShift;
  uint64_t done = at;
  DramQueueParts queue;  // what the channel that finishes last waited for
  for (unsigned ch = 0; ch < channels_.size(); ++ch) {
    const bool drained = !channels_[ch].writes.empty();
    if (drained) drainBatch(ch, at, true);
    if (channels_[ch].last_write_end >= done) {
      done = channels_[ch].last_write_end;
      queue = drained ? channels_[ch].drain_queue : DramQueueParts{};
    }
  }
  stats_.row_hits = hits_;
  stats_.row_misses = misses_;
  const Cycle completion = DramTimings::ceilCycles(done);
  stats_.last_completion = std::max(stats_.last_completion, completion);
  // The probe: a wait for the drain is a write's (its data on the bus is
  // bandwidth, its runs' bank, turnaround and refresh waits theirs).
  if (done > at && completion >= probe_.done) probe_ = {completion, unloadedCycles(true), 0, queue};
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
  const uint64_t arrive = earliest;  // a refresh may move `earliest` on
  const uint64_t cl = t_.cl, burst = t_.burst, trcd = t_.trcd, trp = t_.trp, tras = t_.tras;
  const uint64_t refresh_period = t_.refresh_period;
  const bool open_row = cfg_.open_row;
  // Turnarounds: a read command waits tWTR after the last write data; write
  // data leaves tRTW of idle bus after the last read data.
  uint64_t bus_floor = Write ? std::max(c.bus_free, c.last_read_end + t_.trtw) : c.bus_free;
  uint64_t column_floor = Write ? 0 : c.last_write_end + t_.twtr;
  // Column spacing (MEMORY.md "Bank groups"): data starts tCCD_S apart on the
  // channel (the bus alone when tCCD_S is at most a burst), tCCD_L apart in
  // the run's bank group (its bursts too: one bank), a read tWTR_L after its
  // group's write data. Without bank groups and tCCD_S none of it applies.
  const uint64_t ccd_extra = t_.ccd_s - burst;  // tCCD_S beyond the burst
  if (ccd_extra && c.booked) bus_floor = std::max(bus_floor, c.bus_free + ccd_extra);
  const unsigned group = t_.bank_groups > 1 ? bank_no & (t_.bank_groups - 1) : 0;
  uint64_t group_floor = 0;         // the earliest data start the run's bank group allows
  uint64_t group_column_floor = 0;  // a read's column command: tWTR_L after the group's write data
  if (t_.bank_groups > 1) {
    // (Only where the group's spacing is longer than the channel's: else the
    // bus and the channel's tWTR hold it already.)
    if (t_.ccd_l > t_.ccd_s) group_floor = c.group_next[group];
    if (!Write && t_.twtr_l > t_.twtr && c.group_write_end[group])
      group_column_floor = c.group_write_end[group] + t_.twtr_l;
    column_floor = std::max(column_floor, group_column_floor);
  }
  const uint64_t step = t_.ccd_l;         // between the run's bursts (one bank, one group)
  const uint64_t span = t_.runSpan(n);    // its data, first start to last end
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
  uint64_t act = 0;  // the run's activate (closed page: always; open row: on a row miss)
  uint64_t hold = 0;  // what the channel's activate limits held it back by
  bool after_data = false;  // its first command waited for the bank's last data
  uint64_t xfer, run_hits;
  const uint64_t len = n * burst;  // the bus time its data takes
  bool refreshed = false;  // a refresh closed the bank's row
  size_t gap = 0;
  bool in_gap = false;  // the run's data goes into idle bus time before the latest booking
  RunPlace unrefreshed{};  // the first try's place, when no refresh had moved it yet
  for (unsigned tries = 0;; ++tries) {
    hold = 0;
    after_data = false;
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
        const uint64_t others = std::max(earliest, b.row_ready);
        uint64_t start = std::max(others, b.last_end);
        first_cmd = start;
        after_data = b.last_end > others && (b.open_row == kNoRow || b.last_end > b.act + tras);
        if (b.open_row != kNoRow) {
          first_cmd = std::max(start, b.act + tras);
          start = first_cmd + trp;
        }
        // The channel's activate limits (tRRD, tFAW) may hold the activate
        // back: the bank waits (its column command is later).
        act = c.activates.earliest(start, group);
        hold = act - start;
        start = act;
        b.open_row = row;
        b.act = start;
        b.row_ready = start + trcd;
        column = b.row_ready;
      }
    } else {
      run_hits = n - 1;
      const uint64_t bank_allows = std::max(earliest, b.act_ready);
      after_data = b.act_ready > earliest && b.last_end > b.act + tras;  // act_ready = last_end + tRP
      act = c.activates.earliest(bank_allows, group);
      hold = act - bank_allows;
      column = act + trcd;
      first_cmd = act;
    }
    xfer = std::max(std::max(std::max(column, column_floor) + cl, bus_floor), group_floor);  // the first burst's bus start
    // The column command as the bank and its group allow it (a tCCD_L wait is the bank's side).
    const uint64_t bank_column = group_floor > column + cl ? group_floor - cl : column;
    if (tries == 0 && !refreshed) unrefreshed = {arrive, bank_column, xfer, hold, after_data};  // where it would go without refresh
    // A read the bus would delay may take a gap the bus left idle before its
    // latest booking (FR-FCFS within the window, or any scheduler for a read
    // that arrived before the one that left the gap), never moving a booking.
    // Its bank timing is the same; with refresh only when no window lies
    // between its first command and its data's end.
    // With bank groups no earlier than the group allows (after every burst
    // of the group booked so far: a gap before one of them is not looked
    // at), with tCCD_S beyond the burst that much idle bus on either side.
    // (The channel's tWTR: the gap's own turnaround margins.)
    const uint64_t gap_from = std::max(std::max(column, group_column_floor) + cl, group_floor);
    if (!Write && !refreshed && gap_from < xfer && c.gaps.latestEnd() >= gap_from + span) {
      const DramBusGaps::Asker asker{arrive, c.booked, window_};
      const uint64_t found = c.gaps.find(asker, gap_from - std::min(gap_from, ccd_extra), span + 2 * ccd_extra,
                                         t_.twtr + cl, t_.trtw, gap);
      const uint64_t start = found == DramBusGaps::kNone ? found : found + ccd_extra;
      if (start != DramBusGaps::kNone && start < xfer &&
          (!refresh_period || !t_.refreshOverlapEnd(ch, first_cmd, start + span))) {
        xfer = start;
        in_gap = true;
        break;
      }
    }
    if (!refresh_period) break;
    const uint64_t after = t_.refreshOverlapEnd(ch, first_cmd, xfer + span);
    if (!after) break;
    earliest = after;
    refreshed = true;
  }
  if (refresh_period) bank = b;
  // Its queueing by cause: a refresh that moved the run is charged what it
  // moved it by, the rest as where the run would have gone without it; a
  // run that met a refresh at once (arriving in one, or to a row a refresh
  // closed) from after the refresh, the wait before it the refresh's.
  const uint64_t bank_column = group_floor > column + cl ? group_floor - cl : column;
  RunPlace place{earliest, bank_column, xfer, hold, after_data};
  if (refreshed && unrefreshed.xfer && xfer > unrefreshed.xfer) {
    place = unrefreshed;
    place.refresh_wait = xfer - unrefreshed.xfer;
    place.refresh_from = unrefreshed.xfer;
    place.refresh_to = xfer;
  } else if (refreshed) {
    place.refresh_wait = earliest - arrive;
    place.refresh_from = arrive;
  }
  place.refreshed = refreshed;
  run_queue_ = queueParts(c, place, xfer, in_gap);
  run_queue_.bank += span - len;  // its bursts tCCD_L apart in its bank group: the bank's side
  hits_ += run_hits;
  misses_ += n - run_hits;
  if (run_hits < n) c.activates.record(act, group);  // the run opened its row
  const uint64_t end = xfer + span;
  if (t_.bank_groups > 1) {
    c.group_next[group] = std::max(c.group_next[group], end - burst + t_.ccd_l);
    if (Write) c.group_write_end[group] = std::max(c.group_write_end[group], end);
  }
  if (in_gap) {
    c.gaps.take(gap, xfer, span, burst);
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
      sampleBursts(xfer, n, step);
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
