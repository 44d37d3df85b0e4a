// A port's capacity per cycle, booked earliest-free-first (PortCalendar.hpp).
#include "oit_rop/memory/PortCalendar.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

namespace oit::rop {

PortCalendar::PortCalendar(double bytes_per_clock, Cycle lookback) : lookback_(lookback) {
  if (!(bytes_per_clock > 0)) throw std::invalid_argument("PortCalendar: bytes_per_clock must be > 0");
  // Parts of a cycle per byte, times 2^16: a 64-byte transfer at 43.5 B/clock
  // is 64 x 1506.6 parts, rounded up once per request (never faster than configured).
  parts_per_byte_ = uint64_t(std::ceil(std::ldexp(double(kFull), 16) / bytes_per_clock));
  const size_t size = std::max<size_t>(1024, std::bit_ceil(size_t(2 * lookback + 64)));
  used_.assign(size, 0);
  full_.assign(size / 64, 0);
  mask_ = size - 1;
}

uint32_t PortCalendar::used(Cycle c) const {
  if (c < base_ || c > base_ + mask_) return 0;
  return used_[c & mask_];
}

void PortCalendar::clearRange(size_t first, size_t n) {
  if (n == 0) return;
  std::fill_n(used_.begin() + ptrdiff_t(first), n, 0u);
  // The full bits of slots [first, first + n): a word at a time.
  for (size_t i = first, end = first + n; i < end;) {
    const size_t bit = i & 63, take = std::min<size_t>(64 - bit, end - i);
    const uint64_t bits = take == 64 ? ~uint64_t(0) : ((uint64_t(1) << take) - 1) << bit;
    full_[i >> 6] &= ~bits;
    i += take;
  }
}

void PortCalendar::advanceBase(Cycle base) {
  // The cycles [base_, base) leave the ring: their slots become free for the
  // cycles one ring further on (cleared in at most two ranges of the ring:
  // a retire per fragment must not cost a step per cycle).
  if (base - base_ > mask_) {
    std::fill(used_.begin(), used_.end(), 0);
    std::fill(full_.begin(), full_.end(), 0);
  } else {
    const size_t first = size_t(base_ & mask_), n = size_t(base - base_), head = std::min(n, used_.size() - first);
    clearRange(first, head);
    clearRange(0, n - head);
  }
  base_ = base;
}

void PortCalendar::grow(Cycle last) {
  // Grow the ring (doubling) so that it covers [base_, last]; lay the
  // bookings out again at their cycles.
  size_t size = used_.size();
  while (base_ + size - 1 < last) size *= 2;
  std::vector<uint32_t> used(size, 0);
  std::vector<uint64_t> full_bits(size / 64, 0);
  const uint64_t mask = size - 1;
  for (Cycle c = base_; c <= base_ + mask_; ++c) {
    used[c & mask] = used_[c & mask_];
    if (full(c)) full_bits[(c & mask) >> 6] |= uint64_t(1) << (c & 63);
  }
  used_.swap(used);
  full_.swap(full_bits);
  mask_ = mask;
}

void PortCalendar::bookFrom(Cycle c, uint64_t need, Cycle& start, Cycle& end) {
  // The ring in locals: a store into it cannot alias them, so they are not
  // reloaded per cycle (reloaded after a grow).
  uint32_t* used = used_.data();
  uint64_t* full_bits = full_.data();
  uint64_t mask = mask_;
  Cycle limit = base_ + mask_;  // the last cycle the ring covers
  // The first cycle from c on with capacity left: full cycles skipped, a
  // bitmap word (64 cycles) at a time where possible.
  const auto firstWithRoom = [&] {
    for (;;) {
      if (c > limit) [[unlikely]] {
        grow(c);
        used = used_.data();
        full_bits = full_.data();
        mask = mask_;
        limit = base_ + mask_;
      }
      const unsigned bit = unsigned(c & 63);
      const uint64_t word = full_bits[(c & mask) >> 6] >> bit;
      if ((word & 1) == 0) return;
      c += word == ~uint64_t(0) >> bit ? 64 - bit : unsigned(std::countr_one(word));
    }
  };
  firstWithRoom();
  start = c;
  for (;;) {
    uint32_t& u = used[c & mask];
    if (u == 0 && need >= kFull) {
      // Empty cycles taken whole while they last (a line on an idle port:
      // 4 cycles at 16 B/clock), without the per-cycle share and bitmap
      // walk; the next cycle is empty, so firstWithRoom() would stay on it.
      do {
        used[c & mask] = kFull;
        full_bits[(c & mask) >> 6] |= uint64_t(1) << (c & 63);
        need -= kFull;
        ++c;
      } while (need >= kFull && c <= limit && used[c & mask] == 0);
      if (need == 0) break;
      firstWithRoom();
      continue;
    }
    const uint64_t take = std::min<uint64_t>(kFull - u, need);
    u += uint32_t(take);
    if (u == kFull) full_bits[(c & mask) >> 6] |= uint64_t(1) << (c & 63);
    need -= take;
    ++c;
    if (need == 0) break;
    firstWithRoom();
  }
  end = c;
}

}  // namespace oit::rop
