// BlendAlu: the blending-array read-modify-write unit. Throughput is
// alu.blends_per_clock scaled by the row format (rgba8t8z32: 1, fp16:
// fp16_rate, fp32: fp32_rate); an insert's latency is what its insert did
// (model::InsertWork, reported by the functional insert and carried with the
// fragment): base_latency + cycles_per_compare x rows compared +
// cycles_per_row_moved x rows written (ALGORITHMS.md, "Work per insert").
// An insert may also start late (the A-buffer's node-counter atomic), so
// completions sit in a heap ordered by (cycle, issue order).
#pragma once

#include <algorithm>
#include <cstdint>
#include <functional>
#include <deque>
#include <queue>
#include <utility>
#include <vector>

#include "model/OitAlgorithm.hpp"
#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

struct AluStats {
  uint64_t blends = 0, compares = 0, moves = 0, dropped = 0;
};

class BlendAlu {
 public:
  BlendAlu(const AluConfig& cfg, double format_rate);

  // Without lazy merging (skip.lazy_merge = false) every kept fragment pays
  // the merge as if the array were full: at least `array_rows` rows moved.
  static model::InsertWork chargedWork(model::InsertWork w, model::InsertOutcome o, unsigned array_rows,
                                       bool lazy_merge) {
    if (!lazy_merge && o == model::InsertOutcome::Stored)
      w.moves = uint8_t(std::max<unsigned>(w.moves, std::min(255u, std::max(1u, array_rows))));
    return w;
  }
  static double formatRate(const AluConfig& cfg, const model::StateLayout& layout);

  unsigned latency(model::InsertWork w) const {
    return cfg_.base_latency + cfg_.cycles_per_compare * w.compares + cfg_.cycles_per_row_moved * w.moves;
  }
  unsigned slots(Cycle now) { return rate_.available(now); }
  Cycle nextSlot(Cycle now) const { return rate_.nextAvailable(now); }
  // Starts one blend (or a drop of a late-culled fragment: no work) at `now`;
  // its work begins at `start` >= now (later when it waited for an atomic).
  void issue(Cycle now, uint32_t token, model::InsertWork w, bool drop = false, Cycle start = 0) {  // inline: once per fragment
    rate_.take();
    if (drop) w = {0, 0};
    const Cycle done = std::max(now, start) + latency(w);
    done_.push({done, order_++, token});
    if (start > now) starts_.push_back(start);  // nondecreasing: NodeCounter grants come in order
    next_done_ = std::min(next_done_, done);
    // Counted by selects: drops are random per fragment.
    stats_.dropped += drop;
    stats_.blends += !drop;
    stats_.compares += w.compares;
    stats_.moves += w.moves;
  }
  // The approximate engine's visits: one blend (or drop) counted like issue(),
  // without the completion queue.
  void count(model::InsertWork w, bool drop) {
    if (drop) w = {0, 0};
    stats_.dropped += drop;
    stats_.blends += !drop;
    stats_.compares += w.compares;
    stats_.moves += w.moves;
  }
  // Calls f(token) for each blend finishing at or before `now`, in finishing order.
  template <class F>
  void complete(Cycle now, F&& f) {
    if (now < next_done_) return;  // nothing due (the common cycle; kNever: none in flight)
    while (!done_.empty() && done_.top().done <= now) {
      const uint32_t t = done_.top().token;
      done_.pop();
      f(t);
    }
    next_done_ = done_.empty() ? kNever : done_.top().done;
  }
  Cycle nextCompletion() const { return next_done_; }
  // Every blend in flight still waits for its start (the node counter's atomic).
  bool allWaitingAt(Cycle now) {
    while (!starts_.empty() && starts_.front() <= now) starts_.pop_front();
    return !done_.empty() && starts_.size() == done_.size();
  }
  size_t inFlight() const { return done_.size(); }
  const AluStats& stats() const { return stats_; }

 private:
  struct Done {
    Cycle done;
    uint64_t order;  // issue order breaks ties: equal cycles complete as issued
    uint32_t token;
    bool operator>(const Done& o) const { return done != o.done ? done > o.done : order > o.order; }
  };
  AluConfig cfg_;
  RateLimiter rate_;
  std::priority_queue<Done, std::vector<Done>, std::greater<Done>> done_;
  uint64_t order_ = 0;
  std::deque<Cycle> starts_;  // starts still ahead of the blends that waited
  Cycle next_done_ = kNever;  // earliest completion in flight, kNever when none
  AluStats stats_;
};

}  // namespace oit::rop
