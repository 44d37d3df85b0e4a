// PixelLock unit tests (scoreboard semantics, with a random stall injector)
// and end-to-end lock behaviour of the timing model.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "RopTestUtil.hpp"
#include "oit_rop/PixelLock.hpp"

using namespace oit;
using namespace oit::rop;

namespace {

LockConfig lockCfg(unsigned cap, bool ordered) {
  LockConfig c;
  c.capacity = cap;
  c.ordered = ordered;
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
  PixelLock l(lockCfg(8, true), 64);
  const uint32_t t0 = l.allocate(5), t1 = l.allocate(5), t2 = l.allocate(5);
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
  PixelLock l(lockCfg(8, false), 64);
  const uint32_t t0 = l.allocate(7), t1 = l.allocate(7), t2 = l.allocate(7);
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

TEST(PixelLock, DistinctAddressesNeverWaitAndCapacityBoundsOccupancy) {
  PixelLock l(lockCfg(4, true), 64);
  std::vector<uint32_t> t;
  for (uint32_t a = 0; a < 4; ++a) t.push_back(l.allocate(a * 977));
  EXPECT_TRUE(l.full());
  for (uint32_t i = 4; i-- > 0;) l.arrive(1, t[i]);
  EXPECT_EQ(drainReady(l, 1).size(), 4u);
  EXPECT_EQ(l.stats().conflicts, 0u);
  l.release(2, t[1]);
  EXPECT_FALSE(l.full());
  EXPECT_EQ(l.stats().peak_occupancy, 4u);
}

TEST(PixelLock, DroppedFragmentUnblocksItsSuccessor) {
  PixelLock l(lockCfg(4, true), 64);
  const uint32_t culled = l.allocate(3), next = l.allocate(3);
  l.arrive(4, next);
  EXPECT_FALSE(l.hasReady());
  l.drop(9, culled);  // early depth culled the older fragment
  EXPECT_EQ(drainReady(l, 9), std::vector<uint32_t>{next});
  EXPECT_EQ(l.stats().wait_cycles, 5u);
}

TEST(PixelLock, GranularityAddresses) {
  LockConfig c = lockCfg(4, true);
  c.granularity = LockGranularity::Quad;
  PixelLock quad(c, 10);
  EXPECT_EQ(quad.address(0, 0, 8, 8), quad.address(1, 1, 8, 8));
  EXPECT_NE(quad.address(1, 1, 8, 8), quad.address(2, 1, 8, 8));
  EXPECT_EQ(quad.address(9, 3, 8, 8), 1u * 5 + 4);
  c.granularity = LockGranularity::Tile;
  PixelLock tile(c, 20);
  EXPECT_EQ(tile.address(7, 7, 8, 8), 0u);
  EXPECT_EQ(tile.address(8, 0, 8, 8), 1u);
  EXPECT_EQ(tile.address(0, 8, 8, 8), 3u);  // 3 tiles per row of 20 pixels
  c.granularity = LockGranularity::Pixel;
  PixelLock px(c, 20);
  EXPECT_EQ(px.address(3, 2, 8, 8), 43u);
}

// Random stall injector: random addresses, shader latencies and blend times;
// checks the interlock's invariants every cycle.
TEST(PixelLock, RandomTrafficKeepsInvariants) {
  for (bool ordered : {true, false}) {
    std::mt19937 rng(ordered ? 1 : 2);
    PixelLock l(lockCfg(32, ordered), 64);
    std::map<uint32_t, uint32_t> addr_of;   // token -> address
    std::map<uint32_t, uint64_t> seq_of;    // token -> submission index
    std::multimap<Cycle, uint32_t> arrive_at, release_at;
    std::map<uint32_t, uint64_t> last_entered;  // address -> seq of the last entry
    std::map<uint32_t, int> inside;
    uint64_t seq = 0, released = 0;
    const uint64_t total = 3000;
    for (Cycle now = 0; released < total; ++now) {
      for (auto it = release_at.begin(); it != release_at.end() && it->first <= now; it = release_at.erase(it)) {
        --inside[addr_of[it->second]];
        l.release(now, it->second);
        ++released;
      }
      for (auto it = arrive_at.begin(); it != arrive_at.end() && it->first <= now; it = arrive_at.erase(it))
        l.arrive(now, it->second);
      while (l.hasReady() && rng() % 4 != 0) {  // stall injector on the consumer
        const uint32_t t = l.frontReady();
        l.enterFront(now);
        const uint32_t a = addr_of[t];
        ASSERT_EQ(inside[a]++, 0) << "two fragments inside address " << a;
        if (ordered) {
          auto le = last_entered.find(a);
          if (le != last_entered.end()) {
            ASSERT_LT(le->second, seq_of[t]) << "ordered lock out of submission order";
          }
          last_entered[a] = seq_of[t];
        }
        release_at.emplace(now + 1 + rng() % 12, t);
      }
      if (seq < total && !l.full() && rng() % 2) {
        const uint32_t a = uint32_t(rng() % 6) * 1000003u;  // few hot addresses, colliding hashes
        const uint32_t t = l.allocate(a);
        addr_of[t] = a;
        seq_of[t] = seq++;
        arrive_at.emplace(now + 1 + rng() % 30, t);
      }
      ASSERT_LT(now, 1000000u);
    }
    EXPECT_EQ(l.occupancy(), 0u);
    EXPECT_EQ(l.stats().entries, total);
    EXPECT_GT(l.stats().conflicts, 0u);
    if (ordered) EXPECT_EQ(l.stats().out_of_order_entries, 0u);
    else EXPECT_GT(l.stats().out_of_order_entries, 0u);
  }
}

// ---- End to end: the lock in the timing model ----
using namespace oit::rop::testutil;

RopConfig onePartition() {
  RopConfig c = smallConfig();
  c.partitions.count = 1;
  c.input.latency_model = LatencyModel::Fixed;
  c.input.latency_min = 20;
  return c;
}

TEST(PixelLockTiming, FragmentsToOnePixelSerialiseAtTheBlendLatency) {
  constexpr unsigned N = 300;
  std::vector<Fragment> fs;
  for (unsigned i = 0; i < N; ++i) fs.push_back(model::testutil::frag(3, 3, 0.001f * i, 1, 0, 0, 0.5f));
  const RopConfig cfg = onePartition();
  // alpha: one accumulator "row"; each insert is Stored: 1 row.
  const uint64_t L = cfg.cache.hit_latency + cfg.alu.base_latency + cfg.alu.row_latency * 1;
  const auto r = runInChild([&] { return timed("alpha", {}, fs, 16, 16, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& part = r.stats["timing"]["per_partition"][0];
  const uint64_t pass = part["pass_end_cycles"][0].get<uint64_t>() - part["opaque_end_cycle"].get<uint64_t>();
  EXPECT_GE(pass, N * L);
  EXPECT_LE(pass, N * L + 200);  // + shader latency and pipeline fill
  EXPECT_EQ(r.stats["lock"]["conflicts"].get<uint64_t>(), N - 1);  // with 20-cycle shader, all but the first wait
  EXPECT_GT(r.stats["lock"]["wait_cycles"].get<uint64_t>(), uint64_t(N) * N * L / 4);
  EXPECT_GE(r.stats["timing"]["stages"]["pixel_lock"]["stalls"]["lock_wait"].get<uint64_t>(), (N - 1) * L * 9 / 10);
}

TEST(PixelLockTiming, DistinctPixelsRunAtTheInputRateWithoutLockWaits) {
  std::vector<Fragment> fs;
  for (uint16_t y = 0; y < 64; ++y)
    for (uint16_t x = 0; x < 64; ++x) fs.push_back(model::testutil::frag(x, y, 0.5f, 0, 1, 0, 0.5f));
  RopConfig cfg = onePartition();
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

TEST(PixelLockTiming, CoarserGranularityNeverLowersLockWaits) {
  const auto fs = smallScene(32, 32, 6, 4);
  uint64_t prev = 0;
  for (LockGranularity g : {LockGranularity::Pixel, LockGranularity::Quad, LockGranularity::Tile}) {
    RopConfig cfg = smallConfig();
    cfg.lock.granularity = g;
    model::AlgorithmParams p;
    p.format = model::StorageFormat::Rgba8T8Z32;
    const auto r = runInChild([&] { return timed("mlab", p, fs, 32, 32, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    const uint64_t w = r.stats["lock"]["wait_cycles"];
    EXPECT_GE(w, prev) << int(g);
    prev = w;
  }
  EXPECT_GT(prev, 0u);
}

TEST(PixelLockTiming, UnorderedLockCountsOutOfOrderEntriesAndKeepsTheImage) {
  const auto fs = smallScene(32, 32, 8, 6);
  RopConfig cfg = smallConfig();
  cfg.lock.ordered = false;
  const auto ref = model::testutil::render("mlab", {}, fs, 32, 32);
  const auto r = runInChild([&] { return timed("mlab", {}, fs, 32, 32, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_GT(r.stats["lock"]["out_of_order_entries"].get<uint64_t>(), 0u);
  EXPECT_EQ(std::memcmp(r.image.pixels.data(), ref.image.pixels.data(), r.image.pixels.size() * sizeof(model::Rgb)), 0);
}

}  // namespace
