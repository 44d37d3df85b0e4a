// EarlyDepth: HiZ-decided fragments need no depth read; the others wait for
// the depth tile (fixed-latency fake DRAM), in order; tile buffer reuse.
#include <gtest/gtest.h>

#include <vector>

#include "oit_rop/stages/EarlyDepth.hpp"

using namespace oit::rop;

namespace {
struct FakeDram : MemoryPort {
  Cycle latency = 100;
  std::vector<std::pair<uint64_t, uint32_t>> reads;
  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) override {
    EXPECT_FALSE(write);
    EXPECT_EQ(s, Surface::Depth);
    reads.push_back({addr, bytes});
    return now + latency;
  }
};

std::vector<std::pair<Cycle, uint32_t>> runUntilEmpty(EarlyDepth& e, Cycle from) {
  std::vector<std::pair<Cycle, uint32_t>> out;
  for (Cycle now = from; e.size() > 0 && now < from + 10000; ++now) e.leave(now, [&](uint32_t t) { out.push_back({now, t}); });
  return out;
}
}  // namespace

TEST(EarlyDepth, HiZDecidedFragmentsPassAfterTheStageLatency) {
  FakeDram mem;
  EarlyDepthConfig c;
  c.latency = 4;
  EarlyDepth e(c, 2.0, 256, 1 << 20, mem);
  e.push(10, 1, 0, false);
  e.push(10, 2, 1, false);
  const auto out = runUntilEmpty(e, 11);
  ASSERT_EQ(out.size(), 2u);
  EXPECT_EQ(out[0], (std::pair<Cycle, uint32_t>{14, 1}));
  EXPECT_EQ(out[1], (std::pair<Cycle, uint32_t>{14, 2}));
  EXPECT_TRUE(mem.reads.empty());
  EXPECT_EQ(e.stats().hiz_decided, 2u);
}

TEST(EarlyDepth, DepthReadBlocksInOrderAndTheTileBufferIsReused) {
  FakeDram mem;
  EarlyDepthConfig c;
  c.latency = 4;
  EarlyDepth e(c, 1.0, 256, 1 << 20, mem);
  e.push(0, 1, 5, true);   // reads tile 5: ready at 100
  e.push(1, 2, 9, false);  // decided by HiZ, but behind fragment 1
  e.push(2, 3, 5, true);   // same tile: no second read
  EXPECT_TRUE(e.headWaitsForDepth(50));
  EXPECT_EQ(e.nextEvent(0), 4u);  // the head turns from latency to waiting at 4
  const auto out = runUntilEmpty(e, 1);
  ASSERT_EQ(out.size(), 3u);
  EXPECT_EQ(out[0], (std::pair<Cycle, uint32_t>{100, 1}));
  EXPECT_EQ(out[1], (std::pair<Cycle, uint32_t>{101, 2}));  // 1 per clock
  EXPECT_EQ(out[2], (std::pair<Cycle, uint32_t>{102, 3}));
  ASSERT_EQ(mem.reads.size(), 1u);
  EXPECT_EQ(mem.reads[0], (std::pair<uint64_t, uint32_t>{(1 << 20) + 5 * 256, 256}));
  EXPECT_EQ(e.stats().depth_buffer_hits, 1u);
}

// The approximate engine's visit: depthTileReady() for the fragments the HiZ
// cannot decide (a read at the visit when the 16-entry buffer lacks the tile,
// ready 100 cycles later), countTests() afterwards.
TEST(EarlyDepth, DepthTileReadyAndCountTests) {
  FakeDram mem;
  EarlyDepthConfig c;
  c.latency = 4;
  EarlyDepth e(c, 2.0, 256, 1 << 20, mem);
  struct Visit {
    Cycle now;
    uint32_t tile;
    bool needs_read;
    Cycle leaves;
  };
  // Tiles 19 and 35 share tile 3's slot.
  const Visit visits[] = {{10, 3, true, 110},  {11, 3, true, 110}, {11, 5, false, 15},
                          {12, 19, true, 112}, {13, 3, true, 113}, {200, 35, true, 300}};
  uint64_t reads_needed = 0;
  for (const Visit& v : visits) {
    Cycle leaves = v.now + c.latency;
    if (v.needs_read) {
      ++reads_needed;
      leaves = std::max(leaves, e.depthTileReady(v.now, v.tile));
    }
    EXPECT_EQ(leaves, v.leaves) << "tile " << v.tile << " at " << v.now;
  }
  e.countTests(std::size(visits), std::size(visits) - reads_needed);
  EXPECT_EQ(e.stats().tested, 6u);
  EXPECT_EQ(e.stats().hiz_decided, 1u);
  EXPECT_EQ(e.stats().depth_reads, 4u);  // tiles 3, 19, 3 again and 35
  EXPECT_EQ(e.stats().depth_buffer_hits, 1u);
  ASSERT_EQ(mem.reads.size(), 4u);
  EXPECT_EQ(mem.reads[1], (std::pair<uint64_t, uint32_t>{(1 << 20) + 19 * 256, 256}));
}
