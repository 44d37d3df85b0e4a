// Root-cause attribution (oit_rop/RootCause.hpp, DESIGN.md "Root causes"):
// the accounts and the DRAM split derived by hand. (The roofline
// microbenchmarks, tests/oit_rop/test_bounds.cpp, check that each reports the
// resource it stresses as timing.bound_by with at least 90 % of the cycles.)
#include <gtest/gtest.h>

#include "oit_rop/RootCause.hpp"
#include "oit_rop/memory/DramTestConfig.hpp"
#include "oit_rop/memory/MemorySystem.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

uint64_t at(const RootCauseAccount& a, RootCause c) { return a.cycles()[size_t(c)]; }

// A wait's inner ends: the unloaded access, then refresh, bank, turnaround, bus.
void expectEnds(const WaitSplit& w, Cycle latency, Cycle refresh, Cycle bank, Cycle turn, Cycle queue) {
  EXPECT_EQ(w.latency_end, latency);
  EXPECT_EQ(w.refresh_end, refresh);
  EXPECT_EQ(w.bank_end, bank);
  EXPECT_EQ(w.turn_end, turn);
  EXPECT_EQ(w.queue_end, queue);
}
// The causes a wait from `from` to `to` is charged, accounted alone (no bus record: its
// unloaded access all latency).
RootCauseAccount chargedAlone(Cycle from, Cycle to, const WaitSplit& w) {
  RootCauseAccount a;
  a.setWait(from, w);
  a.account(to);
  return a;
}

// A wait from 4 to 20 whose DRAM unloaded access ends at 10 and queueing at
// 15: 6 cycles of latency, 5 of bandwidth, 5 of the cache's own; then the
// ALU from 20 to 30.
TEST(RootCauseAccount, AWaitIsChargedByItsParts) {
  RootCauseAccount a;
  a.set(0, RootCause::Input);
  a.setWait(4, WaitSplit{10, 15, 15, RootCause::RopCacheMiss});
  a.set(20, RootCause::Alu);
  a.account(30);
  EXPECT_EQ(at(a, RootCause::Input), 4u);
  EXPECT_EQ(at(a, RootCause::DramLatency), 6u);
  EXPECT_EQ(at(a, RootCause::DramBandwidth), 5u);
  EXPECT_EQ(at(a, RootCause::RopCacheMiss), 5u);
  EXPECT_EQ(at(a, RootCause::Alu), 10u);
  EXPECT_EQ(a.total(), 30u);
  // Only the tail of a wait: from 12 on, 3 cycles of queueing, 2 of transfer
  // (its further data: both bandwidth) and 3 of the L2.
  RootCauseAccount b;
  b.setWait(12, WaitSplit{10, 15, 17, RootCause::L2});
  b.skipTo(12);
  b.account(20);
  EXPECT_EQ(at(b, RootCause::DramBandwidth), 5u);
  EXPECT_EQ(at(b, RootCause::DramLatency), 0u);
  EXPECT_EQ(at(b, RootCause::L2), 3u);
}

// A line ready at 180 asked at 100 whose DRAM read completed at 170, 40
// cycles to its first data and 12 more for the rest on an idle channel: 70
// cycles of DRAM: the latency 40 first (overlapping the bus's older data),
// queueing 18, the transfer 12; the last 10 are the cache's.
TEST(RootCauseAccount, SplitWaitPutsTheUnloadedAccessFirst) {
  const WaitSplit w = splitWait(100, 180, DramProbe{170, 40, 12});
  EXPECT_EQ(w.latency_end, 140u);
  EXPECT_EQ(w.queue_end, 158u);
  EXPECT_EQ(w.dram_end, 170u);
  EXPECT_EQ(w.rest, RootCause::RopCacheMiss);
  // No DRAM request (a fast-clear fill): the whole wait is the cache's.
  const WaitSplit c = splitWait(100, 110, DramProbe{});
  EXPECT_EQ(c.latency_end, 100u);
  EXPECT_EQ(c.dram_end, 100u);
}

