#include "oit_rop/memory/DramWriteQueue.hpp"

#include <algorithm>
#include <cstddef>

namespace oit::rop {

DramWriteQueue::DramWriteQueue(unsigned capacity, unsigned high, unsigned low)
    : capacity_(capacity), high_(high), low_(low) {}

uint64_t DramWriteQueue::roomAt(uint64_t arrive, uint64_t bursts) {
  // Writes enter in order: none before a write that had to wait for room.
  uint64_t at = std::max(arrive, waited_until_);
  // Entries whose data is on the bus by then are free.
  while (head_ < in_flight_.size() && in_flight_[head_].end <= at) {
    in_flight_bursts_ -= in_flight_[head_].bursts;
    ++head_;
  }
  const uint64_t waiting = pending_ + bursts;
  const uint64_t allowed = waiting < capacity_ ? capacity_ - waiting : 0;  // in-flight bursts that may remain
  while (in_flight_bursts_ > allowed) {
    at = std::max(at, in_flight_[head_].end);
    in_flight_bursts_ -= in_flight_[head_].bursts;
    ++head_;
  }
  if (head_ == in_flight_.size()) {
    in_flight_.clear();
    head_ = 0;
  } else if (head_ > 64 && head_ * 2 > in_flight_.size()) {  // keep the vector from growing with the frame
    in_flight_.erase(in_flight_.begin(), in_flight_.begin() + std::ptrdiff_t(head_));
    head_ = 0;
  }
  if (at > arrive) waited_until_ = at;
  return at;
}

void DramWriteQueue::add(const Run& r) {
  runs_.push_back(r);
  pending_ += r.bursts;
}

const std::vector<DramWriteQueue::Run>& DramWriteQueue::takeBatch(bool all) {
  batch_.clear();
  taken_.assign(runs_.size(), false);
  const uint64_t target = all ? 0 : low_;
  // Oldest row first, with the later writes of the same row while the queue
  // is above the target: row hits first, then oldest, as the controller's
  // scheduler would drain it; whole runs (one request's bursts) only.
  for (size_t i = 0; i < runs_.size() && pending_ > target; ++i) {
    if (taken_[i]) continue;
    Run merged = runs_[i];
    taken_[i] = true;
    pending_ -= merged.bursts;
    for (size_t j = i + 1; j < runs_.size() && pending_ > target; ++j) {
      if (!taken_[j] && runs_[j].bank == merged.bank && runs_[j].row == merged.row) {
        merged.bursts += runs_[j].bursts;
        merged.accepted = std::max(merged.accepted, runs_[j].accepted);
        pending_ -= runs_[j].bursts;
        taken_[j] = true;
      }
    }
    batch_.push_back(merged);
  }
  size_t kept = 0;
  for (size_t i = 0; i < runs_.size(); ++i)
    if (!taken_[i]) runs_[kept++] = runs_[i];
  runs_.resize(kept);
  return batch_;
}

void DramWriteQueue::drained(uint64_t end, uint64_t bursts) {
  in_flight_.push_back({end, bursts});
  in_flight_bursts_ += bursts;
}

}  // namespace oit::rop
