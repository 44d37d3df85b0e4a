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
