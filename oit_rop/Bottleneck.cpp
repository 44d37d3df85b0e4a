#include "oit_rop/Bottleneck.hpp"

#include <algorithm>

namespace oit::rop {

using nlohmann::json;

json bottleneckJson(const std::vector<PartitionPhases>& parts, Cycle cycles, const ResourceWork& w) {
  RootCauseAccount::Cycles sum{};
  uint64_t total = 0;
  for (const PartitionPhases& p : parts)
    for (unsigned i = 0; i < kRootCauseCount; ++i) {
      sum[i] += p.root_causes[i];
      total += p.root_causes[i];
    }
  json root = json::object();
  unsigned top = 0;
  for (unsigned i = 0; i < kRootCauseCount; ++i) {
    root[rootCauseKey(RootCause(i))] = sum[i];
    if (sum[i] > sum[top]) top = i;
  }
  json bound = {{"resource", total ? rootCauseKey(RootCause(top)) : "none"},
                {"share", total ? double(sum[top]) / double(total) : 0.0}};

  const double pc = double(cycles) * double(parts.size());  // partition-cycles
  auto share = [](double used, double capacity) { return capacity > 0 ? std::min(1.0, used / capacity) : 0.0; };
  json util = {{"input", share(w.input_fragments, w.input_rate * pc)},
               {"early_depth", share(w.depth_tests, w.input_rate * pc)},
               {"lock", share(w.mean_occupancy, w.lock_capacity * double(parts.size()))},
               {"cache_ports", share(w.cache_accesses, w.cache_ports * pc)},
               {"alu", share(w.alu_work, w.alu_rate * pc)},
               {"dram_bus", share(w.dram_busy_cycles, w.dram_channels * double(cycles))}};
  if (w.l2_per_clock > 0) util["l2"] = share(w.l2_bytes, w.l2_per_clock * double(cycles));
  if (w.l3_per_clock > 0) util["l3"] = share(w.l3_bytes, w.l3_per_clock * double(cycles));
  if (w.atomics_per_clock > 0) util["atomics"] = share(w.atomics, w.atomics_per_clock * double(cycles));

  // The phases of the partition that finished last (ties: the first).
  json phases = {{"opaque", 0}, {"transparent", json::array()}, {"resolve", 0}};
  if (!parts.empty()) {
    const PartitionPhases& last = *std::max_element(parts.begin(), parts.end(),
                                                    [](const PartitionPhases& a, const PartitionPhases& b) { return a.end < b.end; });
    phases["opaque"] = last.opaque_end;
    Cycle at = last.opaque_end;
    for (Cycle e : last.pass_end) {
      phases["transparent"].push_back(e - at);
      at = e;
    }
    phases["resolve"] = last.end - at;
  }
  return {{"root_cause_cycles", root}, {"bound_by", bound}, {"utilization", util}, {"phase_cycles", phases}};
}

}  // namespace oit::rop
