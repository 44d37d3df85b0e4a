// The shared levels' slice port: capacity per cycle booked earliest-free-first,
// so that a request booked out of time order fills the gaps (values by hand).
#include <gtest/gtest.h>

#include "oit_rop/TestLcg.hpp"
#include "oit_rop/memory/PortCalendar.hpp"

using namespace oit::rop;

TEST(PortCalendar, InOrderRequestsQueueAtTheRate) {
  PortCalendar p(16.0, 1000);  // 16 B/clock: a 64-byte transfer is 4 cycles
  Cycle s, e;
  p.book(0, 64, s, e);
  EXPECT_EQ(s, 0u);
  EXPECT_EQ(e, 4u);
  p.book(0, 64, s, e);  // behind the first
  EXPECT_EQ(s, 4u);
  EXPECT_EQ(e, 8u);
  p.book(20, 64, s, e);  // an idle port: at once
  EXPECT_EQ(s, 20u);
  EXPECT_EQ(e, 24u);
}

TEST(PortCalendar, AnEarlierRequestFillsTheGapALaterBookingLeft) {
  PortCalendar p(16.0, 1000);
  Cycle s, e;
  p.book(100, 64, s, e);  // a partition ahead books cycles 100..103
  p.book(10, 64, s, e);   // one a quantum behind: cycles 10..13, not behind 103
  EXPECT_EQ(s, 10u);
  EXPECT_EQ(e, 14u);
  p.book(98, 64, s, e);  // 98, 99, then 100..103 are full: 104, 105
  EXPECT_EQ(s, 98u);
  EXPECT_EQ(e, 106u);
  EXPECT_EQ(p.used(101), 1u << 16);
}

TEST(PortCalendar, ARunOfEmptyCyclesStopsAtAPartlyBookedOne) {
  PortCalendar p(16.0, 1000);
  Cycle s, e;
  p.book(10, 8, s, e);  // half of cycle 10
  EXPECT_EQ(p.used(10), 1u << 15);
  // 64 B from 8: cycles 8 and 9 whole, the other half of 10, all of 11, and
  // half of 12 (4 cycles of capacity): done at 13.
  p.book(8, 64, s, e);
  EXPECT_EQ(s, 8u);
  EXPECT_EQ(e, 13u);
  EXPECT_EQ(p.used(9), 1u << 16);
  EXPECT_EQ(p.used(10), 1u << 16);
  EXPECT_EQ(p.used(11), 1u << 16);
  EXPECT_EQ(p.used(12), 1u << 15);
  // A run past the ring's end: the ring is 4096 cycles (2 x 1000 + 64
  // rounded up to a power of two), from 3090 once a request at 4090 retires
  // what is more than the lookback behind it, so to 7185; 64 KiB from 4090
  // is 4096 cycles, to 8185: the ring grows in the middle of the run.
  p.book(4090, 65536, s, e);
  EXPECT_EQ(s, 4090u);
  EXPECT_EQ(e, 4090u + 4096);
  EXPECT_EQ(p.used(7185), 1u << 16);
  EXPECT_EQ(p.used(4090 + 4095), 1u << 16);
  EXPECT_EQ(p.used(4090 + 4096), 0u);
}

TEST(PortCalendar, FractionalRatesShareACycle) {
  PortCalendar p(43.5, 1000);  // 64 B = 1.47 cycles
  Cycle s, e;
  p.book(0, 64, s, e);
  EXPECT_EQ(s, 0u);
  EXPECT_EQ(e, 2u);  // done within cycle 1
  p.book(0, 32, s, e);  // the rest of cycle 1 (0.53 of it: 23 B) and part of cycle 2
  EXPECT_EQ(s, 1u);
  EXPECT_EQ(e, 3u);
}

