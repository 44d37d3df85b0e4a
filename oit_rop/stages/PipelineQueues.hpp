// Small allocation-free building blocks of the ROP stages: an in-order FIFO
// ring, a timing wheel for variable latencies (bucketed ring, no heap: the
// SystemC notes measured a priority queue at 24% of the run), and a
// fixed-point rate limiter for "N per clock" throughputs.
#pragma once

#include <algorithm>
#include <bit>
#include <cstdint>
#include <stdexcept>
#include <vector>

#include "oit_rop/Types.hpp"

namespace oit::rop {

// FIFO ring with power-of-two capacity; grows (amortised) only when full, so a
// warmed-up pipeline never allocates.
template <class T>
class Fifo {
 public:
  explicit Fifo(size_t initial = 16) {
    buf_.resize(std::bit_ceil(std::max<size_t>(initial, 2)));
    mask_ = buf_.size() - 1;
  }
  bool empty() const { return head_ == tail_; }
  size_t size() const { return (tail_ - head_) & mask_; }
  T& front() { return buf_[head_]; }
  const T& front() const { return buf_[head_]; }
  const T& at(size_t i) const { return buf_[(head_ + i) & mask_]; }  // i < size()
  void push(const T& v) {
    buf_[tail_] = v;
    tail_ = (tail_ + 1) & mask_;
    if (tail_ == head_) grow();  // just became full: never observed full
  }
  void pop() { head_ = (head_ + 1) & mask_; }
  void clear() { head_ = tail_ = 0; }

  // The consumer's side of the ring in locals, for a loop that pops many
  // records (the approximate engine): the FIFO's own fields would be reloaded
  // after every store the loop makes through a pointer. Give the head back
  // with setHead() before anything else may look at the FIFO, and take a new
  // cursor() after anything may have pushed to it (or grown it).
  struct Cursor {
    const T* ring;
    size_t mask, head, tail;
    bool empty() const { return head == tail; }
    size_t size() const { return (tail - head) & mask; }
    const T& front() const { return ring[head]; }
    const T& at(size_t i) const { return ring[(head + i) & mask]; }  // i < size(); past it, an older slot
    void pop() { head = (head + 1) & mask; }
  };
  Cursor cursor() const { return {buf_.data(), mask_, head_, tail_}; }
  void setHead(const Cursor& c) { head_ = c.head; }

 private:
  [[gnu::noinline, gnu::cold]] void grow() {  // out of the hot callers (rare)
    const size_t n = buf_.size();
    std::vector<T> b(n * 2);
    for (size_t i = 0; i < n; ++i) b[i] = buf_[(head_ + i) & mask_];
    buf_.swap(b);
    head_ = 0;
    tail_ = n;
    mask_ = buf_.size() - 1;
  }
  std::vector<T> buf_;
  size_t mask_ = 0;  // buf_.size() - 1 (a power of two minus one)
  size_t head_ = 0, tail_ = 0;
};

// Tokens due at a future cycle, at most `horizon` - 1 cycles ahead. Every cycle
// the owner drains the bucket of `now`; the simulator never jumps past
// nextDue(), so no bucket is skipped. Within a bucket, scheduling order.
class TimingWheel {
 public:
  explicit TimingWheel(unsigned horizon)
      : buckets_(std::bit_ceil(std::max(horizon, 2u))),
        used_((buckets_.size() + 63) / 64, 0),
        mask_(buckets_.size() - 1) {}
  unsigned horizon() const { return unsigned(buckets_.size()); }
  void schedule(Cycle due, uint32_t token) {
    const size_t i = due & mask_;
    buckets_[i].push_back(token);
    used_[i >> 6] |= uint64_t(1) << (i & 63);
    ++count_;
  }
  // Calls f(token) for every token due at `now`, in scheduling order.
  template <class F>
  void drain(Cycle now, F&& f) {
    const size_t i = now & mask_;
    auto& b = buckets_[i];
    if (b.empty()) return;
    for (uint32_t t : b) f(t);
    count_ -= b.size();
    b.clear();
    used_[i >> 6] &= ~(uint64_t(1) << (i & 63));
  }
  // First cycle after `now` with a due token (kNever when empty): the first
  // set bit of the occupancy bitmap from bucket now + 1 on, wrapping around.
  Cycle nextDue(Cycle now) const {
    if (count_ == 0) return kNever;
    // words is a power of two (the bucket count is, and is < 64 only when words == 1),
    // so the word index wraps with a mask (a % here was a division per call).
    const size_t mask = mask_, start = (now + 1) & mask, words = used_.size(), wmask = words - 1;
    const size_t w0 = start >> 6;
    uint64_t w = used_[w0] & (~uint64_t(0) << (start & 63));
    for (size_t k = 0;; ++k) {
      if (w) {
        const size_t i = ((w0 + k) & wmask) * 64 + size_t(std::countr_zero(w));
        return now + 1 + ((i - start) & mask);
      }
      if (k == words) return kNever;
      w = used_[(w0 + k + 1) & wmask];
      if (k + 1 == words) w &= ~(~uint64_t(0) << (start & 63));  // wrapped: the bits below start
    }
  }
  size_t size() const { return count_; }

