// lock.mode end to end (cycle engine): the order of each pixel's inserts, and
// so the image, is the submission order (ordered), the lock-entry order
// (unordered) or that of racing read-modify-writes (none, lost updates
// counted); and which fragments the lock scope (granularity, per_primitive)
// orders against which. Hand-built traces with hand-derived timing.
#include <gtest/gtest.h>

#include <cstdlib>

#include "oit_rop/RopTestUtil.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/stages/ShaderInput.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;
using model::testutil::frag;
using model::testutil::kTranspDraw;

namespace {

// One partition, uniform shader latency in [10, 200] from `seed`; the rest
// igpu: input 2/clock, early depth 4, cache hit 10, blend 8 + 2 per row.
RopConfig config(uint64_t seed, LockMode mode, LockGranularity g = LockGranularity::Pixel) {
  RopConfig c;
  c.partitions.count = 1;
  c.input.latency_model = LatencyModel::Uniform;
  c.input.latency_min = 10;
  c.input.latency_max = 200;
  c.input.seed = seed;
  c.lock.mode = mode;
  c.lock.granularity = g;
  c.stats.interval_cycles = 100;
  return c;
}

unsigned latency(uint64_t seed, uint64_t seq) { return ShaderInput(config(seed, LockMode::Ordered).input).latencyOf(seq, 0); }

// The first seed whose two latencies (trace records 0 and 1) satisfy `want`.
template <class F>
uint64_t findSeed(F&& want) {
  for (uint64_t s = 1; s < 100000; ++s)
    if (want(int(latency(s, 0)), int(latency(s, 1)))) return s;
  ADD_FAILURE() << "no seed found";
  return 1;
}

// Two fragments of one pixel (0, 0) of a 2x2 frame (alpha blending: their
// order shows in the colour), rgba8 accumulators (full blend rate, 2/clock).
const Fragment kFirst = frag(0, 0, 0.3f, 1, 0, 0, 0.5f, kTranspDraw, 0);
const Fragment kSecond = frag(0, 0, 0.6f, 0, 1, 0, 0.5f, kTranspDraw, 1);

model::AlgorithmParams rgba8Format() {
  model::AlgorithmParams p;
  p.format = model::StorageFormat::Rgba8T8Z32;
  return p;
}

model::Image functional(const std::vector<Fragment>& fs) {
  return model::testutil::render("alpha", rgba8Format(), fs, 2, 2).image;
}

ChildRun run(const std::vector<Fragment>& fs, const RopConfig& cfg) {
  ChildRun r = runInChild([&] { return timed("alpha", rgba8Format(), fs, 2, 2, cfg); });
  EXPECT_TRUE(r.ok) << r.error;
  return r;
}

uint64_t passEnd(const ChildRun& r) { return r.stats["timing"]["per_partition"][0]["pass_end_cycles"][0]; }
uint64_t lockStat(const ChildRun& r, const char* key) { return r.stats["lock"][key]; }

// Timing of a fragment (hand-derived, as in test_pixel_lock.cpp): both issue
// at cycle 0 (input 2/clock), reach the lock at A = latency + 4 (early depth);
// admitted on arrival, one enters the cache at A + 1, its line is there at
// A + 11 (a clear fill or a hit: 10 cycles) and its blend (8 + 2 x 1 row)
// ends, releasing the lock, at A + 21. One admitted at a release R enters the
// cache in R and releases at R + 20.

// The later-submitted fragment is shaded 30 or more cycles sooner: it is
// done before the other reaches the lock.
TEST(LockModes, ReversedArrivalGivesTheEntryOrdersImage) {
  const uint64_t seed = findSeed([](int l0, int l1) { return l0 - l1 >= 30; });
  const uint64_t a0 = latency(seed, 0) + 4, a1 = latency(seed, 1) + 4;
  const std::vector<Fragment> submitted{kFirst, kSecond}, reversed{kSecond, kFirst};
  ASSERT_NE(functional(submitted).pixels, functional(reversed).pixels);

  // Ordered: the second waits from its arrival until the first released.
  const ChildRun o = run(submitted, config(seed, LockMode::Ordered));
  EXPECT_EQ(o.image.pixels, functional(submitted).pixels);
  EXPECT_EQ(lockStat(o, "conflicts"), 1u);
  EXPECT_EQ(lockStat(o, "wait_cycles"), a0 + 21 - a1);
  EXPECT_EQ(lockStat(o, "out_of_order_entries"), 0u);
  EXPECT_EQ(passEnd(o), a0 + 21 + 20);
  EXPECT_EQ(o.stats["lock"]["mode"], "ordered");

  // Unordered: the second enters on arrival, the first finds the pixel free.
  const ChildRun u = run(submitted, config(seed, LockMode::Unordered));
  EXPECT_EQ(u.image.pixels, functional(reversed).pixels);
  EXPECT_EQ(lockStat(u, "conflicts"), 0u);
  EXPECT_EQ(lockStat(u, "wait_cycles"), 0u);
  EXPECT_EQ(lockStat(u, "out_of_order_entries"), 1u);
  EXPECT_EQ(passEnd(u), a0 + 21);
  EXPECT_EQ(u.counts.stored, 2u);
  EXPECT_TRUE(u.counts.balanced());

  // None: the read-modify-writes do not overlap, nothing is lost.
  const ChildRun n = run(submitted, config(seed, LockMode::None));
  EXPECT_EQ(n.image.pixels, functional(reversed).pixels);
  EXPECT_EQ(lockStat(n, "lost_updates"), 0u);
  EXPECT_EQ(passEnd(n), a0 + 21);
}

// The two reach the lock within 15 cycles, the second-submitted first: with
// no interlock both read the clear array before either writes; the later
// write (the first-submitted, 21 cycles after its arrival) replaces the other's
// update: one lost, the pixel holds the first-submitted fragment alone.
TEST(LockModes, OverlappingReadModifyWritesLoseOneUpdate) {
  const uint64_t seed = findSeed([](int l0, int l1) { return l0 - l1 >= 1 && l0 - l1 <= 15; });
  const uint64_t a0 = latency(seed, 0) + 4, a1 = latency(seed, 1) + 4;
  const std::vector<Fragment> submitted{kFirst, kSecond};

  const ChildRun n = run(submitted, config(seed, LockMode::None));
  EXPECT_EQ(lockStat(n, "lost_updates"), 1u);
  EXPECT_EQ(n.image.pixels, functional({kFirst}).pixels);
  EXPECT_EQ(n.counts.stored, 2u);  // each fragment's insert was its own Stored
  EXPECT_EQ(lockStat(n, "conflicts"), 0u);
  EXPECT_EQ(passEnd(n), a0 + 21);

  // Unordered: the first-submitted waits for the other's release at a1 + 21.
  const ChildRun u = run(submitted, config(seed, LockMode::Unordered));
  EXPECT_EQ(u.image.pixels, functional({kSecond, kFirst}).pixels);
  EXPECT_EQ(lockStat(u, "lost_updates"), 0u);
  EXPECT_EQ(lockStat(u, "conflicts"), 1u);
  EXPECT_EQ(lockStat(u, "wait_cycles"), a1 + 21 - a0);
  EXPECT_EQ(passEnd(u), a1 + 21 + 20);
}

// Lock scope: the address is the pixel, its 2x2 quad or its tile; with
// lock.per_primitive the fragments of one primitive share it. Two fragments
// on different pixels of one quad, the second arriving first (seed of the
// overlap case, so they are in flight together):
//  - pixel: different addresses, nothing orders or excludes them;
//  - quad, two primitives: ordered, the second waits for the first's
//    release although they never touch the same pixel; unordered, the first
//    waits for the second's (exclusion only); none: nothing;
//  - quad, one primitive: they share the lock (no wait), unless
//    per_primitive = false (then as two primitives).
// The image is the same in every case (different pixels).
TEST(LockModes, ScopeDecidesWhichFragmentsAreOrderedAgainstWhich) {
  const uint64_t seed = findSeed([](int l0, int l1) { return l0 - l1 >= 1 && l0 - l1 <= 15; });
  const uint64_t a0 = latency(seed, 0) + 4, a1 = latency(seed, 1) + 4;
  const Fragment right = frag(1, 0, 0.6f, 0, 1, 0, 0.5f, kTranspDraw, 1);
  Fragment right_same_prim = right;
  right_same_prim.prim = 0;
  struct Case {
    const char* what;
    LockGranularity g;
    bool same_primitive, per_primitive;
    LockMode mode;
    uint64_t conflicts, wait;
  };
  for (const Case& c : {Case{"pixel ordered", LockGranularity::Pixel, false, true, LockMode::Ordered, 0, 0},
                        Case{"pixel unordered", LockGranularity::Pixel, false, true, LockMode::Unordered, 0, 0},
                        Case{"quad ordered", LockGranularity::Quad, false, true, LockMode::Ordered, 1, a0 + 21 - a1},
                        Case{"quad unordered", LockGranularity::Quad, false, true, LockMode::Unordered, 1, a1 + 21 - a0},
                        Case{"quad none", LockGranularity::Quad, false, true, LockMode::None, 0, 0},
                        Case{"tile ordered", LockGranularity::Tile, false, true, LockMode::Ordered, 1, a0 + 21 - a1},
                        Case{"quad ordered, one primitive", LockGranularity::Quad, true, true, LockMode::Ordered, 0, 0},
                        Case{"quad unordered, one primitive", LockGranularity::Quad, true, true, LockMode::Unordered, 0, 0},
                        Case{"quad ordered, one primitive, per_primitive off", LockGranularity::Quad, true, false,
                             LockMode::Ordered, 1, a0 + 21 - a1}}) {
    SCOPED_TRACE(c.what);
    RopConfig cfg = config(seed, c.mode, c.g);
    cfg.lock.per_primitive = c.per_primitive;
    const std::vector<Fragment> fs{kFirst, c.same_primitive ? right_same_prim : right};
    const ChildRun r = run(fs, cfg);
    EXPECT_EQ(lockStat(r, "conflicts"), c.conflicts);
    EXPECT_EQ(lockStat(r, "wait_cycles"), c.wait);
    EXPECT_EQ(lockStat(r, "lost_updates"), 0u);  // different pixels never race
    EXPECT_EQ(r.image.pixels, functional(fs).pixels);
  }
}

// With a fixed shader latency fragments reach the lock in submission order,
// so an unordered lock lets each address's fragments in in that order: the
// ordered image, at every granularity (random scene, two partitions).
TEST(LockModes, UnorderedInArrivalOrderEqualsOrderedAtEveryScope) {
  const auto fs = smallScene(32, 32, 8, 11);
  const model::Image ref = model::testutil::render("mlab", {}, fs, 32, 32).image;
  for (LockGranularity g : {LockGranularity::Pixel, LockGranularity::Quad, LockGranularity::Tile}) {
    SCOPED_TRACE(int(g));
    RopConfig cfg = smallConfig();
    cfg.input.latency_model = LatencyModel::Fixed;
    cfg.lock.mode = LockMode::Unordered;
    cfg.lock.granularity = g;
    const ChildRun r = runInChild([&] { return timed("mlab", {}, fs, 32, 32, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_EQ(r.image.pixels, ref.pixels);
    EXPECT_EQ(r.stats["lock"]["out_of_order_entries"].get<uint64_t>(), 0u);
  }
}

// Random latencies on a random scene: the ordered image is the functional one
// at every scope; unordered and none still give every fragment one outcome
// (the same totals: outcomes only move between fragments), none loses updates,
// and none ignores the scope (no lock: the same frame at every granularity).
TEST(LockModes, EveryModeCountsEveryFragmentAndNoneIgnoresTheScope) {
  const auto fs = smallScene(32, 32, 8, 12);
  const model::RenderResult ref = model::testutil::render("mlab", {}, fs, 32, 32);
  nlohmann::json none_pixel;
  for (LockGranularity g : {LockGranularity::Pixel, LockGranularity::Quad, LockGranularity::Tile}) {
    for (LockMode mode : {LockMode::Ordered, LockMode::Unordered, LockMode::None}) {
      SCOPED_TRACE(::testing::Message() << "granularity " << int(g) << " mode " << int(mode));
      RopConfig cfg = smallConfig();
      cfg.lock.mode = mode;
      cfg.lock.granularity = g;
      const ChildRun r = runInChild([&] { return timed("mlab", {}, fs, 32, 32, cfg); });
      ASSERT_TRUE(r.ok) << r.error;
      EXPECT_TRUE(r.counts.balanced());
      EXPECT_EQ(r.counts.fragments_in, ref.counts.fragments_in);
      EXPECT_EQ(r.counts.culled, ref.counts.culled);
      if (mode == LockMode::Ordered) {
        EXPECT_EQ(r.image.pixels, ref.image.pixels);
        EXPECT_EQ(r.counts.stored, ref.counts.stored);
      }
      if (mode != LockMode::None) {
        EXPECT_EQ(r.stats["lock"]["lost_updates"].get<uint64_t>(), 0u);
      } else {
        EXPECT_GT(r.stats["lock"]["lost_updates"].get<uint64_t>(), 0u);
        EXPECT_EQ(r.stats["lock"]["conflicts"].get<uint64_t>(), 0u);
        if (g == LockGranularity::Pixel) {
          none_pixel = r.stats["timing"];
        } else {
          EXPECT_EQ(r.stats["timing"], none_pixel);
        }
      }
    }
  }
}

// The approximate engine refuses the modes it does not model (one line).
TEST(LockModes, ApproximateEngineRefusesUnorderedAndNone) {
  for (LockMode mode : {LockMode::Unordered, LockMode::None}) {
    RopConfig cfg = config(1, mode);
    cfg.sim.engine = SimEngine::Approximate;
    const ChildRun r = runInChild([&] { return timed("alpha", {}, {kFirst}, 2, 2, cfg); });
    EXPECT_FALSE(r.ok);
    EXPECT_EQ(r.error, std::string("timing config: lock.mode=") + lockModeName(mode) +
                           " is not modelled by sim.engine=approximate (it visits fragments in submission order, "
                           "so it cannot apply inserts in lock-entry order or race them); use sim.engine=cycle or "
                           "lock.mode=ordered");
  }
}

}  // namespace