// Delays of 3 (lock) and 1 (ALU) share 10 cycles: 7 and 2 whole, the cycle
// left to the larger remainder (both 2/4: the first cause, the lock): 8 and 2.
// With no delay gathered the fallback takes all.
TEST(RootCauseAccount, DelaySharesAddUpExactly) {
  DelayShares s;
  RootCauseAccount a;
  s.add(RootCause::LockWait, 3);
  s.add(RootCause::Alu, 1);
  s.chargeTo(a, 10, RootCause::ScoreboardFull);
  EXPECT_EQ(at(a, RootCause::LockWait), 8u);
  EXPECT_EQ(at(a, RootCause::Alu), 2u);
  s.chargeTo(a, 5, RootCause::ScoreboardFull);  // the delays were used up
  EXPECT_EQ(at(a, RootCause::ScoreboardFull), 5u);
  EXPECT_EQ(a.total(), 15u);
}

// The DRAM's split on the round configuration (DramTestConfig.hpp: controller
// 40, tRCD = CL = 11, a 64 B burst 4 cycles, one channel):
//  - one 64 B read at cycle 0 on an idle channel: 40 + 11 + 11 + 4 = 66, all latency;
//  - a 256 B read: its first burst at 66, three more at the bus's rate: 78,
//    66 latency and 12 bandwidth;
//  - a 64 B read to another bank asked with it: its row opens in parallel, its
//    data waits for the bus until 78: done 82, 66 latency and 16 queueing.
TEST(RootCauseAccount, DramWaitSplitsIntoQueueingAndUnloadedAccess) {
  MemorySystem m(roundDramConfig(1), kRoundMhz);
  ASSERT_EQ(m.unloadedCycles(false), kCtrl + kTrcd + kCl + kBurst);
  m.resetProbe();
  EXPECT_EQ(m.access(0, 0, 64, false, Surface::BlendArrays), 66u);
  EXPECT_EQ(m.probe().done, 66u);
  EXPECT_EQ(m.probe().unloaded, 66u);
  WaitSplit w = splitWait(0, 66, m.probe());
  EXPECT_EQ(w.latency_end, 66u);
  EXPECT_EQ(w.queue_end, 66u);
  EXPECT_EQ(w.dram_end, 66u);

  MemorySystem n(roundDramConfig(1), kRoundMhz);
  n.resetProbe();
  EXPECT_EQ(n.access(0, 0, 256, false, Surface::BlendArrays), 78u);
  EXPECT_EQ(n.probe().transfer, 12u);
  w = splitWait(0, 78, n.probe());
  EXPECT_EQ(w.latency_end, 66u);
  EXPECT_EQ(w.queue_end, 66u);
  EXPECT_EQ(w.dram_end, 78u);  // bandwidth: its own three further bursts
  ASSERT_NE(n.bankOf(8192), n.bankOf(0));
  n.resetProbe();
  EXPECT_EQ(n.access(0, 8192, 64, false, Surface::BlendArrays), 82u);
  w = splitWait(0, 82, n.probe());
  EXPECT_EQ(w.latency_end, 66u);
  EXPECT_EQ(w.queue_end, 82u);  // queued 16 cycles behind the first read's data
  EXPECT_EQ(w.dram_end, 82u);
  // A posted write's latency is the controller's: accepted at 40 on an empty queue.
  n.resetProbe();
  EXPECT_EQ(n.access(0, 1 << 20, 64, true, Surface::BlendArrays), 40u);
  EXPECT_EQ(n.probe().unloaded, 40u);
}

