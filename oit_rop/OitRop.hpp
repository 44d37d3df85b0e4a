// OitRop: the top sc_module of the timing model: N RopPartitions (screen
// tiles interleaved, FrameGeometry) sharing one DramSystem (the shared cache
// levels l2 and l3, when configured, in front of the DRAM), plus a sampler
// process that records the time series every stats.interval_cycles and, when
// a VCD path is given, traces a few key values (sc_trace).
#pragma once

#include <systemc>

#include <memory>
#include <string>
#include <vector>

#include "oit_rop/memory/CacheLevel.hpp"
#include "oit_rop/memory/DramSystem.hpp"
#include "oit_rop/RopPartition.hpp"

namespace oit::rop {

struct TimeSample {
  Cycle cycle = 0;
  uint64_t dram_bytes = 0;   // bytes the DRAM buses moved in the interval ending at `cycle`
  uint32_t occupancy = 0;    // scoreboard entries in use, all partitions
  uint32_t lock_waiters = 0; // fragments waiting for their pixel lock
};

class OitRop : public sc_core::sc_module {
 public:
  SC_HAS_PROCESS(OitRop);
  OitRop(sc_core::sc_module_name name, const PartitionSetup& setup, const std::string& vcd_path);
  ~OitRop() override;

  DramSystem& dram() { return dram_; }
  // The shared cache levels (null when not configured).
  const CacheLevel* l2() const { return l2_.get(); }
  const CacheLevel* l3() const { return l3_.get(); }
  unsigned partitionCount() const { return unsigned(parts_.size()); }
  const RopPartition& partition(unsigned i) const { return *parts_[i]; }
  const std::vector<TimeSample>& samples() const { return samples_; }
  // The time series' period: stats.interval_cycles, doubled each time the
  // series reached stats.max_samples (pairs of samples merged).
  Cycle sampleInterval() const { return interval_; }
  bool allDone() const;

 private:
  void sampler();

  const RopConfig& cfg_;
  CoreClock clock_;
  DramSystem dram_;
  std::unique_ptr<CacheLevel> l3_, l2_;  // built before the partitions, which reach them
  std::vector<std::unique_ptr<RopPartition>> parts_;
  sc_core::sc_event_or_list done_list_;
  std::vector<TimeSample> samples_;
  Cycle interval_ = 1;
  sc_core::sc_trace_file* vcd_ = nullptr;
  // Values the VCD traces (updated by the sampler).
  sc_dt::uint64 tr_dram_bytes_ = 0;
  sc_dt::uint64 tr_interval_ = 0;  // the period of tr_dram_bytes_'s sample (doubles with the series)
  std::vector<unsigned> tr_occupancy_;
  unsigned tr_waiters_ = 0;
};

}  // namespace oit::rop
