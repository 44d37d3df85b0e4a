// The A-buffer resolve's list walks issue each step when the previous one's
// reads are back, in time with the partition's other requests (issue 22 s5).
// Until then a tile's whole walk was booked when the tile was fetched, its
// reads at cycles up to the walk's length ahead; the shared levels' port
// calendars keep `2 x sim.quantum_cycles + 4096` cycles behind their latest
// request, so every request the partition made meanwhile (the colour writes
// of the tiles before) was taken as arriving that far on: the resolve waited
// for an idle l2 port (hair at 10.6 M fragments, iris-pro-5200: a third of
// the resolve).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

class AbufferWalkInTime : public ::testing::TestWithParam<SimEngine> {};

// Three 8x8 tiles in a row, one partition: one node in tile 0, one in tile 1,
// a list of 200 in one pixel of tile 2 (fp32 nodes, 24 B), sorting free. The
// l2 (1 MiB, one slice of 64 B/clock, hit latency 50) holds the nodes, and
// its port is idle: the frame moves about 5 KB of nodes and 3 x 256 B of
// colour through it. So tile 2's walk is 200 dependent l2 hits of 50 cycles
// (the first also waits for the fill of the node burst the resolve's start
// wrote in part), from when its heads are there (the tile issues at cycle 1:
// two tiles a cycle; a ROP-cache hit of 10): it ends at W >= 11 + 200 x 50.
// Tiles 0 and 1 resolve meanwhile, 128 cycles each (64 px at 2 blends/clock
// x the fp32 rate 0.25), and tile 2 after its walk in max(64 px, 200 nodes)
// / 0.5 = 400 cycles (alu 656 in all), then its colour crosses the port in
// 256 / 64 = 4 cycles: the frame's tail, `l2`. The resolve is W + 404, and
// every cycle of it but the ALU's and that tail waits for the walk. (Booked
// at once, tile 2's walk moved the l2's calendar ~10,000 cycles on, and tile
// 0's colour write, taken as arriving at its ring's oldest cycle, held tile 1
// by the posted-write window: 4,334 cycles of `l2` with the port idle.)
TEST_P(AbufferWalkInTime, TheResolveNeverWaitsForAnIdlePort) {
  using model::testutil::frag;
  std::vector<Fragment> fs;
  uint32_t prim = 0;
  fs.push_back(frag(0, 0, 0.5f, 0.5f, 0.25f, 0.125f, 0.25f, model::testutil::kTranspDraw, prim++));
  fs.push_back(frag(8, 0, 0.5f, 0.5f, 0.25f, 0.125f, 0.25f, model::testutil::kTranspDraw, prim++));
  for (unsigned i = 0; i < 200; ++i)
    fs.push_back(
        frag(16, 0, 0.9f - 0.004f * float(i), 0.5f, 0.25f, 0.125f, 0.25f, model::testutil::kTranspDraw, prim++));
  RopConfig c = smallConfig();
  c.partitions.count = 1;
  c.sim.engine = GetParam();
  c.l2.size_bytes = 1u << 20;
  c.l2.slices = 1;
  c.l2.bytes_per_clock = 64.0;
  c.abuffer.sort_cycles_per_compare = 0;
  c.abuffer.sort_cycles_per_move = 0;
  ASSERT_EQ(c.l2.hit_latency, 50u);
  ASSERT_EQ(c.cache.hit_latency, 10u);
  ASSERT_EQ(c.alu.blends_per_clock, 2u);
  const auto r = runInChild([&] { return timed("abuffer", model::AlgorithmParams{}, fs, 24, 8, c); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& rc = r.stats["timing"]["root_cause_cycles"];
  const uint64_t resolve = r.stats["timing"]["phase_cycles"]["resolve"].get<uint64_t>();
  EXPECT_EQ(r.stats["memory"]["node_pool_bytes_read"].get<uint64_t>(), 202u * 24);
  EXPECT_EQ(rc["l2"].get<uint64_t>(), 4u) << rc.dump();
  EXPECT_EQ(r.stats["timing"]["stages"]["resolve"]["busy"].get<uint64_t>(), 128u + 128 + 400);
  EXPECT_EQ(r.stats["timing"]["stages"]["resolve"]["stalls"]["list_walk"].get<uint64_t>(), resolve - 656 - 4)
      << rc.dump();
  const uint64_t walk_end = resolve - 404;
  EXPECT_GE(walk_end, 11u + 200 * 50);
  // The partly written burst's fill is one DRAM read (DESIGN.md: about 70
  // cycles unloaded on these timings), not another walk.
  EXPECT_LE(walk_end, 11u + 200 * 50 + 200);
}

INSTANTIATE_TEST_SUITE_P(BothEngines, AbufferWalkInTime, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
