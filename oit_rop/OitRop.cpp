#include "oit_rop/OitRop.hpp"

#include <fmt/format.h>
#include <sysc/tracing/sc_tracing_ids.h>

#include <cmath>
#include <utility>

namespace oit::rop {

OitRop::OitRop(sc_core::sc_module_name name, const PartitionSetup& setup, const std::string& vcd_path)
    : sc_module(name),
      cfg_(*setup.cfg),
      clock_(setup.cfg->clock.core_mhz),
      dram_("dram", setup.cfg->dram, setup.cfg->clock.core_mhz) {
  // The shared levels, from the DRAM up: l3 behind l2 (a victim l3 gets the
  // l2's evictions), the first of them the partitions' entry.
  const RopConfig& c = *setup.cfg;
  const Cycle lookback = PortCalendar::sharedLookback(c.sim.quantum_cycles);
  MemoryPort* below = &dram_.entry();
  if (c.l2.size_bytes != 0) {
    if (c.l3.size_bytes != 0) {
      l3_ = std::make_unique<CacheLevel>("l3", c.l3, lookback, *below, nullptr, c.stats.level_miss_classes);
      below = l3_.get();
    }
    l2_ = std::make_unique<CacheLevel>("l2", c.l2, lookback, *below,
                                       l3_ && c.l3.victim_only ? l3_.get() : nullptr, c.stats.level_miss_classes);
    dram_.setEntry(*l2_);
  }
  const unsigned n = setup.geo->partitions;
  for (unsigned i = 0; i < n; ++i) {
    parts_.push_back(std::make_unique<RopPartition>(fmt::format("partition{}", i).c_str(), i, setup, dram_.entry(),
                                                    dram_.memory()));
    parts_.back()->dram.bind(dram_.target);  // multi-passthrough: one binding per partition
    done_list_ |= parts_.back()->doneEvent();
  }
  tr_occupancy_.assign(n, 0);
  if (!vcd_path.empty()) {
    std::string base = vcd_path;
    if (base.size() > 4 && base.compare(base.size() - 4, 4, ".vcd") == 0) base.resize(base.size() - 4);
    vcd_ = sc_core::sc_create_vcd_trace_file(base.c_str());
    // The time unit is the kernel's resolution (1 ps by default), which every
    // kernel time is a multiple of: a coarser unit (1 ns) cannot represent a
    // 1150 MHz clock's edges and SystemC warns (W713) at every sample.
    sc_core::sc_report_handler::set_actions(sc_core::SC_ID_TRACING_TIMESCALE_UNIT_, sc_core::SC_DO_NOTHING);
    const double res_s = sc_core::sc_get_time_resolution().to_seconds();
    const std::pair<double, sc_core::sc_time_unit> units[] = {
        {1.0, sc_core::SC_SEC}, {1e-3, sc_core::SC_MS}, {1e-6, sc_core::SC_US},
        {1e-9, sc_core::SC_NS}, {1e-12, sc_core::SC_PS}, {1e-15, sc_core::SC_FS}};
    for (const auto& [unit_s, u] : units)
      if (unit_s <= res_s * (1.0 + 1e-9)) {
        vcd_->set_time_unit(std::round(res_s / unit_s), u);
        break;
      }
    sc_core::sc_trace(vcd_, tr_dram_bytes_, "dram_bytes_per_interval");
    // The VCD is written as the frame runs: after the series' period doubles,
    // its earlier samples stay at the finer period, so the period of each DRAM
    // sample is traced beside it (bytes per cycle = bytes / interval).
    sc_core::sc_trace(vcd_, tr_interval_, "dram_interval_cycles");
    sc_core::sc_trace(vcd_, tr_waiters_, "lock_waiters");
    for (unsigned i = 0; i < n; ++i)
      sc_core::sc_trace(vcd_, tr_occupancy_[i], fmt::format("partition{}_occupancy", i));
  }
  SC_THREAD(sampler);
}

OitRop::~OitRop() {
  if (vcd_) sc_core::sc_close_vcd_trace_file(vcd_);
}

bool OitRop::allDone() const {
  for (const auto& p : parts_)
    if (!p->done()) return false;
  return true;
}

void OitRop::sampler() {
  interval_ = std::max<uint64_t>(1, cfg_.stats.interval_cycles);
  // An even limit: merging pairs keeps the grid (sample n at n x interval).
  const size_t max_samples = std::max<size_t>(2, size_t(cfg_.stats.max_samples) & ~size_t(1));
  for (Cycle c = interval_;; c += interval_) {
    const sc_core::sc_time t = clock_.time(c);
    if (t > sc_core::sc_time_stamp()) wait(t - sc_core::sc_time_stamp(), done_list_);
    if (allDone()) return;
    if (sc_core::sc_time_stamp() < t) {  // woken by a partition finishing: keep sampling on the grid
      c -= interval_;
      continue;
    }
    // The bytes the buses moved in [c - interval, c) (by bus time, as the
    // report's series): final now, since every request booked from here on has
    // a later `now` than c and no burst starts before its request.
    const std::vector<uint64_t>& bus = dram_.memory().stats().bus_bytes_per_interval;
    const size_t bucket = size_t(c / interval_) - 1;
    TimeSample s;
    s.cycle = c;
    s.dram_bytes = bucket < bus.size() ? bus[bucket] : 0;
    for (unsigned i = 0; i < parts_.size(); ++i) {
      tr_occupancy_[i] = parts_[i]->occupancy();
      s.occupancy += tr_occupancy_[i];
      s.lock_waiters += parts_[i]->lockWaiters();
    }
    tr_dram_bytes_ = s.dram_bytes;
    tr_interval_ = interval_;
    tr_waiters_ = s.lock_waiters;
    samples_.push_back(s);
    if (samples_.size() == max_samples) {
      // The series is as long as allowed: keep it as if sampled at twice the
      // period from the start (bytes add up; occupancy and waiters are the
      // values at the later sample's cycle, as a sample at 2 x interval reads).
      for (size_t i = 0; i < max_samples / 2; ++i) {
        TimeSample m = samples_[2 * i + 1];
        m.dram_bytes += samples_[2 * i].dram_bytes;
        samples_[i] = m;
      }
      samples_.resize(max_samples / 2);
      interval_ *= 2;
      dram_.memory().coarsenSamples();
    }
  }
}

}  // namespace oit::rop