// Never more than the rate: requests out of order by up to 200 cycles, far
// more bytes than the port moves meanwhile (a backlog): the bookings end no
// sooner than bytes / rate after the first request could start, and (every
// cycle of the backlog filled, earliest first) no later either.
TEST(PortCalendar, NeverBooksMoreThanTheRateAndLeavesNoHoles) {
  PortCalendar p(8.0, 512);
  oit::rop::testutil::TestLcg rng{7, 13};
  uint64_t bytes = 0;
  Cycle now = 1000, first = ~Cycle(0), last_end = 0;
  for (int i = 0; i < 20000; ++i) {
    now += rng(3);
    const Cycle at = now - rng(200);  // up to 200 cycles behind
    const uint32_t b = uint32_t(32 * (1 + rng(4)));
    Cycle s, e;
    p.book(at, b, s, e);
    ASSERT_GE(s, at);
    ASSERT_GT(e, s);
    bytes += b;
    first = std::min(first, at);
    last_end = std::max(last_end, e);
  }
  for (Cycle c = last_end - 10000; c < last_end; ++c) ASSERT_EQ(p.used(c), 1u << 16) << c;  // the backlog: full
  EXPECT_GE(last_end - first, bytes / 8);
  EXPECT_LE(last_end - first, bytes / 8 + 16);  // (idle cycles only before the backlog built up)
}

// Retiring cycles frees their slots for the cycles one ring further on. These
// tests retire by large steps (advanceBase: at most two ranges of the ring,
// bit masks a 64-bit word at a time), across 64-bit words of the full-cycle
// bitmap and across the ring's end, and check which cycles are free afterwards
// through used() and through a booking (which skips the cycles whose full bit
// is set). At 1 B/clock one byte books one whole cycle; lookback 0: only
// retireBefore moves the ring; the ring then has max(1024, bit_ceil(0 + 64)) =
// 1024 slots (cycle c in slot c mod 1024, its full bit in word (c mod 1024) / 64).
namespace {
constexpr uint32_t kWholeCycle = 1u << 16;
// used(c) == expect for every c in [first, last): the first cycle that is not.
testing::AssertionResult usedIs(const PortCalendar& p, Cycle first, Cycle last, uint32_t expect) {
  for (Cycle c = first; c < last; ++c)
    if (p.used(c) != expect) return testing::AssertionFailure() << "used(" << c << ") = " << p.used(c) << ", expected " << expect;
  return testing::AssertionSuccess();
}
// Makes the ring of a 1 B/clock, lookback-0 calendar cover [base, base + 1024)
// (base < 1024) with every slot booked: the whole ring booked from cycle 0,
// the cycles before `base` retired, the freed ones booked again.
void fillRingFrom(PortCalendar& p, Cycle base) {
  Cycle s, e;
  p.book(0, 1024, s, e);
  p.retireBefore(base);
  p.book(1024, uint32_t(base), s, e);
  EXPECT_EQ(e, base + 1024);
}
}  // namespace

TEST(PortCalendar, RetiringAcrossBitmapWordsFreesExactlyTheRetiredSlots) {
  PortCalendar p(1.0, 0);
  Cycle s, e;
  p.book(0, 1024, s, e);  // the whole ring: cycles 0..1023, every slot full
  ASSERT_EQ(s, 0u);
  ASSERT_EQ(e, 1024u);
  // Cycles 0..999 leave (slots 0..999: words 0..14 whole, bits 0..39 of word
  // 15); the ring now covers 1000..2023: 1000..1023 still booked (slots
  // 1000..1023, bits 40..63 of word 15), 1024..2023 (slots 0..999) free.
  p.retireBefore(1000);
  EXPECT_TRUE(usedIs(p, 1000, 1024, kWholeCycle));
  EXPECT_TRUE(usedIs(p, 1024, 2024, 0));
  // A booking from 1000 skips the 24 full cycles and takes the 1000 free ones
  // after them: it ends at 2024, the ring's end (a stale full bit would push
  // it further, and the ring would grow).
  p.book(1000, 1000, s, e);
  EXPECT_EQ(s, 1024u);
  EXPECT_EQ(e, 2024u);
  EXPECT_TRUE(usedIs(p, 1000, 2024, kWholeCycle));
}

