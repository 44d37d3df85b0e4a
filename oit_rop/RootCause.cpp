#include "oit_rop/RootCause.hpp"

#include <algorithm>
#include <numeric>

namespace oit::rop {

namespace {
__extension__ typedef unsigned __int128 U128;  // n x delay can pass 2^64

// floor(a x b / c) (c > 0), without a 128-bit division where a x b fits 64 bits.
inline uint64_t mulDiv(uint64_t a, uint64_t b, uint64_t c) {
  uint64_t ab;
  if (!__builtin_mul_overflow(a, b, &ab)) return ab / c;
  return uint64_t(U128(a) * b / c);
}

// The part [l, e) of a wait's DRAM queueing and transfer, by cause (the
// WaitSplit's inner ends clamped to it).
struct QueueSplit {
  uint64_t refresh = 0, bank = 0, turnaround = 0, bandwidth = 0;
};
// A WaitSplit built without the queue's inner ends (below latency_end): all
// of its queueing is the bus's.
WaitSplit withQueueEnds(WaitSplit w) {
  if (w.turn_end < w.latency_end) w.refresh_end = w.bank_end = w.turn_end = w.latency_end;
  return w;
}
QueueSplit queueSplit(const WaitSplit& ws, Cycle l, Cycle e) {
  // [l, e) covers part of the queueing (in its proportions, as
  // RootCauseAccount::account) and the transfer after it.
  const WaitSplit w = withQueueEnds(ws);
  const Cycle q0 = std::clamp(w.latency_end, l, e), q1 = std::clamp(w.queue_end, q0, e);
  QueueSplit s;
  if (q1 > q0 && w.turn_end > w.latency_end) {  // (all of it the bus's: no division)
    const uint64_t len = q1 - q0, all = w.queue_end - w.latency_end;
    s.refresh = mulDiv(len, w.refresh_end - w.latency_end, all);
    s.bank = mulDiv(len, w.bank_end - w.refresh_end, all);
    s.turnaround = mulDiv(len, w.turn_end - w.bank_end, all);
  }
  s.bandwidth = (e - l) - s.refresh - s.bank - s.turnaround;
  return s;
}
}  // namespace

const char* rootCauseKey(RootCause c) {
  switch (c) {
    case RootCause::Input: return "input";
    case RootCause::InputStarvation: return "input_starvation";
    case RootCause::ScoreboardFull: return "scoreboard_full";
    case RootCause::LockWait: return "lock_wait";
    case RootCause::Alu: return "alu";
    case RootCause::RopCacheMiss: return "rop_cache_miss";
    case RootCause::L2: return "l2";
    case RootCause::DramLatency: return "dram_latency";
    case RootCause::DramBandwidth: return "dram_bandwidth";
    case RootCause::PipelineLatency: return "pipeline_latency";
    case RootCause::Atomics: return "atomic_wait";
    case RootCause::ListWalk: return "list_walk";
    case RootCause::Sort: return "sort";
    case RootCause::DramBankConflict: return "dram_bank_conflict";
    case RootCause::DramTurnaround: return "dram_turnaround";
    case RootCause::DramRefresh: return "dram_refresh";
  }
  return "?";
}

WaitSplit splitWait(Cycle now, Cycle ready, const DramProbe& d, RootCause rest) {
  WaitSplit w{now, now, now, rest};
  if (d.done > now && ready > now) {
    // The DRAM part ends at its completion (or at `ready`, when the cache's
    // answer came first). Of it, the last `transfer` cycles move the rest of
    // its data and the `unloaded` before them reach its first data, as on an
    // idle controller; what is left before them is queueing.
    const Cycle dram = std::min(d.done, ready) - now;
    const Cycle xfer = std::min(dram, d.transfer);
    const Cycle lat = std::min(dram - xfer, d.unloaded);
    const Cycle queue = dram - xfer - lat;
    w.latency_end = now + lat;
    w.queue_end = w.latency_end + queue;
    w.dram_end = w.queue_end + xfer;
    // The queueing in the controller's proportions (whole shares; the cycles
    // left over to the bus, all of them when the controller saw nothing).
    const uint64_t sum = d.queue.sum();
    auto part = [&](uint64_t x) { return sum ? Cycle(mulDiv(queue, x, sum)) : 0; };
    w.refresh_end = w.latency_end + part(d.queue.refresh);
    w.bank_end = w.refresh_end + part(d.queue.bank);
    w.turn_end = w.bank_end + part(d.queue.turnaround);
  }
  return w;
}

const MissWait* MissWaits::freeingMiss(Cycle frees) const {
  const MissWait* best = nullptr;
  for (size_t i = 0; i < size_; ++i)
    if (ring_[i].ready >= frees && (!best || ring_[i].ready < best->ready)) best = &ring_[i];
  return best;
}

void splitLatency(uint64_t n, Cycle from, Cycle to, const BusShareFn& bus, uint64_t& latency, uint64_t& bandwidth) {
  bandwidth = n && bus ? std::min<uint64_t>(n, uint64_t(double(n) * bus(from, to) + 0.5)) : 0;
  latency = n - bandwidth;
}

void RootCauseAccount::account(Cycle now) {
  if (now <= since_) return;
  if (!wait_) {
    cycles_[size_t(cause_)] += now - since_;
  } else {
    Cycle at = since_;
    auto charge = [&](Cycle until, RootCause c) {
      if (until > at) {
        const Cycle to = std::min(until, now);
        cycles_[size_t(c)] += to - at;
        at = to;
      }
    };
    if (w_.latency_end > at) {  // the unloaded access: latency where the buses were idle
      const Cycle to = std::min(w_.latency_end, now);
      uint64_t lat, bw;
      splitLatency(to - at, at, to, bus_, lat, bw);
      cycles_[size_t(RootCause::DramLatency)] += lat;
      cycles_[size_t(RootCause::DramBandwidth)] += bw;
      at = to;
    }
    // The queueing: any part of it in the proportions of the whole (which
    // cycles of a wait's queueing a stage waits for says nothing about which
    // cause they were; a position order would charge tails to the last one).
    const WaitSplit w = withQueueEnds(w_);
    if (w.queue_end > at && w.queue_end > w.latency_end) {
      const Cycle to = std::min(w.queue_end, now);
      const QueueSplit q = queueSplit(w_, at, to);  // [at, to) is queueing only (at >= latency_end or empty)
      cycles_[size_t(RootCause::DramRefresh)] += q.refresh;
      cycles_[size_t(RootCause::DramBankConflict)] += q.bank;
      cycles_[size_t(RootCause::DramTurnaround)] += q.turnaround;
      cycles_[size_t(RootCause::DramBandwidth)] += q.bandwidth;
      at = to;
    }
    charge(w_.dram_end, RootCause::DramBandwidth);
    cycles_[size_t(w_.rest)] += now - at;
  }
  since_ = now;
}

uint64_t RootCauseAccount::total() const { return std::accumulate(cycles_.begin(), cycles_.end(), uint64_t(0)); }

void DelayShares::addWait(Cycle from, Cycle to, const WaitSplit& w) {
  if (to <= from) return;
  const Cycle l = std::clamp(w.latency_end, from, to), e = std::clamp(w.dram_end, l, to);
  addUnloaded(from, l, l - from);
  if (e == l) {  // no DRAM queueing or transfer in [from, to) (an l2 hit's wait): no split
    delay_[size_t(w.rest)] += to - e;
    return;
  }
  const QueueSplit q = queueSplit(w, l, e);
  delay_[size_t(RootCause::DramRefresh)] += q.refresh;
  delay_[size_t(RootCause::DramBankConflict)] += q.bank;
  delay_[size_t(RootCause::DramTurnaround)] += q.turnaround;
  delay_[size_t(RootCause::DramBandwidth)] += q.bandwidth;
  delay_[size_t(w.rest)] += to - e;
}

void DelayShares::addLike(uint64_t n, Cycle from, Cycle to, const WaitSplit& w) {
  if (n == 0) return;
  if (to <= from) {
    delay_[size_t(w.rest)] += n;
    return;
  }
  const Cycle l = std::clamp(w.latency_end, from, to), e = std::clamp(w.dram_end, l, to);
  const uint64_t span = to - from, lat_all = n * (l - from) / span;
  addUnloaded(from, l, lat_all);
  if (e == l) {  // no DRAM queueing or transfer in [from, to) (an l2 hit's wait): no split
    delay_[size_t(w.rest)] += n - lat_all;
    return;
  }
  const QueueSplit q = queueSplit(w, l, e);
  const uint64_t refresh = n * q.refresh / span, bank = n * q.bank / span, turn = n * q.turnaround / span;
  const uint64_t bw = n * q.bandwidth / span;
  delay_[size_t(RootCause::DramRefresh)] += refresh;
  delay_[size_t(RootCause::DramBankConflict)] += bank;
  delay_[size_t(RootCause::DramTurnaround)] += turn;
  delay_[size_t(RootCause::DramBandwidth)] += bw;
  delay_[size_t(w.rest)] += n - lat_all - bw - refresh - bank - turn;
}

void DelayShares::addUnloaded(Cycle from, Cycle to, uint64_t n) {
  if (n == 0) return;
  unloaded_ += n;
  spans_.push_back({from, to, n});
  open_last_to_ = std::max(open_last_to_, to);
}

void DelayShares::chargeTo(RootCauseAccount& acc, uint64_t n, RootCause fallback) {
  if (n == 0) return;
  constexpr unsigned kUnloaded = kRootCauseCount;
  uint64_t sum = unloaded_;
  unsigned causes = unloaded_ != 0, only = kUnloaded;  // how many have a delay; the one, when one
  for (unsigned i = 0; i < kRootCauseCount; ++i)
    if (delay_[i]) {
      sum += delay_[i];
      ++causes;
      only = i;
    }
  if (sum == 0) {
    acc.add(fallback, n);
    return;
  }
  // Whole shares first, the cycles left to the largest remainders (ties: the
  // first cause; the unloaded accesses, kept apart, last), so the shares add
  // up to n exactly. One cause alone takes all n (its share n x d / d, no
  // remainder): no division.
  std::array<uint64_t, kRootCauseCount + 1> rem{}, got{};
  uint64_t given = 0;
  if (causes == 1) {
    got[only] = n;
    given = n;
  }
  for (unsigned i = 0; i <= kRootCauseCount && causes > 1; ++i) {
    const uint64_t d = i == kUnloaded ? unloaded_ : delay_[i];
    if (d == 0) continue;  // no share, no remainder
    uint64_t whole, x64;
    if (!__builtin_mul_overflow(n, d, &x64)) {  // the common case: no 128-bit division
      whole = x64 / sum;
      rem[i] = x64 % sum;
    } else {
      const U128 x = U128(n) * d;
      whole = uint64_t(x / sum);
      rem[i] = uint64_t(x % sum);
    }
    got[i] = whole;
    given += whole;
  }
  for (; given < n; ++given) {
    const size_t i = size_t(std::max_element(rem.begin(), rem.end()) - rem.begin());
    ++got[i];
    rem[i] = 0;
  }
  for (unsigned i = 0; i < kRootCauseCount; ++i) acc.add(RootCause(i), got[i]);
  const uint64_t end = spans_base_ + spans_.size();
  if (got[kUnloaded]) {
    charges_.push_back({got[kUnloaded], open_begin_, end, open_last_to_});
  } else if (charges_.empty()) {  // no charge holds these spans
    spans_.clear();
    spans_base_ = end;
  }
  open_begin_ = end;
  open_last_to_ = 0;
  delay_.fill(0);
  unloaded_ = 0;
}

void DelayShares::settle(RootCauseAccount& acc, Cycle before) {
  while (!charges_.empty() && charges_.front().last_to <= before) {
    const Charge c = charges_.front();
    charges_.pop_front();
    // The charge's cycles in the proportions of its spans' latency and bandwidth.
    double all = 0.0, busy = 0.0;
    for (uint64_t i = c.begin; i < c.end; ++i) {
      const Span& s = spans_[i - spans_base_];
      all += double(s.n);
      if (bus_) busy += double(s.n) * bus_(s.from, s.to);
    }
    const uint64_t bw = all > 0 ? std::min<uint64_t>(c.cycles, uint64_t(double(c.cycles) * busy / all + 0.5)) : 0;
    acc.add(RootCause::DramBandwidth, bw);
    acc.add(RootCause::DramLatency, c.cycles - bw);
    // Spans before the next charge's (or the open ones) are done with.
    const uint64_t keep = charges_.empty() ? open_begin_ : charges_.front().begin;
    while (spans_base_ < keep) {
      spans_.pop_front();
      ++spans_base_;
    }
  }
}

}  // namespace oit::rop