// The unloaded access is latency only where the buses were idle: the second
// read above waits 66 cycles of unloaded access, then 16 of queueing. The
// buses' record holds 20 busy cycles (the two reads' data, [62, 82)) in its
// first 256-cycle block, taken as spread over the block: 66 x 20 / 256 = 5.2,
// so 5 of the 66 cycles are bandwidth and 61 latency; bandwidth 5 + 16 = 21.
TEST(RootCauseAccount, UnloadedAccessWhileTheBusIsBusyIsBandwidth) {
  MemorySystem m(roundDramConfig(1), kRoundMhz);
  m.access(0, 0, 256, false, Surface::BlendArrays);
  m.resetProbe();
  ASSERT_EQ(m.access(0, 8192, 64, false, Surface::BlendArrays), 82u);
  EXPECT_NEAR(m.busShare(0, 256), 20.0 / 256.0, 1e-12);
  RootCauseAccount a;
  a.setBusShare(BusShareFn::of(m));
  a.setWait(0, splitWait(0, 82, m.probe()));
  a.account(82);
  EXPECT_EQ(at(a, RootCause::DramLatency), 61u);
  EXPECT_EQ(at(a, RootCause::DramBandwidth), 21u);
}

// The queueing split by what the controller waited for (round configuration
// as above: controller 40, tRCD = CL = tRP = 11, a burst 4, 8 KiB rows, 8
// banks; tWTR 6 clocks = 6 cycles):
//  - a bank conflict: a read of row 0 of bank 0 (done 66), then one of row 1
//    of bank 0 (byte 8 x 8 KiB) asked at 0: its precharge waits for the first
//    one's data (66), precharge to 77, activate to 88, data from 99: done
//    103, 66 unloaded and 37 of queueing: from arrival + tRCD + CL = 62 to
//    66 the bus moved the first read's data (bandwidth, 4), from 66 to 99
//    the bank opened the row (bank conflict, 33);
//  - a turnaround: a write to bank 1 drained at 40 (activate 40, data
//    [62, 66)), then a read of bank 2 asked at 0: its row opens at 51, the
//    bus is free at 66 (4 cycles behind arrival + tRCD + CL = 62: the bus),
//    its column command waits for tWTR after the write data: 72, data at 83,
//    done 87: 21 of queueing, 4 the bus's, 17 the turnaround's (tWTR + CL).
TEST(RootCauseAccount, DramQueueingSplitsByWhatTheControllerWaitedFor) {
  MemorySystem m(roundDramConfig(1), kRoundMhz);
  m.access(0, 0, 64, false, Surface::BlendArrays);
  ASSERT_EQ(m.bankOf(8 * 8192), m.bankOf(0));
  ASSERT_NE(m.rowOf(8 * 8192), m.rowOf(0));
  m.resetProbe();
  ASSERT_EQ(m.access(0, 8 * 8192, 64, false, Surface::BlendArrays), 103u);
  WaitSplit w = splitWait(0, 103, m.probe());
  expectEnds(w, 66, 66, 99, 99, 103);
  const RootCauseAccount a = chargedAlone(0, 103, w);
  EXPECT_EQ(at(a, RootCause::DramLatency), 66u);
  EXPECT_EQ(at(a, RootCause::DramBankConflict), 33u);
  EXPECT_EQ(at(a, RootCause::DramBandwidth), 4u);

  MemorySystem n(roundDramConfig(1), kRoundMhz);
  ASSERT_EQ(n.twtrCycles(), 6.0);
  ASSERT_EQ(n.access(0, 8192, 64, true, Surface::BlendArrays), 40u);
  ASSERT_EQ(n.drainWrites(40), 66u);
  n.resetProbe();
  ASSERT_EQ(n.access(0, 2 * 8192, 64, false, Surface::BlendArrays), 87u);
  w = splitWait(0, 87, n.probe());
  const RootCauseAccount b = chargedAlone(0, 87, w);
  EXPECT_EQ(at(b, RootCause::DramLatency), 66u);
  EXPECT_EQ(at(b, RootCause::DramTurnaround), 17u);
  EXPECT_EQ(at(b, RootCause::DramBandwidth), 4u);
  EXPECT_EQ(at(b, RootCause::DramBankConflict), 0u);
  EXPECT_EQ(b.total(), 87u);
  // The approximate engine's shares take the same split.
  DelayShares s;
  RootCauseAccount d;
  s.addWait(0, 87, w);
  s.chargeTo(d, 87, RootCause::ScoreboardFull);
  s.finish(d);  // the unloaded access's split waits for the bookings over it
  EXPECT_EQ(d.cycles(), b.cycles());
}

