// The A-buffer's budgets change its image, in the functional model and the
// timing model alike (issue 22: "pool overflow and truncation are the
// functional model's too: it takes the same parameters"): a timing run with a
// pool that overflows, or a local array that truncates, draws exactly the
// functional run's image with the same parameters, on both engines, and counts
// exactly the fragments past the pool as dropped. And the resolve's list walk
// reads the nodes at the addresses their writes went to.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <vector>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

constexpr uint32_t kFrameW = 64, kFrameH = 64;

// The transparent fragments that reach the A-buffer: in front of their pixel's
// nearest opaque fragment (a = 0 included: the A-buffer keeps them).
uint64_t fragmentsInFront(const std::vector<Fragment>& fs) {
  std::vector<float> opaque_z(size_t(kFrameW) * kFrameH, std::numeric_limits<float>::infinity());
  for (const Fragment& f : fs)
    if (f.draw == model::testutil::kOpaqueDraw) opaque_z[f.y * kFrameW + f.x] = std::min(opaque_z[f.y * kFrameW + f.x], f.z);
  uint64_t n = 0;
  for (const Fragment& f : fs) n += f.draw != model::testutil::kOpaqueDraw && f.z < opaque_z[f.y * kFrameW + f.x];
  return n;
}

struct Budget {
  const char* name;
  double nodes_per_pixel;  // 0: unlimited pool
  unsigned max_sorted;     // 0: unlimited local array
  model::StorageFormat format;
};

class AbufferBudgetOn : public ::testing::TestWithParam<SimEngine> {};

