// Microbenchmarks against analytic bounds (issue 21, "What must hold"): a
// trace built here stresses one resource; its frame must come within 3 % of
// the bound derived by hand from the configuration (in the comments) and
// never below it, on both engines. (The DRAM-only streams, row hits, bank
// parallelism and the controller's policies, are tested beside the DRAM
// controller, tests/oit_rop/memory/test_memory_system.cpp.)
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "oit_rop/RopTestUtil.hpp"

using namespace oit;
using namespace oit::rop;
using namespace oit::rop::testutil;

namespace {

// `layers` fragments per pixel over a w x h frame (RopTestUtil.hpp), each
// layer nearer than the last by 1/1024.
std::vector<Fragment> layersOf(uint16_t w, uint16_t h, unsigned layers) {
  return layerSweeps(w, h, layers, 1.0f / 1024.0f);
}

// One partition, no shared levels, fixed shader latency: every cost below is
// then a term of the configuration.
RopConfig base() {
  RopConfig c = smallConfig();
  c.partitions.count = 1;
  c.input.latency_model = LatencyModel::Fixed;
  c.input.latency_min = 40;
  return c;
}

model::AlgorithmParams rgba8(unsigned layers = 4) {
  model::AlgorithmParams p;
  p.layers = layers;
  p.format = model::StorageFormat::Rgba8T8Z32;
  return p;
}

uint64_t cyclesOf(const ChildRun& r) { return r.stats["timing"]["cycles"].get<uint64_t>(); }

void expectWithin3Percent(uint64_t cycles, double bound) {
  ::testing::Test::RecordProperty("percent_above_bound", std::to_string(100.0 * (double(cycles) / bound - 1)));
  EXPECT_GE(double(cycles), bound);
  EXPECT_LE(double(cycles), 1.03 * bound) << "bound " << bound << ", " << 100.0 * (double(cycles) / bound - 1) << " % above";
}

// The root-cause attribution names the resource the trace stresses as
// timing.bound_by with at least 90 % of the partition-cycles (issue 22, item
// 4; oit_rop/DESIGN.md "Root causes"), and the causes add up to every
// partition's cycles.
void expectBoundBy(const ChildRun& r, const std::string& cause) {
  const auto& t = r.stats["timing"];
  uint64_t charged = 0, ends = 0;
  for (const auto& [k, v] : t["root_cause_cycles"].items()) charged += v.get<uint64_t>();
  for (const auto& p : t["per_partition"]) ends += p["end_cycle"].get<uint64_t>();
  EXPECT_EQ(charged, ends);
  ::testing::Test::RecordProperty("bound_share", std::to_string(t["bound_by"]["share"].get<double>()));
  EXPECT_EQ(t["bound_by"]["resource"].get<std::string>(), cause) << t["root_cause_cycles"].dump();
  EXPECT_GE(t["bound_by"]["share"].get<double>(), 0.90) << t["root_cause_cycles"].dump();
  EXPECT_DOUBLE_EQ(t["bound_by"]["share"].get<double>(),
                   double(t["root_cause_cycles"][cause].get<uint64_t>()) / double(charged));
}

class Bounds : public ::testing::TestWithParam<SimEngine> {};

// 16x16 pixels x 256 layers of alpha blending (rgba8: 4 B per pixel, always
// Stored) at 1 fragment per clock: 65 536 fragments can issue no faster than
// 65 536 cycles. Everything else is fast: 4 blends per clock, the arrays
// (1 KiB) fit the 64 KiB cache, a pixel's fragments are 256 cycles apart (its
// lock is long free). The rest is the last fragment's latency (40 + 4 + 1 + 10
// + 10) and the resolve of 4 tiles (64 cycles + its reads and writes).
TEST_P(Bounds, InputBound) {
  RopConfig c = base();
  c.sim.engine = GetParam();
  c.input.fragments_per_clock = 1.0;
  c.alu.blends_per_clock = 4;
  const auto fs = layersOf(16, 16, 256);
  const auto r = runInChild([&] { return timed("alpha", rgba8(), fs, 16, 16, c); });
  ASSERT_TRUE(r.ok) << r.error;
  expectWithin3Percent(cyclesOf(r), 65536.0);
  expectBoundBy(r, "input");
}

// The same trace at 4 fragments per clock into 1 blend per clock (rgba8 rows
// blend at the full rate): 65 536 blends need 65 536 cycles.
TEST_P(Bounds, AluBound) {
  RopConfig c = base();
  c.sim.engine = GetParam();
  c.input.fragments_per_clock = 4.0;
  c.alu.blends_per_clock = 1;
  const auto fs = layersOf(16, 16, 256);
  const auto r = runInChild([&] { return timed("alpha", rgba8(), fs, 16, 16, c); });
  ASSERT_TRUE(r.ok) << r.error;
  expectWithin3Percent(cyclesOf(r), 65536.0);
  expectBoundBy(r, "alu");
}

// 4096 fragments to one pixel: each enters the lock when the one before
// released it (end of blend), reaches the cache in that cycle, hits (10), and
// blends for base 8 + 2 x 1 row written (alpha: one accumulator, no compare): a
// release every 20 cycles, 4096 x 20 = 81 920 cycles however fast the input.
TEST_P(Bounds, LockBoundOnOnePixel) {
  RopConfig c = base();
  c.sim.engine = GetParam();
  c.input.fragments_per_clock = 2.0;
  c.alu.blends_per_clock = 4;
  const auto fs = layersOf(1, 1, 4096);
  const auto r = runInChild([&] { return timed("alpha", rgba8(), fs, 8, 8, c); });
  ASSERT_TRUE(r.ok) << r.error;
  const double per_fragment = c.cache.hit_latency + c.alu.base_latency + c.alu.cycles_per_row_moved * 1.0;  // no compare
  ASSERT_EQ(per_fragment, 20.0);
  expectWithin3Percent(cyclesOf(r), 4096 * per_fragment);
  expectBoundBy(r, "lock_wait");
  EXPECT_EQ(r.stats["lock"]["conflicts"].get<uint64_t>(), 4095u);
}

// A stream through a 16-line ROP cache into an l2 of one 4 B/clock port:
// 64x32 pixels, mlab k = 8 rgba8t8z32 (64 B per pixel: one line each, 2048
// lines), two layers. Bytes over the l2's port:
//  - layer 1: 2048 clear fills (fast clear, none from the l2); from the 17th
//    on each evicts a dirty line: 2032 write-backs of 64 B;
//  - layer 2: each line was evicted (16 lines, a 2048-line stream): 2048 fills
//    of 64 B and 2048 dirty write-backs of 64 B;
//  - resolve: each pixel's 2 rows and the empty third (24 B) lie in its one
//    line: 2048 reads of 64 B (the 16 lines still cached are evicted, dirty,
//    by the first ones: 16 write-backs), and 32 tiles' colour, 256 B each.
// 2032 x 64 + 2048 x 128 + 2048 x 64 + 16 x 64 + 32 x 256 = 532 480 B, at
// 4 B/clock: 133 120 cycles; the l2 holds everything (256 KiB), DRAM sees
// nothing. The other limits are far: 4096 fragments at 1 per clock, 16 misses
// in flight x 64 B per (16 + 20) cycles.
TEST_P(Bounds, L2BandwidthBound) {
  RopConfig c = base();
  c.sim.engine = GetParam();
  c.cache.size_bytes = 1024;
  c.input.fragments_per_clock = 1.0;
  c.l2.size_bytes = 256 * 1024;
  c.l2.ways = 16;
  c.l2.slices = 1;
  c.l2.hit_latency = 20;
  c.l2.bytes_per_clock = 4.0;
  const auto fs = layersOf(64, 32, 2);
  const auto r = runInChild([&] { return timed("mlab", rgba8(8), fs, 64, 32, c); });
  ASSERT_TRUE(r.ok) << r.error;
  const auto& l2 = r.stats["memory"]["levels"][1];
  ASSERT_EQ(l2["name"], "l2");
  EXPECT_EQ(l2["read_bytes"].get<uint64_t>(), 2048u * 64 * 2);
  EXPECT_EQ(l2["write_bytes"].get<uint64_t>(), 2032u * 64 + 2048 * 64 + 16 * 64 + 32 * 256);
  EXPECT_EQ(r.stats["memory"]["dram_read_bytes"]["total"].get<uint64_t>() +
                r.stats["memory"]["dram_write_bytes"]["total"].get<uint64_t>(),
            0u);
  expectWithin3Percent(cyclesOf(r), 532480.0 / 4.0);
  expectBoundBy(r, "l2");
}

// A whole frame bound by DRAM: the stream above, four layers, an 8 KiB ROP
// cache (128 lines), no l2, one DDR3-1600 channel (12.8 GB/s at 1150 MHz:
// 11.1304 B/cycle). Layer 1: clear fills, 2048 - 128 = 1920 dirty write-backs;
// layers 2 to 4: every fragment misses (a 2048-line stream through 128
// lines): 3 x 2048 fills and 3 x 2048 write-backs; the resolve: 2048 reads,
// the 128 lines left dirty written back, 32 colour tiles of 256 B. Reads
// 8192 x 64 B, writes 8192 x 64 B + 8 KiB: 1 056 768 B, 94 944 cycles of bus.
// A fill and the write-back of the line 128 behind it share a row (8 KiB
// rows), so the bus streams; the miss latency (46 + 15.8 + 5.75 cycles per
// line) is hidden by 16 misses in flight (16 x 64 B per 68 cycles: 15
// B/cycle > 11.13). (Measured with writes written at once: +1.0 % on both
// engines; with the write queue below +0.4 % over its bound; the rest is the
// startup, before the cache's first eviction, and the resolve's reads meeting
// its colour writes in one bank.) The controller's refresh and read/write
// turnarounds are off (they have their own bounds in
// memory/test_dram_bounds.cpp), but not its write queue: here 128 bursts
// deep, writes wait until 112 bursts do and drain down to 32, and after each
// batch the next read's data comes CL after the last write's (the read
// command waits for the write data; with tWTR = 0 the bus idles CL = 11 x
// 1.25 ns = 15.8125 cycles, dram_turnaround). 8192 + 128 write bursts:
// batches after the 112th and every 80 more, floor((8320 - 112) / 80) + 1 =
// 103 switches back to reads (the last writes drain after the last read):
// + 1 629 cycles. (With the preset's queue, 56 / 32 of 64: the next test; with
// the preset's turnarounds and refresh the frame takes +13.2 % over the bus
// time.)
// The DRAM frames' configuration: an 8 KiB ROP cache, 1 fragment per clock,
// one DDR3-1600 channel without refresh or turnarounds (each test adds the
// mechanism it stresses), and their run: four layers of 64 x 32 pixels.
RopConfig dramFrameConfig(SimEngine engine) {
  RopConfig c = base();
  c.sim.engine = engine;
  c.cache.size_bytes = 8 * 1024;
  c.input.fragments_per_clock = 1.0;
  c.dram.channels = 1;
  c.dram.trefi_ns = c.dram.trfc_ns = 0;
  c.dram.twtr = c.dram.trtw = 0;
  return c;
}
ChildRun runDramFrame(const RopConfig& c) {
  const auto fs = layersOf(64, 32, 4);
  return runInChild([&] { return timed("mlab", rgba8(8), fs, 64, 32, c); });
}
// The bandwidth-bound frames: their write queue of `size` bursts drains at
// `high` down to `low`; the bus time of the bytes derived above, 94 944 cycles
// at 12.8 GB/s (1150 MHz), plus `switches` back to reads of CL = 11 x 1.25 ns
// each.
ChildRun runDramFrameWithWriteQueue(SimEngine engine, unsigned size, unsigned high, unsigned low) {
  RopConfig c = dramFrameConfig(engine);
  c.dram.write_queue = size;
  c.dram.write_high = high;
  c.dram.write_low = low;
  return runDramFrame(c);
}
constexpr double kDramClCycles = 11 * 1.25 * 1150.0 / 1000.0;
double dramBoundFrameCycles(const ChildRun& r, double switches) {
  const uint64_t read = r.stats["memory"]["dram_read_bytes"]["total"].get<uint64_t>();
  const uint64_t written = r.stats["memory"]["dram_write_bytes"]["total"].get<uint64_t>();
  EXPECT_EQ(read, 8192u * 64);
  EXPECT_EQ(written, 8192u * 64 + 32 * 256);
  return double(read + written) / (12.8 * 1000.0 / 1150.0) + switches * kDramClCycles;
}

TEST_P(Bounds, DramBoundFrame) {
  const auto r = runDramFrameWithWriteQueue(GetParam(), 128, 112, 32);
  ASSERT_TRUE(r.ok) << r.error;
  expectWithin3Percent(cyclesOf(r), dramBoundFrameCycles(r, 103));
  expectBoundBy(r, "dram_bandwidth");
}

// The same frame with the preset's write queue (64 entries, drains at 56 down
// to 32): batches after the 56th write burst and every 24 more,
// floor((8320 - 56) / 24) + 1 = 345 switches back to reads (measured: 345
// batches), each leaving the bus idle CL = 15.8125 cycles: 5 455 cycles over
// the bus time, 94 944 + 5 455 = 100 399 (measured 100 819 on both engines,
// +0.4 %). The root causes charge part of that idle to dram_turnaround: 4 208
// cycles, 4.2 % of the frame, on the cycle engine (dram_bandwidth 90.9 %),
// 1 615, 1.6 %, on the approximate one (dram_bandwidth 93.7 %, dram_latency
// 1.4 %: its transparent phase charges a full miss queue the latest miss's
// wait, DramActivateLimitFrame below). Not all of it: on the cycle engine the
// DRAM causes hold 96 702 cycles against 100 399 of bus time and switches, the
// rest is input (2 148) and alu (1 952), time in which the partition waited for
// no line while bus work and switches went on (not split further). So the
// switches' idle bounds the share from above, on both engines: a turnaround
// charged beyond the bus's idle for the switches would be a cause invented;
// dram_bandwidth must bound the frame (90.9 % and 93.7 %). (Before 925817e's
// act-cause changes: 4.1 % and 89.6 % on the cycle engine.)
TEST_P(Bounds, DramBoundFrameWithThePresetsWriteQueue) {
  const auto r = runDramFrameWithWriteQueue(GetParam(), 64, 56, 32);
  ASSERT_TRUE(r.ok) << r.error;
  const double switches = (8320 - 56) / 24 + 1;
  expectWithin3Percent(cyclesOf(r), dramBoundFrameCycles(r, switches));
  expectBoundBy(r, "dram_bandwidth");
  const double turnaround = double(r.stats["timing"]["root_cause_cycles"]["dram_turnaround"].get<uint64_t>());
  RecordProperty("turnaround_share", std::to_string(turnaround / double(cyclesOf(r))));
  EXPECT_GT(turnaround, 0.0);
  EXPECT_LE(turnaround, switches * kDramClCycles) << r.stats["timing"]["root_cause_cycles"].dump();
}

// The same frame with the DRAM's queueing made of something other than the
// bus moving data (issue 22 s3: "bound by DRAM bandwidth" at 30 % bus
// utilisation was a wrong answer). One bank, closed page and tRAS = 400 DRAM
// clocks: every access activates the one bank, which takes tRAS + tRP (411
// clocks x 1.4375 = 591 cycles at 1150 MHz) before the next may, against
// 5.75 cycles of data per 64 B line (a 256 B colour tile: 23): the bus is
// busy about 1-4 % of the time, the frame waits for the bank.
TEST_P(Bounds, DramBankConflictFrame) {
  RopConfig c = dramFrameConfig(GetParam());
  c.dram.banks = 1;
  c.dram.open_row = false;
  c.dram.tras = 400;
  const auto r = runDramFrame(c);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_LT(r.stats["timing"]["utilization"]["dram_bus"].get<double>(), 0.05);
  expectBoundBy(r, "dram_bank_conflict");
}

// And made of the channel's activate limits (MEMORY.md, "Activate limits"):
// closed page over the 8 banks with tRRD 60 and tFAW 240 DRAM clocks (x 1.4375
// = 345 cycles): every run opens a row, four per tFAW at most, against 5.75
// cycles of data per burst: the bus idles, the frame waits for the activates.
// Activate k (counted by row_misses, one per closed-page run) comes no earlier
// than floor(k / 4) tFAW after the first, and before the frame's end, so the
// frame is at least floor((row_misses - 1) / 4) x 345 cycles (measured +0.4 %
// on both engines). The wait is the bank's side of the controller, and
// dram_bank_conflict bounds the frame with 97.2 % of the partition-cycles on
// both engines, dram_latency 0.4 % / 0.6 %. (Until this was asserted,
// 69 % and 65 %: the resolve's acquires, refused for a full miss queue, were
// charged the latest miss's wait, its front, i.e. its unloaded access, 84 of
// the ~86 cycles between activates: dram_latency 15.8 % / 19.9 %; and a
// fill's queueing behind the bank's row cycle (tRAS + tRP, 56 cycles) and the
// window (30 more) was split by the bus's record, its 12 % busy time
// dram_bandwidth: 13.5 % / 13.2 %. Now the refused acquire takes the wait of
// the miss that frees the queue, and a run its bank placed is the bank's;
// DESIGN.md "Root causes". Until session 21 the approximate engine's
// transparent phase still charged a full miss queue the proportions of the
// latest miss's whole wait: dram_bank_conflict 93.4 %, dram_latency 4.5 %.)
TEST_P(Bounds, DramActivateLimitFrame) {
  RopConfig c = dramFrameConfig(GetParam());
  c.dram.open_row = false;
  c.dram.trrd = 60;
  c.dram.tfaw = 240;
  const auto r = runDramFrame(c);
  ASSERT_TRUE(r.ok) << r.error;
  const uint64_t activates = r.stats["memory"]["row_misses"].get<uint64_t>();
  EXPECT_GE(activates, 8192u);  // every fill is a run of its own
  const double tfaw = 240 * 1.25 * 1150.0 / 1000.0;
  expectWithin3Percent(cyclesOf(r), double((activates - 1) / 4) * tfaw);
  EXPECT_LT(r.stats["timing"]["utilization"]["dram_bus"].get<double>(), 0.15);
  const auto& t = r.stats["timing"];
  EXPECT_EQ(t["bound_by"]["resource"].get<std::string>(), "dram_bank_conflict") << t["root_cause_cycles"].dump();
  EXPECT_GE(t["bound_by"]["share"].get<double>(), 0.95) << t["root_cause_cycles"].dump();
  EXPECT_LT(t["root_cause_cycles"]["dram_latency"].get<double>(), 0.01 * double(cyclesOf(r)))
      << t["root_cause_cycles"].dump();
}

// And made of turnarounds: a write queue of one burst (every write-back
// drains at once) and tWTR = tRTW = 200 DRAM clocks (287.5 cycles): each of
// the 8192 write-backs between two fills switches the bus twice, 2 x 287.5 +
// CL against 2 x 5.75 cycles of data: the bus idles while it turns around.
TEST_P(Bounds, DramTurnaroundFrame) {
  RopConfig c = dramFrameConfig(GetParam());
  c.dram.twtr = c.dram.trtw = 200;
  c.dram.write_queue = c.dram.write_high = 1;
  c.dram.write_low = 0;
  const auto r = runDramFrame(c);
  ASSERT_TRUE(r.ok) << r.error;
  EXPECT_LT(r.stats["timing"]["utilization"]["dram_bus"].get<double>(), 0.05);
  expectBoundBy(r, "dram_turnaround");
}

INSTANTIATE_TEST_SUITE_P(Validation, Bounds, ::testing::ValuesIn(kBothEngines), engineName);

}  // namespace
