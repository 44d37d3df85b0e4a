#include "oit_rop/RootCause.hpp"

#include <algorithm>
#include <numeric>

namespace oit::rop {

namespace {
__extension__ typedef unsigned __int128 U128;  // n x delay can pass 2^64
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
    w.latency_end = now + lat;
    w.queue_end = w.latency_end + (dram - xfer - lat);
    w.dram_end = w.queue_end + xfer;
  }
  return w;
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
    charge(w_.dram_end, RootCause::DramBandwidth);
    cycles_[size_t(w_.rest)] += now - at;
  }
  since_ = now;
}

uint64_t RootCauseAccount::total() const { return std::accumulate(cycles_.begin(), cycles_.end(), uint64_t(0)); }

void DelayShares::addWait(Cycle from, Cycle to, const WaitSplit& w) {
  if (to <= from) return;
  const Cycle l = std::clamp(w.latency_end, from, to), e = std::clamp(w.dram_end, l, to);
  uint64_t lat, bw;
  splitLatency(l - from, from, l, bus_, lat, bw);
  delay_[size_t(RootCause::DramLatency)] += lat;
  delay_[size_t(RootCause::DramBandwidth)] += bw + (e - l);
  delay_[size_t(w.rest)] += to - e;
}

void DelayShares::addLike(uint64_t n, Cycle from, Cycle to, const WaitSplit& w) {
  if (n == 0) return;
  if (to <= from) {
    delay_[size_t(w.rest)] += n;
    return;
  }
  const Cycle l = std::clamp(w.latency_end, from, to), e = std::clamp(w.dram_end, l, to);
  const double busy = bus_ ? bus_(from, l) : 0.0;
  const uint64_t span = to - from, lat_all = n * (l - from) / span;
  const uint64_t lat = uint64_t(double(lat_all) * (1.0 - busy) + 0.5), bw = (lat_all - lat) + n * (e - l) / span;
  delay_[size_t(RootCause::DramBandwidth)] += bw;
  delay_[size_t(RootCause::DramLatency)] += lat;
  delay_[size_t(w.rest)] += n - bw - lat;
}

void DelayShares::chargeTo(RootCauseAccount& acc, uint64_t n, RootCause fallback) {
  if (n == 0) return;
  const uint64_t sum = std::accumulate(delay_.begin(), delay_.end(), uint64_t(0));
  if (sum == 0) {
    acc.add(fallback, n);
    return;
  }
  // Whole shares first, the cycles left to the largest remainders (ties: the
  // first cause), so the shares add up to n exactly.
  std::array<uint64_t, kRootCauseCount> rem{};
  uint64_t given = 0;
  for (unsigned i = 0; i < kRootCauseCount; ++i) {
    if (delay_[i] == 0) continue;  // no share, no remainder
    uint64_t whole, x64;
    if (!__builtin_mul_overflow(n, delay_[i], &x64)) {  // the common case: no 128-bit division
      whole = x64 / sum;
      rem[i] = x64 % sum;
    } else {
      const U128 x = U128(n) * delay_[i];
      whole = uint64_t(x / sum);
      rem[i] = uint64_t(x % sum);
    }
    acc.add(RootCause(i), whole);
    given += whole;
  }
  for (; given < n; ++given) {
    const size_t i = size_t(std::max_element(rem.begin(), rem.end()) - rem.begin());
    acc.add(RootCause(i), 1);
    rem[i] = 0;
  }
  delay_.fill(0);
}

}  // namespace oit::rop