TEST(PortCalendar, RetiringAcrossTheRingsEndClearsBothRanges) {
  PortCalendar p(1.0, 0);
  fillRingFrom(p, 1000);  // the ring [1000, 2024), every slot booked
  Cycle s, e;
  // Cycles 1000..1099 leave: slots 1000..1023 (bits 40..63 of word 15, up to
  // the ring's end) and, wrapped, slots 0..75 (word 0 whole, bits 0..11 of
  // word 1). The ring covers 1100..2123: 1100..2023 stay booked; 2024..2047
  // (slots 1000..1023) and 2048..2123 (slots 0..75) free.
  p.retireBefore(1100);
  EXPECT_TRUE(usedIs(p, 1100, 2024, kWholeCycle));
  EXPECT_TRUE(usedIs(p, 2024, 2124, 0));
  // Exactly 100 free cycles, the first at 2024: 100 bytes end at the ring's end.
  p.book(1100, 100, s, e);
  EXPECT_EQ(s, 2024u);
  EXPECT_EQ(e, 2124u);
  EXPECT_TRUE(usedIs(p, 1100, 2124, kWholeCycle));
}

TEST(PortCalendar, RetiringMoreThanTheRingFreesEverySlot) {
  PortCalendar p(1.0, 0);
  fillRingFrom(p, 700);  // [700, 1724) full
  Cycle s, e;
  // 700 -> 3000: 2300 cycles leave, more than the ring's 1024: every slot
  // cleared; the ring covers 3000..4023, all free.
  p.retireBefore(3000);
  EXPECT_TRUE(usedIs(p, 3000, 4024, 0));
  p.book(3000, 1024, s, e);
  EXPECT_EQ(s, 3000u);
  EXPECT_EQ(e, 4024u);
}

// The lookback moves the ring as requests arrive: lookback 300 gives a ring of
// max(1024, bit_ceil(2 x 300 + 64) = 1024) slots, and a request at cycle n
// retires the cycles before n - 300 (here across the ring's end).
TEST(PortCalendar, ALaterRequestRetiresTheCyclesPastTheLookback) {
  PortCalendar p(1.0, 300);
  Cycle s, e;
  p.book(0, 1000, s, e);  // cycles 0..999 (slots 0..999)
  ASSERT_EQ(e, 1000u);
  // A request at 1000 retires 0..699: the ring covers 700..1723, its 24
  // cycles 1000..1023 fill the ring's end; 1024..1723 (slots 0..699) are free.
  p.book(1000, 24, s, e);
  EXPECT_EQ(s, 1000u);
  EXPECT_EQ(e, 1024u);
  EXPECT_TRUE(usedIs(p, 700, 1024, kWholeCycle));
  EXPECT_TRUE(usedIs(p, 1024, 1724, 0));
  p.book(1024, 700, s, e);  // every slot booked
  ASSERT_EQ(e, 1724u);
  // A request at 1400 retires 700..1099: slots 700..1023 (from bit 60 of word
  // 10 to the ring's end) and 0..75 (word 0, bits 0..11 of word 1). The ring
  // covers 1100..2123: 1100..1723 booked, 1724..2123 (400 cycles) free, so the
  // request, whose own cycle is booked, starts at 1724.
  p.book(1400, 1, s, e);
  EXPECT_EQ(s, 1724u);
  EXPECT_EQ(e, 1725u);
  EXPECT_TRUE(usedIs(p, 1100, 1725, kWholeCycle));
  EXPECT_TRUE(usedIs(p, 1725, 2124, 0));
  p.book(1400, 399, s, e);  // the other 399 free cycles: up to the ring's end
  EXPECT_EQ(s, 1725u);
  EXPECT_EQ(e, 2124u);
}