 private:
  std::vector<std::vector<uint32_t>> buckets_;
  std::vector<uint64_t> used_;  // bit i: bucket i holds tokens
  size_t mask_;                 // buckets_.size() - 1 (kept: size() of a vector of vectors divides by 24)
  size_t count_ = 0;
};

// "rate per clock" as integer credits in 1/2^20 units, accumulated lazily by
// elapsed cycles: the same answers whether or not idle cycles are skipped.
// The rate is the requested one rounded to 2^-20 per clock: within 0.05 % at
// the smallest configurable rate, 0.001 per clock (CONFIG.md). Overflow-free
// up to kMaxPerClock: credit <= cap <= 2^30 and rate * dt < rate * cap <= 2^60.
class RateLimiter {
 public:
  static constexpr unsigned kShift = 20;
  static constexpr int64_t kOne = int64_t(1) << kShift;
  static constexpr double kMaxPerClock = 1024;
  explicit RateLimiter(double per_clock = 1.0) {
    if (!(per_clock > 0) || !(per_clock <= kMaxPerClock))
      throw std::invalid_argument("rate per clock must be in (0, 1024]");
    rate_ = std::max<int64_t>(1, int64_t(per_clock * kOne + 0.5));
    cap_ = std::max(rate_, kOne);
    credit_ = cap_;
  }
  // Tokens that may pass at `now` (call once per cycle per stage, before take()).
  // No "time advanced?" branch (selects instead): dt = 0 adds nothing, and an
  // earlier `now` than the last call's (no caller does that) adds nothing either.
  unsigned available(Cycle now) {
    const Cycle dt = now > last_ ? now - last_ : 0;
    credit_ = dt >= Cycle(cap_) ? cap_ : std::min(cap_, credit_ + rate_ * int64_t(dt));
    last_ = now > last_ ? now : last_;
    return unsigned(uint64_t(credit_) >> kShift);  // credit_ >= 0: take() only spends what available() granted
  }
  void take() { credit_ -= kOne; }
  // Earliest cycle > now at which one token is available. Counted from the
  // last available() call, so callers may skip available() on cycles where
  // they take nothing (the credit accrues the same either way).
  Cycle nextAvailable(Cycle now) const {
    if (credit_ >= kOne) return now + 1;
    return std::max(now + 1, last_ + Cycle((kOne - credit_ + rate_ - 1) / rate_));
  }
  double perClock() const { return double(rate_) / kOne; }

 private:
  int64_t rate_ = kOne, cap_ = kOne, credit_ = kOne;
  Cycle last_ = 0;
};

// Anything that books DRAM transfers (the partition's TLM port, or a fixed
// latency fake in unit tests). Returns the completion cycle.
class MemoryPort {
 public:
  virtual ~MemoryPort() = default;
  virtual Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) = 0;
};

}  // namespace oit::rop
