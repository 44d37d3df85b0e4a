// bottleneckJson (oit_rop/Bottleneck.hpp): the report's root_cause_cycles,
// bound_by, utilization and phase_cycles from the partitions' accounts and
// the resources' work, with values derived by hand. (test_bounds.cpp checks
// that whole frames built to stress one resource are bound by it.)
#include <gtest/gtest.h>

#include "oit_rop/Bottleneck.hpp"

using namespace oit::rop;
using nlohmann::json;

namespace {

PartitionPhases partition(Cycle opaque_end, std::vector<Cycle> pass_end, Cycle end,
                          std::initializer_list<std::pair<RootCause, uint64_t>> causes) {
  PartitionPhases p;
  p.opaque_end = opaque_end;
  p.pass_end = std::move(pass_end);
  p.end = end;
  for (const auto& [c, n] : causes) p.root_causes[size_t(c)] = n;
  return p;
}

TEST(Bottleneck, BoundByTheCauseWithMostPartitionCyclesSummedOverPartitions) {
  // Partition 0: alu 600, l2 400 (1,000 cycles); partition 1: alu 100, l2 700,
  // input 200. Sums: alu 700, l2 1,100, input 200 of 2,000: bound by l2, 55 %
  // (though partition 0 alone is ALU-bound).
  const std::vector<PartitionPhases> parts = {
      partition(0, {900}, 1000, {{RootCause::Alu, 600}, {RootCause::L2, 400}}),
      partition(0, {950}, 1000, {{RootCause::Alu, 100}, {RootCause::L2, 700}, {RootCause::Input, 200}})};
  const json j = bottleneckJson(parts, 1000, ResourceWork{});
  EXPECT_EQ(j["bound_by"]["resource"], "l2");
  EXPECT_DOUBLE_EQ(j["bound_by"]["share"].get<double>(), 0.55);
  EXPECT_EQ(j["root_cause_cycles"]["alu"].get<uint64_t>(), 700u);
  EXPECT_EQ(j["root_cause_cycles"]["l2"].get<uint64_t>(), 1100u);
  EXPECT_EQ(j["root_cause_cycles"]["input"].get<uint64_t>(), 200u);
  EXPECT_EQ(j["root_cause_cycles"]["atomic_wait"].get<uint64_t>(), 0u);  // every cause is listed
  EXPECT_EQ(j["root_cause_cycles"].size(), size_t(kRootCauseCount));
}

TEST(Bottleneck, NoCyclesIsBoundByNothing) {
  const json j = bottleneckJson({partition(0, {}, 0, {})}, 0, ResourceWork{});
  EXPECT_EQ(j["bound_by"]["resource"], "none");
  EXPECT_EQ(j["bound_by"]["share"].get<double>(), 0.0);
}

TEST(Bottleneck, UtilisationIsWorkOverWhatTheResourceCouldDoAndNeverAboveOne) {
  // Two partitions, a 1,000-cycle frame: 2,000 partition-cycles.
  //   input: 3,000 fragments at 2 per clock per partition: 3,000 / 4,000 = 0.75
  //   early depth: 1,000 tests at the input rate: 0.25
  //   lock: mean occupancy 64 of 2 x 128 entries: 0.25
  //   cache ports: 500 accesses at 1 per clock: 0.25
  //   alu: 5,000 blends at 2 per clock = 1.25 of capacity: clamped to 1
  //   DRAM: 300 busy bus cycles over 2 channels x 1,000: 0.15
  //   l2: 16,000 bytes at 64 per clock (all slices) x 1,000 cycles: 0.25
  //   no l3 and no node counter (their rates 0): not in the report
  ResourceWork w;
  w.input_fragments = 3000;
  w.input_rate = 2;
  w.depth_tests = 1000;
  w.mean_occupancy = 64;
  w.lock_capacity = 128;
  w.cache_accesses = 500;
  w.cache_ports = 1;
  w.alu_work = 5000;
  w.alu_rate = 2;
  w.dram_busy_cycles = 300;
  w.dram_channels = 2;
  w.l2_bytes = 16000;
  w.l2_per_clock = 64;
  const json j = bottleneckJson({partition(0, {}, 1000, {}), partition(0, {}, 1000, {})}, 1000, w);
  const json& u = j["utilization"];
  EXPECT_DOUBLE_EQ(u["input"].get<double>(), 0.75);
  EXPECT_DOUBLE_EQ(u["early_depth"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(u["lock"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(u["cache_ports"].get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(u["alu"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(u["dram_bus"].get<double>(), 0.15);
  EXPECT_DOUBLE_EQ(u["l2"].get<double>(), 0.25);
  EXPECT_FALSE(u.contains("l3"));
  EXPECT_FALSE(u.contains("atomics"));
}

TEST(Bottleneck, PhasesAreThoseOfThePartitionThatFinishedLast) {
  // Partition 1 ends last (1,200): opaque 100, passes end at 700 and 1,000,
  // so transparent [600, 300], resolve 200; they add up to its end.
  const std::vector<PartitionPhases> parts = {partition(150, {800}, 1100, {}),
                                              partition(100, {700, 1000}, 1200, {})};
  const json j = bottleneckJson(parts, 1200, ResourceWork{});
  const json& ph = j["phase_cycles"];
  EXPECT_EQ(ph["opaque"].get<uint64_t>(), 100u);
  EXPECT_EQ(ph["transparent"], json::array({600, 300}));
  EXPECT_EQ(ph["resolve"].get<uint64_t>(), 200u);
}

}  // namespace