// 64x64, depth up to 8: about 18 k fragments reach the A-buffer. A pool of
// 1 node per pixel holds 4096 of them, so every later one is dropped: exactly
// (in front) - 4096. A local array of 2 truncates every pixel deeper than 2.
// Each budget changes the image (it differs from the unlimited A-buffer's),
// and the timing run's image is the functional run's, bit for bit.
TEST_P(AbufferBudgetOn, TimingImageEqualsTheFunctionalImageUnderDropsAndTruncation) {
  const auto fs = smallScene(kFrameW, kFrameH, 8, 31);
  const uint64_t in_front = fragmentsInFront(fs);
  const uint64_t capacity = uint64_t(kFrameW) * kFrameH;  // nodes_per_pixel 1
  ASSERT_GT(in_front, 2 * capacity);           // the pool overflows by more than half
  const auto exact = model::testutil::render("abuffer", model::AlgorithmParams{}, fs, kFrameW, kFrameH);
  for (const Budget& b : {Budget{"pool", 1.0, 0, model::StorageFormat::Fp32},
                          Budget{"truncate", 0.0, 2, model::StorageFormat::Fp32},
                          Budget{"pool+truncate rgba8", 1.0, 2, model::StorageFormat::Rgba8T8Z32}}) {
    SCOPED_TRACE(b.name);
    model::AlgorithmParams p;
    p.format = b.format;
    p.abuffer.nodes_per_pixel = b.nodes_per_pixel;
    p.abuffer.max_sorted = b.max_sorted;
    p.abuffer.overflow = model::ABufferOverflow::Truncate;
    RopConfig cfg = smallConfig();  // the timing model's abuffer.* say the same (the CLI fills both from them)
    cfg.sim.engine = GetParam();
    cfg.abuffer.nodes_per_pixel = b.nodes_per_pixel;
    cfg.abuffer.max_sorted = b.max_sorted ? b.max_sorted : cfg.abuffer.max_sorted;
    cfg.abuffer.overflow = ABufferOverflowPolicy::Truncate;
    const auto functional = model::testutil::render("abuffer", p, fs, kFrameW, kFrameH);
    const auto r = runInChild([&] { return timed("abuffer", p, fs, kFrameW, kFrameH, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_EQ(model::testutil::maxDiff(r.image, functional.image), 0.0);
    EXPECT_GT(model::testutil::maxDiff(r.image, exact.image), 0.0);  // the budget is visible in the image
    const uint64_t dropped = b.nodes_per_pixel > 0 ? in_front - capacity : 0;
    EXPECT_EQ(r.stats["fragments"]["dropped_pool_full"].get<uint64_t>(), dropped);
    EXPECT_EQ(r.counts.discarded, functional.counts.discarded);
    EXPECT_EQ(r.counts.stored, in_front - dropped);
  }
}

INSTANTIATE_TEST_SUITE_P(TimingRun, AbufferBudgetOn, ::testing::ValuesIn(kBothEngines), engineName);

// The walk reads each node where its write put it (NodePool: node i at the
// pool's base + 24 i for fp32 nodes). One partition, one 8x8 tile, one node
// per pixel: 64 x 24 = 1536 B = 24 whole 64 B bursts written into an l2 of
// 1 MiB (write-allocate, whole lines: nothing fetched), so the resolve's 64
// node reads all hit there and no node byte is read from DRAM. (With scattered read addresses, as before, every
// one of the 64 reads missed to DRAM.)
TEST_P(AbufferBudgetOn, TheListWalkReadsTheNodesWhereTheCounterPutThem) {
  const std::vector<Fragment> fs = layerSweeps(8, 8, 1, 0.5f);
  RopConfig cfg = smallConfig();
  cfg.partitions.count = 1;
  cfg.sim.engine = GetParam();
  cfg.l2.size_bytes = 1u << 20;
  ASSERT_EQ(cfg.l2.line_bytes, 64u);
  ASSERT_EQ(cfg.dram.burst_bytes, 64u);
  const auto r = runInChild([&] { return timed("abuffer", model::AlgorithmParams{}, fs, 8, 8, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& m = r.stats["memory"];
  EXPECT_EQ(m["node_pool_bytes_written"].get<uint64_t>(), 64u * 24);
  EXPECT_EQ(m["node_pool_bytes_read"].get<uint64_t>(), 64u * 24);
  EXPECT_EQ(m["dram_read_bytes"]["blend_arrays"].get<uint64_t>(), 0u);
}

// timing.utilization.atomics: the node counter's increments over what it can
// serve in the frame, abuffer.atomics_per_clock x cycles. 64x64 distinct
// pixels, one fragment each (4096 stored nodes), two partitions issuing 2 per
// clock each, a fixed 20-cycle shader, the counter slowed to 0.25 per clock:
// one increment takes 4 cycles of its capacity, so from the first request (at
// 35: shader 20, early depth 4, lock entry 1, cache hit 10) the counter serves
// increment i at 35 + 4 i + 3 (the fragments ask far sooner, about i / 4 + 35),
// the last at 35 + 16 383 = 16 418; its index returns abuffer.atomic_latency
// (100) later and its blend (base 8 + one node moved x 2 = 10 cycles) ends the
// pass at 16 528, in whichever partition took it (the latest pass end).
TEST_P(AbufferBudgetOn, AtomicsUtilizationIsTheCountersShareOfItsRate) {
  const std::vector<Fragment> fs = layerSweeps(64, 64, 1, 0.5f);
  RopConfig cfg = smallConfig();
  cfg.sim.engine = GetParam();
  cfg.input.latency_model = LatencyModel::Fixed;
  cfg.input.latency_min = 20;
  cfg.abuffer.atomics_per_clock = 0.25;
  ASSERT_EQ(cfg.partitions.count, 2u);
  ASSERT_EQ(cfg.abuffer.atomic_latency, 100u);
  ASSERT_EQ(cfg.alu.base_latency + cfg.alu.cycles_per_row_moved, 10u);
  const auto r = runInChild([&] { return timed("abuffer", model::AlgorithmParams{}, fs, 64, 64, cfg); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& t = r.stats["timing"];
  EXPECT_EQ(r.stats["alu"]["node_counter"]["atomics"].get<uint64_t>(), 4096u);
  const double cycles = t["cycles"].get<double>();
  EXPECT_DOUBLE_EQ(t["utilization"]["atomics"].get<double>(), 4096.0 / (0.25 * cycles));
  uint64_t pass_end = 0;
  for (const auto& p : t["per_partition"]) pass_end = std::max(pass_end, p["pass_end_cycles"][0].get<uint64_t>());
  EXPECT_EQ(pass_end, 35u + 4 * 4095 + 3 + 100 + 10);
  // A bounded algorithm has no counter: no atomics entry.
  const auto m = runInChild([&] { return timed("mlab", model::AlgorithmParams{}, fs, 64, 64, cfg); });
  ASSERT_TRUE(m.ok) << m.error;
  EXPECT_FALSE(m.stats["timing"]["utilization"].contains("atomics"));
}

}  // namespace
