// BlendAlu: the blending-array read-modify-write unit. Throughput is
// alu.blends_per_clock scaled by the row format (rgba8t8z32: 1, fp16:
// fp16_rate, fp32: fp32_rate); latency is base_latency + row_latency x rows
// touched, where rows comes from the functional InsertOutcome (rowsFor()).
// Latencies take few distinct values, so completions sit in one in-order FIFO
// per row count (no priority queue).
#pragma once

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "model/OitAlgorithm.hpp"
#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

struct AluStats {
  uint64_t blends = 0, rows = 0, dropped = 0;
};

class BlendAlu {
 public:
  // rows_max: the largest rows value issue() will get.
  BlendAlu(const AluConfig& cfg, double format_rate, unsigned rows_max);

  // Rows read-modify-written by one insert with `outcome`: Stored writes one
  // row, Merged rewrites the whole array (merge / eviction), Discarded only
  // compares. Without lazy merging (skip.lazy_merge = false) every kept
  // fragment pays the merge. `array_rows` = the layout's rows (>= 1 used).
  static unsigned rowsFor(model::InsertOutcome outcome, unsigned array_rows, bool lazy_merge) {
    const unsigned merge = std::max(1u, array_rows);
    switch (outcome) {
      case model::InsertOutcome::Stored: return lazy_merge ? 1u : merge;
      case model::InsertOutcome::Merged: return merge;
      case model::InsertOutcome::Discarded: return 0u;
    }
    return 0u;
  }
  static double formatRate(const AluConfig& cfg, const model::StateLayout& layout);

  unsigned latency(unsigned rows) const { return cfg_.base_latency + cfg_.row_latency * rows; }
  unsigned slots(Cycle now) { return rate_.available(now); }
  Cycle nextSlot(Cycle now) const { return rate_.nextAvailable(now); }
  // Starts one blend (or a drop of a late-culled fragment: rows = 0).
  void issue(Cycle now, uint32_t token, unsigned rows, bool drop = false) {  // inline: once per fragment
    rate_.take();
    rows = std::min(rows, rows_max_);
    const Cycle done = now + latency(rows);
    done_[rows].push({done, token});
    next_done_ = std::min(next_done_, done);
    ++in_flight_;
    // Counted by selects: drops are random per fragment.
    stats_.dropped += drop;
    stats_.blends += !drop;
    stats_.rows += drop ? 0u : rows;
  }
  // The approximate engine's visits: n blends (or drops) counted like n
  // issue()s, without the completion queue (the engine tallies its visits by
  // kind and counts them after the phase).
  void countMany(unsigned rows, bool drop, uint64_t n) {
    rows = std::min(rows, rows_max_);
    stats_.dropped += drop ? n : 0;
    stats_.blends += drop ? 0 : n;
    stats_.rows += drop ? 0 : n * rows;
  }
  // A blend's latency as issue() schedules it, rows capped at rows_max.
  unsigned latencyOf(unsigned rows) const { return latency(std::min(rows, rows_max_)); }
  // Calls f(token) for each blend finishing at `now`.
  template <class F>
  void complete(Cycle now, F&& f) {
    if (now < next_done_) return;  // nothing due (the common cycle; kNever: none in flight)
    next_done_ = kNever;
    for (auto& q : done_) {
      while (!q.empty() && q.front().first <= now) {
        const uint32_t t = q.front().second;
        q.pop();
        --in_flight_;
        f(t);
      }
      if (!q.empty()) next_done_ = std::min(next_done_, q.front().first);
    }
  }
  Cycle nextCompletion() const { return next_done_; }
  size_t inFlight() const { return in_flight_; }
  const AluStats& stats() const { return stats_; }

 private:
  AluConfig cfg_;
  RateLimiter rate_;
  std::vector<Fifo<std::pair<Cycle, uint32_t>>> done_;  // index: rows
  unsigned rows_max_;  // done_.size() - 1 (kept: size() divides by sizeof(Fifo))
  size_t in_flight_ = 0;
  // Earliest completion in flight, kNever when none: each FIFO holds one
  // latency, so its front is its earliest and the minimum over the fronts is exact.
  Cycle next_done_ = kNever;
  AluStats stats_;
};

}  // namespace oit::rop
