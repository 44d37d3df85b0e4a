// PixelLock unit tests (scoreboard semantics, with a random stall injector)
// and end-to-end lock behaviour of the timing model.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "oit_rop/RopTestUtil.hpp"
#include "oit_rop/stages/PixelLock.hpp"

using namespace oit;
using namespace oit::rop;

namespace {

LockConfig lockCfg(unsigned cap, bool ordered, LockGranularity g = LockGranularity::Pixel, bool per_primitive = true) {
  LockConfig c;
  c.capacity = cap;
  c.mode = ordered ? LockMode::Ordered : LockMode::Unordered;
  c.granularity = g;
  c.per_primitive = per_primitive;
  return c;
}

std::vector<uint32_t> drainReady(PixelLock& l, Cycle now) {
  std::vector<uint32_t> v;
  while (l.hasReady()) {
    v.push_back(l.frontReady());
    l.enterFront(now);
  }
  return v;
}

TEST(PixelLock, OrderedAdmitsSameAddressInSubmissionOrder) {
  PixelLock l(lockCfg(8, true));
  const uint32_t t0 = l.allocate(5, 0), t1 = l.allocate(5, 0), t2 = l.allocate(5, 0);  // pixel: owners ignored
  l.arrive(1, t2);  // shaded out of order
  l.arrive(2, t1);
  EXPECT_FALSE(l.hasReady());
  EXPECT_EQ(l.waiting(), 2u);
  l.arrive(3, t0);
  EXPECT_EQ(drainReady(l, 3), std::vector<uint32_t>{t0});
  l.release(10, t0);
  EXPECT_EQ(drainReady(l, 10), std::vector<uint32_t>{t1});
  l.release(20, t1);
  EXPECT_EQ(drainReady(l, 20), std::vector<uint32_t>{t2});
  l.release(30, t2);
  EXPECT_EQ(l.stats().conflicts, 2u);
  EXPECT_EQ(l.stats().wait_cycles, (10u - 2u) + (20u - 1u));
  EXPECT_EQ(l.stats().longest_wait, 19u);
  EXPECT_EQ(l.stats().out_of_order_entries, 0u);
  EXPECT_EQ(l.occupancy(), 0u);
}

TEST(PixelLock, UnorderedIsMutualExclusionAndCountsOutOfOrderEntries) {
  PixelLock l(lockCfg(8, false));
  const uint32_t t0 = l.allocate(7, 0), t1 = l.allocate(7, 1), t2 = l.allocate(7, 2);
  l.arrive(1, t2);
  EXPECT_EQ(drainReady(l, 1), std::vector<uint32_t>{t2});  // enters before older t0, t1
  l.arrive(2, t1);
  l.arrive(3, t0);
  EXPECT_FALSE(l.hasReady());  // t2 inside
  l.release(5, t2);
  EXPECT_EQ(drainReady(l, 5), std::vector<uint32_t>{t0});  // oldest waiting first
  l.release(6, t0);
  EXPECT_EQ(drainReady(l, 6), std::vector<uint32_t>{t1});
  l.release(7, t1);
  EXPECT_EQ(l.stats().out_of_order_entries, 1u);  // t2 only: t0 and t1 entered with no older one in flight
  EXPECT_EQ(l.stats().conflicts, 2u);
}

// No interlock: every arrival enters at once, however many of its address
// are inside; entering before an older fragment of the address is counted.
TEST(PixelLock, NoneAdmitsEveryArrivalAtOnce) {
  LockConfig c = lockCfg(8, true, LockGranularity::Tile);
  c.mode = LockMode::None;
  PixelLock l(c);
  const uint32_t t0 = l.allocate(7, 0), t1 = l.allocate(7, 1), t2 = l.allocate(7, 2);
  l.arrive(1, t2);
  l.arrive(2, t0);
  EXPECT_EQ(drainReady(l, 2), (std::vector<uint32_t>{t2, t0}));  // t2 still inside
  l.arrive(3, t1);
  EXPECT_EQ(drainReady(l, 3), std::vector<uint32_t>{t1});
  EXPECT_EQ(l.waiting(), 0u);
  l.release(4, t0);
  l.release(5, t1);
  l.release(6, t2);
  EXPECT_EQ(l.stats().conflicts, 0u);
  EXPECT_EQ(l.stats().wait_cycles, 0u);
  EXPECT_EQ(l.stats().out_of_order_entries, 2u);  // t2 (t0 and t1 in flight) and t1 (t0 inside)
  EXPECT_EQ(l.occupancy(), 0u);
}

TEST(PixelLock, DistinctAddressesNeverWaitAndCapacityBoundsOccupancy) {
  PixelLock l(lockCfg(4, true));
  std::vector<uint32_t> t;
  for (uint32_t a = 0; a < 4; ++a) t.push_back(l.allocate(a * 977, a));
  EXPECT_TRUE(l.full());
  for (uint32_t i = 4; i-- > 0;) l.arrive(1, t[i]);
  EXPECT_EQ(drainReady(l, 1).size(), 4u);
  EXPECT_EQ(l.stats().conflicts, 0u);
  l.release(2, t[1]);
  EXPECT_FALSE(l.full());
  EXPECT_EQ(l.stats().peak_occupancy, 4u);
}

TEST(PixelLock, DroppedFragmentUnblocksItsSuccessor) {
  PixelLock l(lockCfg(4, true));
  const uint32_t culled = l.allocate(3, 0), next = l.allocate(3, 1);
  l.arrive(4, next);
  EXPECT_FALSE(l.hasReady());
  l.drop(9, culled);  // early depth culled the older fragment
  EXPECT_EQ(drainReady(l, 9), std::vector<uint32_t>{next});
  EXPECT_EQ(l.stats().wait_cycles, 5u);
}

// Quad/tile granularity with lock.per_primitive: fragments of one owner (a
// primitive's run) share the address; the next owner waits for all of them.
TEST(PixelLock, OrderedGroupedOwnersEnterTogether) {
  PixelLock l(lockCfg(8, true, LockGranularity::Quad));
  ASSERT_TRUE(l.grouped());
  const uint32_t a0 = l.allocate(5, 10), a1 = l.allocate(5, 10), b0 = l.allocate(5, 12), b1 = l.allocate(5, 12);
  l.arrive(1, a1);  // before the older a0 arrived: same primitive, no wait
  EXPECT_EQ(drainReady(l, 1), std::vector<uint32_t>{a1});
  l.arrive(2, b1);
  l.arrive(3, b0);
  EXPECT_FALSE(l.hasReady());
  l.release(4, a1);
  EXPECT_FALSE(l.hasReady());  // a0 of the older primitive is still in flight
  l.arrive(5, a0);
  EXPECT_EQ(drainReady(l, 5), std::vector<uint32_t>{a0});
  l.release(9, a0);
  EXPECT_EQ(drainReady(l, 9), (std::vector<uint32_t>{b0, b1}));  // the whole next primitive, oldest first
  l.release(10, b1);
  l.release(11, b0);
  EXPECT_EQ(l.stats().conflicts, 2u);
  EXPECT_EQ(l.stats().wait_cycles, (9u - 2u) + (9u - 3u));
  EXPECT_EQ(l.stats().out_of_order_entries, 0u);
  EXPECT_EQ(l.occupancy(), 0u);
}

TEST(PixelLock, UngroupedQuadAndPixelGranularityIgnoreOwners) {
  for (const LockConfig& c : {lockCfg(8, true, LockGranularity::Quad, false), lockCfg(8, true, LockGranularity::Pixel)}) {
    PixelLock l(c);
    EXPECT_FALSE(l.grouped());
    const uint32_t a0 = l.allocate(5, 10), a1 = l.allocate(5, 10);
    l.arrive(1, a1);
    EXPECT_FALSE(l.hasReady());  // waits for a0 though it is of the same primitive
    l.arrive(2, a0);
    EXPECT_EQ(drainReady(l, 2), std::vector<uint32_t>{a0});
    l.release(6, a0);
    EXPECT_EQ(drainReady(l, 6), std::vector<uint32_t>{a1});
    EXPECT_EQ(l.stats().conflicts, 1u);
    EXPECT_EQ(l.stats().wait_cycles, 5u);
  }
}

TEST(PixelLock, UnorderedGroupedOwnersShareTheAddress) {
  PixelLock l(lockCfg(8, false, LockGranularity::Tile));
  const uint32_t a0 = l.allocate(7, 1), a1 = l.allocate(7, 1), b0 = l.allocate(7, 3);
  l.arrive(1, b0);
  EXPECT_EQ(drainReady(l, 1), std::vector<uint32_t>{b0});  // out of order: a0, a1 older
  l.arrive(2, a0);
  l.arrive(3, a1);
  EXPECT_FALSE(l.hasReady());  // another owner inside
  l.release(6, b0);
  EXPECT_EQ(drainReady(l, 6), (std::vector<uint32_t>{a0, a1}));
  const uint32_t a2 = l.allocate(7, 1);  // a later fragment of the owner inside joins it
  l.arrive(7, a2);
  EXPECT_EQ(drainReady(l, 7), std::vector<uint32_t>{a2});
  l.release(8, a0);
  l.release(8, a1);
  l.release(9, a2);
  EXPECT_EQ(l.stats().conflicts, 2u);
  EXPECT_EQ(l.stats().wait_cycles, (6u - 2u) + (6u - 3u));
  EXPECT_EQ(l.stats().out_of_order_entries, 1u);  // b0 only
  EXPECT_EQ(l.occupancy(), 0u);
}

// Random stall injector: random addresses, owners (primitive runs), shader
// latencies and blend times; checks the interlock's invariants every cycle:
// inside an address only one owner; ordered: a fragment enters only when no
// older fragment of its address and of another owner is in flight.
TEST(PixelLock, RandomTrafficKeepsInvariants) {
  for (const bool grouped : {false, true})
    for (const bool ordered : {true, false}) {
      SCOPED_TRACE(::testing::Message() << "grouped " << grouped << " ordered " << ordered);
      std::mt19937 rng((ordered ? 1 : 2) + (grouped ? 10 : 0));
      PixelLock l(lockCfg(32, ordered, grouped ? LockGranularity::Quad : LockGranularity::Pixel));
      ASSERT_EQ(l.grouped(), grouped);
      std::map<uint32_t, uint32_t> addr_of, owner_of;  // token -> address, owner
      std::map<uint32_t, uint64_t> seq_of;              // token -> submission index
      std::multimap<Cycle, uint32_t> arrive_at, release_at;
      std::map<uint32_t, std::set<uint32_t>> in_flight;  // address -> tokens allocated, not released
      std::map<uint32_t, std::set<uint32_t>> inside;     // address -> tokens entered, not released
      uint64_t seq = 0, released = 0, shared_entries = 0;
      uint32_t run = 0;
      const uint64_t total = 3000;
      for (Cycle now = 0; released < total; ++now) {
        for (auto it = release_at.begin(); it != release_at.end() && it->first <= now; it = release_at.erase(it)) {
          const uint32_t t = it->second;
          inside[addr_of[t]].erase(t);
          in_flight[addr_of[t]].erase(t);
          l.release(now, t);
          ++released;
        }
        for (auto it = arrive_at.begin(); it != arrive_at.end() && it->first <= now; it = arrive_at.erase(it))
          l.arrive(now, it->second);
        while (l.hasReady() && rng() % 4 != 0) {  // stall injector on the consumer
          const uint32_t t = l.frontReady();
          l.enterFront(now);
          const uint32_t a = addr_of[t];
          for (uint32_t o : inside[a]) {
            ASSERT_TRUE(grouped && owner_of[o] == owner_of[t]) << "two owners inside address " << a;
            ++shared_entries;
          }
          if (ordered) {
            for (uint32_t o : in_flight[a])
              if (seq_of[o] < seq_of[t]) {
                ASSERT_TRUE(grouped && owner_of[o] == owner_of[t]) << "ordered lock out of submission order";
              }
          }
          inside[a].insert(t);
          release_at.emplace(now + 1 + rng() % 12, t);
        }
        if (seq < total && !l.full() && rng() % 2) {
          const uint32_t a = uint32_t(rng() % 6) * 1000003u;  // few hot addresses
          if (rng() % 3 == 0) run = uint32_t(seq);                  // a new primitive starts
          const uint32_t t = l.allocate(a, run);
          addr_of[t] = a;
          owner_of[t] = run;
          seq_of[t] = seq++;
          in_flight[a].insert(t);
          arrive_at.emplace(now + 1 + rng() % 30, t);
        }
        ASSERT_LT(now, 1000000u);
      }
      EXPECT_EQ(l.occupancy(), 0u);
      EXPECT_EQ(l.stats().entries, total);
      EXPECT_GT(l.stats().conflicts, 0u);
      if (grouped) {
        EXPECT_GT(shared_entries, 0u);  // owners did share addresses
      }
      if (ordered) {
        EXPECT_EQ(l.stats().out_of_order_entries, 0u);
      } else {
        EXPECT_GT(l.stats().out_of_order_entries, 0u);
      }
    }
}

// ---- End to end: the lock in the timing model ----
using namespace oit::rop::testutil;

RopConfig onePartition(SimEngine engine = SimEngine::CycleStepped) {
  RopConfig c = smallConfig();
  c.partitions.count = 1;
  c.input.latency_model = LatencyModel::Fixed;
  c.input.latency_min = 20;
  c.sim.engine = engine;
  return c;
}

// The analytic lock expectations hold for both engines: the cycle
// engine and the approximate one give the same, hand-derived figures.
class PixelLockTimingOn : public ::testing::TestWithParam<SimEngine> {};

// N fragments to one pixel, N <= the scoreboard's capacity (all issue at the
// input rate, 2/clk): fragment i issues at floor(i/2) and reaches the lock at
// floor(i/2) + 24 (fixed shader 20, early depth 4). The first is admitted at
// once, enters the cache a cycle later and releases at 45 (hit 10, blend 8 +
// 2 x 1 row); each waiter is admitted at its predecessor's release, enters the
// cache in that cycle and holds the lock L = hit + base + row = 20 cycles:
// fragment i >= 1 is admitted at 45 + (i - 1) L, and the pass ends at
// 45 + (N - 1) L.
//  wait_cycles = sum over i = 1 .. N-1 of 45 + (i - 1) L - (floor(i/2) + 24)
//              = 388 299 for N = 200.
//  pixel_lock's lock_wait: from cycle 24 (fragment 1 waits) to the last
//  admission at 45 + (N - 2) L, less cycle 25 and the N - 2 earlier admission
//  cycles (busy: a fragment entered): 21 + (N - 2) L - 1 - (N - 2).
TEST_P(PixelLockTimingOn, FragmentsToOnePixelSerialiseAtTheBlendLatency) {
  constexpr uint64_t N = 200;
  std::vector<Fragment> fs;
  for (unsigned i = 0; i < N; ++i) fs.push_back(model::testutil::frag(3, 3, 0.001f * i, 1, 0, 0, 0.5f));
  const RopConfig cfg = onePartition(GetParam());
  ASSERT_LE(N, cfg.lock.capacity);
  ASSERT_EQ(cfg.input.fragments_per_clock, 2.0);
  // alpha: one accumulator "row"; each insert is Stored: 1 row.
  const uint64_t L = cfg.cache.hit_latency + cfg.alu.base_latency + cfg.alu.cycles_per_row_moved * 1;  // alpha: one accumulator written, no compare
  ASSERT_EQ(L, 20u);
  uint64_t wait = 0;
  for (uint64_t i = 1; i < N; ++i) wait += 45 + (i - 1) * L - (i / 2 + 24);
  ASSERT_EQ(wait, 388299u);
  const auto r = runInChild([&] { return timed("alpha", {}, fs, 16, 16, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& part = r.stats["timing"]["per_partition"][0];
  const uint64_t pass = part["pass_end_cycles"][0].get<uint64_t>() - part["opaque_end_cycle"].get<uint64_t>();
  EXPECT_EQ(pass, 45 + (N - 1) * L);
  EXPECT_EQ(r.stats["lock"]["conflicts"].get<uint64_t>(), N - 1);  // with 20-cycle shader, all but the first wait
  EXPECT_EQ(r.stats["lock"]["wait_cycles"].get<uint64_t>(), wait);
  EXPECT_EQ(r.stats["lock"]["longest_wait"].get<uint64_t>(), 45 + (N - 2) * L - ((N - 1) / 2 + 24));
  const uint64_t lock_wait = r.stats["timing"]["stages"]["pixel_lock"]["stalls"]["lock_wait"];
  EXPECT_EQ(lock_wait, 21 + (N - 2) * L - 1 - (N - 2));
}

TEST_P(PixelLockTimingOn, DistinctPixelsRunAtTheInputRateWithoutLockWaits) {
  std::vector<Fragment> fs;
  for (uint16_t y = 0; y < 64; ++y)
    for (uint16_t x = 0; x < 64; ++x) fs.push_back(model::testutil::frag(x, y, 0.5f, 0, 1, 0, 0.5f));
  RopConfig cfg = onePartition(GetParam());
  cfg.cache.size_bytes = 1u << 20;  // every tile's line fits: only clear fills
  model::AlgorithmParams p;
  p.format = model::StorageFormat::Rgba8T8Z32;  // full ALU rate: 2 blends/clock = input rate
  const auto r = runInChild([&] { return timed("mlab", p, fs, 64, 64, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& part = r.stats["timing"]["per_partition"][0];
  const double pass = part["pass_end_cycles"][0].get<double>() - part["opaque_end_cycle"].get<double>();
  const double ideal = 4096.0 / cfg.input.fragments_per_clock;
  EXPECT_GE(pass, ideal);
  EXPECT_LE(pass, ideal * 1.05 + 100);
  EXPECT_EQ(r.stats["lock"]["wait_cycles"].get<uint64_t>(), 0u);
  EXPECT_EQ(r.stats["lock"]["conflicts"].get<uint64_t>(), 0u);
  EXPECT_EQ(r.stats["cache"]["misses"].get<uint64_t>(), r.stats["cache"]["clear_fills"].get<uint64_t>());
}

// The lock address follows lock.granularity. One 8x8 tile, one fragment per
// pixel in raster order (64), one partition, fixed 20-cycle shader, input
// 2/clk, mlab (k = 4) into empty arrays: each insert compares one row and
// writes one (InsertWork {1, 1}). Fragment k issues at floor(k/2), reaches the
// lock at floor(k/2) + 24 (shader 20 + early depth 4) and, admitted at once,
// releases at floor(k/2) + 46 (enter the cache 1 cycle later, hit 10, blend
// 8 + 1 compare + 2 x 1 row). A waiter admitted at a release enters the cache
// in that cycle and holds the lock H = hit 10 + 8 + 1 + 2 = 21 cycles.
//  - pixel: no two fragments share an address: 0 conflicts; the pass ends with
//    the last release, 31 + 46 = 77.
//  - quad: 16 quads of 4; (x, y) and (x+1, y) issue together, the row below
//    4 cycles later, all within the first one's hold: 3 conflicts per quad, 48;
//    a quad issued at c releases at c + 46, 67, 88, 109; the last quad's first
//    fragment (6, 6) issues at 27: the pass ends at 27 + 109 = 136. Waits per
//    quad: 46 - 24, 67 - 28, 88 - 28 = 22 + 39 + 60.
//  - tile: every fragment but the first waits: 63 conflicts; releases at
//    46 + 21 j for the j-th; the pass ends at 46 + 63 x 21 = 1369; fragment k
//    (k >= 1) waits from floor(k/2) + 24 to 46 + 21 (k - 1).
// Each fragment is its own primitive here. When all 64 are one primitive,
// lock.per_primitive lets them hold the quad/tile lock together: the pixel
// case's figures at every granularity; without it, the figures above again.
// The approximate engine gives these figures too (since it hands out blend
// slots by time; in visit order the quads after a waiter queued behind its
// late blend: pass 685, waits 14,792; DESIGN.md).
TEST_P(PixelLockTimingOn, GranularitySetsTheLockAddressOfOneTile) {
  std::vector<Fragment> fs, one_prim;
  for (uint16_t y = 0; y < 8; ++y)
    for (uint16_t x = 0; x < 8; ++x) {
      fs.push_back(model::testutil::frag(x, y, 0.5f, 1, 0, 0, 0.5f, model::testutil::kTranspDraw, y * 8u + x));
      one_prim.push_back(model::testutil::frag(x, y, 0.5f, 1, 0, 0, 0.5f, model::testutil::kTranspDraw, 7));
    }
  RopConfig base = onePartition(GetParam());
  ASSERT_EQ(base.partitions.tile_width, 8u);
  ASSERT_EQ(base.partitions.tile_height, 8u);
  ASSERT_EQ(base.input.fragments_per_clock, 2.0);
  const uint64_t H =
      base.cache.hit_latency + base.alu.base_latency + base.alu.cycles_per_compare + base.alu.cycles_per_row_moved;
  ASSERT_EQ(H, 21u);
  uint64_t tile_wait = 0;
  for (uint64_t k = 1; k < 64; ++k) tile_wait += 46 + H * (k - 1) - (k / 2 + 24);
  struct Case {
    LockGranularity g;
    bool one_primitive, per_primitive;
    uint64_t conflicts, pass, wait;
  };
  const uint64_t quad_wait = 16 * (22 + 39 + 60);
  for (const Case& c : {Case{LockGranularity::Pixel, false, true, 0, 77, 0},
                        Case{LockGranularity::Quad, false, true, 48, 136, quad_wait},
                        Case{LockGranularity::Tile, false, true, 63, 46 + 63 * H, tile_wait},
                        Case{LockGranularity::Pixel, true, true, 0, 77, 0},
                        Case{LockGranularity::Quad, true, true, 0, 77, 0},
                        Case{LockGranularity::Tile, true, true, 0, 77, 0},
                        Case{LockGranularity::Quad, true, false, 48, 136, quad_wait},
                        Case{LockGranularity::Tile, true, false, 63, 46 + 63 * H, tile_wait}}) {
    SCOPED_TRACE(::testing::Message() << "granularity " << int(c.g) << " one primitive " << c.one_primitive
                                      << " per_primitive " << c.per_primitive);
    RopConfig cfg = base;
    cfg.lock.granularity = c.g;
    cfg.lock.per_primitive = c.per_primitive;
    model::AlgorithmParams p;
    p.format = model::StorageFormat::Rgba8T8Z32;
    const auto r = runInChild([&] { return timed("mlab", p, c.one_primitive ? one_prim : fs, 8, 8, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    const auto& part = r.stats["timing"]["per_partition"][0];
    EXPECT_EQ(part["opaque_end_cycle"].get<uint64_t>(), 0u);
    EXPECT_EQ(part["pass_end_cycles"][0].get<uint64_t>(), c.pass);
    EXPECT_EQ(r.stats["lock"]["conflicts"].get<uint64_t>(), c.conflicts);
    EXPECT_EQ(r.stats["lock"]["wait_cycles"].get<uint64_t>(), c.wait);
  }
}

// A random scene: coarser addresses strictly raise the waits here (the scene
// has many fragments per pixel, quad and tile in flight together).
TEST_P(PixelLockTimingOn, CoarserGranularityRaisesLockWaits) {
  const auto fs = smallScene(32, 32, 6, 4);
  uint64_t prev = 0;
  for (LockGranularity g : {LockGranularity::Pixel, LockGranularity::Quad, LockGranularity::Tile}) {
    RopConfig cfg = smallConfig();
    cfg.sim.engine = GetParam();
    cfg.lock.granularity = g;
    model::AlgorithmParams p;
    p.format = model::StorageFormat::Rgba8T8Z32;
    const auto r = runInChild([&] { return timed("mlab", p, fs, 32, 32, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    const uint64_t w = r.stats["lock"]["wait_cycles"];
    EXPECT_GT(w, prev) << int(g);
    prev = w;
  }
}

INSTANTIATE_TEST_SUITE_P(PixelLockTiming, PixelLockTimingOn, ::testing::ValuesIn(kBothEngines), engineName);

// The unordered interlock admits a fragment while an older one of its pixel is
// still in flight; every fragment still ends in one counted outcome (decided
// at its lock entry; test_lock_modes.cpp checks the images).
TEST(PixelLockTiming, UnorderedLockCountsOutOfOrderEntries) {
  const auto fs = smallScene(32, 32, 8, 6);
  RopConfig cfg = smallConfig();
  cfg.lock.mode = LockMode::Unordered;
  const auto r = runInChild([&] { return timed("mlab", {}, fs, 32, 32, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_GT(r.stats["lock"]["out_of_order_entries"].get<uint64_t>(), 0u);
  EXPECT_TRUE(r.counts.balanced());
  EXPECT_EQ(r.stats["lock"]["mode"], "unordered");
}

}  // namespace
