// What bounds a frame (DESIGN.md "Root causes"): the partitions' cycles by
// root cause, the cause with the largest share (`bound_by`), the utilisation
// of each resource, and the frame's phases, as report.json's timing keys
// root_cause_cycles, bound_by, utilization and phase_cycles.
#pragma once

#include <nlohmann/json.hpp>

#include <vector>

#include "oit_rop/RootCause.hpp"
#include "oit_rop/Types.hpp"

namespace oit::rop {

// A partition's phase ends (PartitionResult) and its cycles by root cause.
struct PartitionPhases {
  Cycle opaque_end = 0, end = 0;
  std::vector<Cycle> pass_end;
  RootCauseAccount::Cycles root_causes{};
};

// What the resources did over the frame (sums over partitions) and what they
// could do per cycle (per partition; the DRAM's for all channels).
struct ResourceWork {
  double input_fragments = 0, input_rate = 0;          // opaque + transparent issued; fragments per clock
  double depth_tests = 0;                              // early depth, at the input rate
  double mean_occupancy = 0, lock_capacity = 0;        // scoreboard entries in use (sampled, all partitions)
  double cache_accesses = 0, cache_ports = 0;          // ROP-cache accesses; accesses per clock
  double alu_work = 0, alu_rate = 0;                   // blends + resolved pixels; per clock (format rate in)
  double dram_busy_cycles = 0, dram_channels = 0;      // data-bus cycles over all channels
  // Shared levels (absent: per_clock 0): bytes through their slices' ports
  // (requested reads and writes, victims in) and what the ports move per clock.
  double l2_bytes = 0, l2_per_clock = 0, l3_bytes = 0, l3_per_clock = 0;
  // The A-buffer's node counter (absent: per_clock 0): increments, and the GPU's rate.
  double atomics = 0, atomics_per_clock = 0;
};

// timing.root_cause_cycles, .bound_by, .utilization and .phase_cycles for a
// frame of `cycles` on `parts` (the phases are those of the partition that
// finished last: they add up to the frame's cycles).
nlohmann::json bottleneckJson(const std::vector<PartitionPhases>& parts, Cycle cycles, const ResourceWork& w);

}  // namespace oit::rop