// A refresh is charged what it moved a run by (round configuration, refresh
// windows [1000, 1100) on channel 0: tREFI 1000 ns, tRFC 100 ns at 1 ns a
// cycle). A read of row 0 of bank 0 asked at 900: activate 940, data [962,
// 966). A read of row 1 of bank 0 asked at 900 would precharge at 966 (the
// first one's data), activate 977, column 988, data [999, 1003): it meets
// the window, so it goes after it, on the bank the refresh closed: activate
// 1100, column 1111, data [1122, 1126), done 1126. Its wait: 66 unloaded,
// 160 of queueing: the refresh moved its data from 999 to 1122 (123); where
// it would have gone, it waited 4 for the bus (the first read's data, from
// 940 + tRCD + CL = 962 to 966) and 33 for its bank (966 to 999). (Charged
// from arrival to the window's end, first, the refresh took all 160.)
TEST(RootCauseAccount, RefreshIsChargedWhatItMovedTheRun) {
  DramConfig c = roundDramConfig(1);
  c.trefi_ns = 1000.0;
  c.trfc_ns = 100.0;
  MemorySystem m(c, kRoundMhz);
  ASSERT_EQ(m.access(900, 0, 64, false, Surface::BlendArrays), 966u);
  ASSERT_EQ(m.bankOf(8 * 8192), m.bankOf(0));
  m.resetProbe();
  ASSERT_EQ(m.access(900, 8 * 8192, 64, false, Surface::BlendArrays), 1126u);
  const WaitSplit w = splitWait(900, 1126, m.probe());
  expectEnds(w, 966, 966 + 123, 966 + 123 + 33, 966 + 123 + 33, 1126);
  const RootCauseAccount a = chargedAlone(900, 1126, w);
  EXPECT_EQ(at(a, RootCause::DramLatency), 66u);
  EXPECT_EQ(at(a, RootCause::DramRefresh), 123u);
  EXPECT_EQ(at(a, RootCause::DramBankConflict), 33u);
  EXPECT_EQ(at(a, RootCause::DramBandwidth), 4u);
}

// The final drain is a wait like any other (round configuration): two
// writes to rows 0 and 1 of bank 1 posted at 0 (accepted at 40), drained
// at 40: row 0 activates at 40, data [62, 66); row 1 precharges at 66,
// activates at 77, column 88, data [99, 103): done 103. The batch's parts:
// its data on the bus, 2 x 4, and the second run's bank, 66 to 99: 33. A
// wait from 40: the write's unloaded access, the controller's 40; 23 of
// queueing, 33 / 41 of it the bank's: 18 (floor of 18.5), 5 bandwidth.
// (Before issue 22 s4 all 63 were dram_bandwidth.)
TEST(RootCauseAccount, TheFinalDrainIsSplitByWhatTheDramDid) {
  MemorySystem m(roundDramConfig(1), kRoundMhz);
  ASSERT_EQ(m.bankOf(9 * 8192), m.bankOf(8192));
  ASSERT_NE(m.rowOf(9 * 8192), m.rowOf(8192));
  ASSERT_EQ(m.access(0, 8192, 64, true, Surface::BlendArrays), 40u);
  ASSERT_EQ(m.access(0, 9 * 8192, 64, true, Surface::BlendArrays), 40u);
  m.resetProbe();
  ASSERT_EQ(m.drainWrites(40), 103u);
  EXPECT_EQ(m.probe().done, 103u);
  EXPECT_EQ(m.probe().unloaded, 40u);
  const RootCauseAccount a = chargedAlone(40, 103, splitWait(40, 103, m.probe()));
  EXPECT_EQ(at(a, RootCause::DramLatency), 40u);
  EXPECT_EQ(at(a, RootCause::DramBankConflict), 18u);
  EXPECT_EQ(at(a, RootCause::DramBandwidth), 5u);
}

