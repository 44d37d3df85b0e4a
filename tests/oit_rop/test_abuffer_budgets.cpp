// The A-buffer's budgets change its image, in the functional model and the
// timing model alike (issue 22: "pool overflow and truncation are the
// functional model's too: it takes the same parameters"): a timing run with a
// pool that overflows, or a local array that truncates, draws exactly the
// functional run's image with the same parameters, on both engines, and counts
// exactly the fragments past the pool as dropped.
#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <vector>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

constexpr uint32_t W = 64, H = 64;

bool sameBits(const model::Image& a, const model::Image& b) {
  return a.width == b.width && a.height == b.height &&
         std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(model::Rgb)) == 0;
}

// The transparent fragments that reach the A-buffer: in front of their pixel's
// nearest opaque fragment (a = 0 included: the A-buffer keeps them).
uint64_t fragmentsInFront(const std::vector<Fragment>& fs) {
  std::vector<float> opaque_z(size_t(W) * H, std::numeric_limits<float>::infinity());
  for (const Fragment& f : fs)
    if (f.draw == model::testutil::kOpaqueDraw) opaque_z[f.y * W + f.x] = std::min(opaque_z[f.y * W + f.x], f.z);
  uint64_t n = 0;
  for (const Fragment& f : fs) n += f.draw != model::testutil::kOpaqueDraw && f.z < opaque_z[f.y * W + f.x];
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
  const auto fs = smallScene(W, H, 8, 31);
  const uint64_t in_front = fragmentsInFront(fs);
  const uint64_t capacity = uint64_t(W) * H;  // nodes_per_pixel 1
  ASSERT_GT(in_front, 2 * capacity);           // the pool overflows by more than half
  const auto exact = model::testutil::render("abuffer", model::AlgorithmParams{}, fs, W, H);
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
    const auto functional = model::testutil::render("abuffer", p, fs, W, H);
    const auto r = runInChild([&] { return timed("abuffer", p, fs, W, H, cfg); });
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_TRUE(sameBits(r.image, functional.image));
    EXPECT_FALSE(sameBits(r.image, exact.image));  // the budget is visible in the image
    const uint64_t dropped = b.nodes_per_pixel > 0 ? in_front - capacity : 0;
    EXPECT_EQ(r.stats["fragments"]["dropped_pool_full"].get<uint64_t>(), dropped);
    EXPECT_EQ(r.counts.discarded, functional.counts.discarded);
    EXPECT_EQ(r.counts.stored, in_front - dropped);
  }
}

INSTANTIATE_TEST_SUITE_P(TimingRun, AbufferBudgetOn, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
