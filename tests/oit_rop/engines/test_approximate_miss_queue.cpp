// A frame bound by the ROP cache's miss queue, on both engines, against the
// chain of misses derived by hand: the approximate engine's retry of a miss
// the queue refused (at the cycle an entry frees) must reach the memory
// system in time order with the other partitions' requests (DESIGN.md, "The
// continuum paper's Titan X point").
#include <gtest/gtest.h>

#include <string>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

class MissQueueBound : public ::testing::TestWithParam<SimEngine> {};

// Four partitions, one miss-queue entry each, and a DRAM whose every access
// is dominated by a 1000 ns controller latency (1150 cycles at 1150 MHz), so
// that each partition's misses form one chain, each waiting for the one
// before it, and the four chains share a DRAM that is nearly idle.
//
// The frame: four layers over 64 x 32 pixels (8 x 4 tiles of 8 x 8, tile
// (tx, ty) in partition (tx + ty) mod 4: 8 tiles, 512 pixels each), mlab k = 8
// rgba8t8z32 (64 B per pixel: one 64 B line), an 8 KiB ROP cache (128 lines).
// Per partition:
// - layer 1: 512 misses, all clear fills (fast clear): the first 128 take a
//   free way (the hit latency, 10 cycles), the other 384 evict a dirty line,
//   whose write-back the controller accepts after its latency: W = 1150;
// - layers 2 to 4: every fragment misses (a 512-line stream through 128
//   lines): 1536 fills, each an activate, CL and one burst on a closed page
//   behind the controller: R = ceil((1000 + 11 x 1.25 + 11 x 1.25 + 5) ns x
//   1.15) = ceil(1187.375) = 1188 (its victim's write-back, accepted at 1150,
//   is ready before);
// - the resolve: its 512 lines miss too (the 128 left resident are the last
//   two tiles', and the first tiles' misses evict them, least recently used,
//   before their turn): 512 x R.
// Chain: 384 x 1150 + (1536 + 512) x 1188 = 441,600 + 2,433,024 = 2,874,624
// cycles; the rest (the first 128 clear fills, the blends, the colour writes
// and the final drain) is a few thousand. The bus moves 4 reads per 1188
// cycles (5.75 cycles each): no queueing to speak of.
// Measured, the partitions' ends: cycle engine 2,915,004 to 2,916,756 (+1.40
// to +1.47 %), approximate 2,915,798 to 2,917,550 (+1.43 to +1.49 %). Before
// the fix the approximate engine's frame took 5,021,398 cycles (+74.7 %):
// each partition's refused misses went to DRAM at the cycle their entry
// would free, up to thousands of cycles ahead of its time and of the other
// partitions' (which SystemC keeps within a quantum of each other), so the
// other partitions' requests, booked later but due earlier, queued behind
// them in their banks (a bank takes accesses in booking order).
TEST_P(MissQueueBound, EachPartitionIsItsChainOfMisses) {
  RopConfig c = smallConfig();
  c.sim.engine = GetParam();
  c.partitions.count = 4;
  c.input.latency_model = LatencyModel::Fixed;
  c.input.latency_min = 40;
  c.input.fragments_per_clock = 1.0;
  c.cache.size_bytes = 8 * 1024;
  c.cache.miss_queue = 1;
  c.l2.size_bytes = 0;
  c.l3.size_bytes = 0;
  c.dram.channels = 1;
  c.dram.open_row = false;
  c.dram.controller_ns = 1000;
  c.dram.trefi_ns = c.dram.trfc_ns = 0;
  c.dram.twtr = c.dram.trtw = 0;
  const auto fs = layerSweeps(64, 32, 4, 1.0f / 1024.0f);
  model::AlgorithmParams p;
  p.layers = 8;
  p.format = model::StorageFormat::Rgba8T8Z32;
  const auto r = runInChild([&] { return timed("mlab", p, fs, 64, 32, c); });
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_EQ(r.stats["cache"]["misses"].get<uint64_t>(), 4u * (512 * 4 + 512));
  EXPECT_EQ(r.stats["cache"]["clear_fills"].get<uint64_t>(), 4u * 512);
  const double chain = 384.0 * 1150 + (1536.0 + 512) * 1188;
  for (const auto& part : r.stats["timing"]["per_partition"]) {
    const double end = double(part["end_cycle"].get<uint64_t>());
    EXPECT_GE(end, chain);
    EXPECT_LE(end, 1.03 * chain) << 100.0 * (end / chain - 1) << " % above the chain";
  }
}

INSTANTIATE_TEST_SUITE_P(ApproximateMissQueue, MissQueueBound, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