// A wait the bank's row cycle or the channel's activate limits set is the
// bank's, however busy the bus was meanwhile (closed page, round
// configuration; MEMORY.md "Activate limits"):
//  - tRAS 30: read A of bank 0 asked at 0 activates at 40 (data [62, 66));
//    the bank may activate again at max(66, 40 + 30) + tRP = 81 (its row
//    cycle, not its data). Read B of bank 1 asked at 0: data [66, 70). Read C
//    of bank 0 asked at 0: activate 81, column 92, data [103, 107): 66
//    unloaded, 41 of queueing, all of it the bank's (until this change 8 of
//    it, 62 to 70, were dram_bandwidth: the bus moved A and B meanwhile,
//    though on any bus C's activate waits for tRAS + tRP);
//  - tRRD 4, tFAW 40: reads of banks 0 to 4 asked at 0 activate at 40, 44,
//    48, 52 and 40 + tFAW = 80; the fifth's data [102, 106), done 106: 66
//    unloaded, 40 of queueing, all the bank's (it was 16 of bus, the four
//    reads' data [62, 78), and 24 of bank).
// A read of `addr` asked at 0, done at `done`: 66 cycles unloaded, the rest
// of its queueing the bank's, none the bus's.
void expectQueueingAllTheBanks(MemorySystem& m, uint64_t addr, Cycle done) {
  m.resetProbe();
  ASSERT_EQ(m.access(0, addr, 64, false, Surface::BlendArrays), done);
  const RootCauseAccount a = chargedAlone(0, done, splitWait(0, done, m.probe()));
  EXPECT_EQ(at(a, RootCause::DramLatency), 66u);
  EXPECT_EQ(at(a, RootCause::DramBankConflict), done - 66);
  EXPECT_EQ(at(a, RootCause::DramBandwidth), 0u);
}
TEST(RootCauseAccount, ARowCycleOrActivateLimitWaitIsTheBanksWhateverTheBusMoved) {
  DramConfig c = roundDramConfig(1);
  c.open_row = false;
  c.tras = 30;
  MemorySystem m(c, kRoundMhz);
  ASSERT_NE(m.bankOf(8192), m.bankOf(0));
  ASSERT_EQ(m.bankOf(8 * 8192), m.bankOf(0));
  ASSERT_EQ(m.access(0, 0, 64, false, Surface::BlendArrays), 66u);
  ASSERT_EQ(m.access(0, 8192, 64, false, Surface::BlendArrays), 70u);
  expectQueueingAllTheBanks(m, 8 * 8192, 107);

  c.tras = 0;
  c.trrd = 4;
  c.tfaw = 40;
  MemorySystem n(c, kRoundMhz);
  for (uint64_t bank = 0; bank < 4; ++bank)
    ASSERT_EQ(n.access(0, bank * 8192, 64, false, Surface::BlendArrays), 66u + 4 * bank);
  expectQueueingAllTheBanks(n, 4 * 8192, 106);
}

// A refused access waits for the miss queue's first free entry: the miss
// whose line is ready first at or after it frees (MissWaits), not the latest.
TEST(RootCauseAccount, MissWaitsGiveTheMissThatFreesTheQueue) {
  const WaitSplit w100{10, 20, 30}, w130{11, 21, 31}, w150{12, 22, 32}, fallback{1, 2, 3};
  MissWaits q(2);
  q.add(0, 100, w100);
  EXPECT_EQ(q.freeing(100, fallback), w100);
  q.add(5, 150, w150);
  q.add(7, 130, w130);  // two kept: 100 is forgotten
  EXPECT_EQ(q.freeing(90, fallback), w130);
  EXPECT_EQ(q.freeing(131, fallback), w150);
  EXPECT_EQ(q.freeing(151, fallback), fallback);
  // The miss itself (the approximate engine takes the tail of its wait from when it was asked).
  const MissWait* m = q.freeingMiss(131);
  ASSERT_NE(m, nullptr);
  EXPECT_EQ(m->from, 5u);
  EXPECT_EQ(m->ready, 150u);
  EXPECT_EQ(q.freeingMiss(151), nullptr);
}

}  // namespace
