// The binary reader's resident memory stays bounded whatever the trace size:
// a trace several times the budget is streamed batch by batch while the
// resident set size is sampled after every batch.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "test_format_helpers.hpp"
#include "traces/ResidentMemory.hpp"
#include "traces/TraceIO.hpp"

namespace oit::test {
namespace {

constexpr uint32_t kFullHdW = 1920, kFullHdH = 1080;

Fragment fragmentAt(uint64_t i) {
  return Fragment{static_cast<uint16_t>(i % kFullHdW), static_cast<uint16_t>((i / kFullHdW) % kFullHdH),
                  static_cast<float>(i % 1000) / 1000.0f, 0.25f, 0.5f, 0.75f, 0.5f,
                  static_cast<uint32_t>(i), static_cast<uint32_t>(i % 3)};
}

void streamWithinBudget(ColourEncoding enc, uint64_t file_bytes) {
  constexpr uint64_t kBudget = 48ull << 20;
  const uint64_t record_bytes = enc == ColourEncoding::Fp32 ? 32 : 20;
  const uint64_t count = file_bytes / record_bytes;
  TempDir dir;
  const std::string p = dir.path("big.oitt");
  {
    auto w = createTraceWriter(p, makeHeader(kFullHdW, kFullHdH, enc,
                                             {{0, DrawClass::Opaque, "a"},
                                              {1, DrawClass::Transparent, "b"},
                                              {2, DrawClass::Transparent, "c"}}));
    std::vector<Fragment> chunk(1 << 16);
    for (uint64_t base = 0; base < count; base += chunk.size()) {
      const size_t n = static_cast<size_t>(std::min<uint64_t>(chunk.size(), count - base));
      for (size_t k = 0; k < n; ++k) chunk[k] = fragmentAt(base + k);
      w->write(std::span<const Fragment>(chunk.data(), n));
    }
    w->commit();
  }
  ASSERT_GT(std::filesystem::file_size(p), 4 * kBudget);  // the test means something

  auto src = openTrace(p, {.batch_records = 1 << 16});
  const uint64_t baseline = residentBytes();
  ASSERT_GT(baseline, 0u);
  uint64_t peak = baseline, seen = 0, mismatches = 0;
  for (auto b = src->next(); !b.empty(); b = src->next()) {
    // Spot-check content so the loop really reads what was written.
    const Fragment want = fragmentAt(seen + b.size() - 1);
    if (b.back().prim != want.prim || b.back().x != want.x || b.back().z != want.z) ++mismatches;
    seen += b.size();
    peak = std::max(peak, residentBytes());
  }
  ::testing::Test::RecordProperty("peak_rss_growth_kib", std::to_string((peak - baseline) >> 10));
  EXPECT_EQ(seen, count);
  EXPECT_EQ(mismatches, 0u);
  EXPECT_LT(peak - baseline, kBudget) << "peak RSS growth " << ((peak - baseline) >> 20)
                                      << " MiB while streaming " << (file_bytes >> 20) << " MiB";
  std::filesystem::remove(p);
}

TEST(FormatMemory, Fp32StreamOf256MiBStaysUnder48MiBResident) {
  streamWithinBudget(ColourEncoding::Fp32, 256ull << 20);
}

TEST(FormatMemory, Unorm8StreamOf256MiBStaysUnder48MiBResident) {
  streamWithinBudget(ColourEncoding::Unorm8, 256ull << 20);
}

}  // namespace
}  // namespace oit::test
