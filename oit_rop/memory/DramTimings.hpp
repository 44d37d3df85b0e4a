// The DRAM's timings converted once to the controller's time unit, the tick
// (1 core cycle = 2^16 ticks, rounded up: MEMORY.md "units"), and the refresh
// windows of each channel. Fractional DRAM timings and bandwidths never
// accumulate rounding along a stream this way.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

// Throws std::invalid_argument("DramConfig: " + what) unless ok: the DRAM
// timing and address-map checks share one message form.
void requireDramConfig(bool ok, const char* what);

struct DramTimings {
  static constexpr unsigned kTickShift = 16;
  static constexpr uint64_t kTicksPerCycle = uint64_t(1) << kTickShift;

  // Core cycles to ticks, rounding up so that a latency or transfer time is
  // never shorter than configured; within 1e-9 (relative) of a whole tick is
  // that tick (5.75 cycles must not become 5.75 cycles + 1 tick through noise).
  static uint64_t ticks(double cycles);
  static double cycles(uint64_t ticks) { return std::ldexp(double(ticks), -int(kTickShift)); }
  // Rounds ticks up to whole core cycles.
  static uint64_t ceilCycles(uint64_t ticks) { return (ticks + kTicksPerCycle - 1) >> kTickShift; }

  // Throws std::invalid_argument ("DramConfig: ...") on unusable values.
  DramTimings(const DramConfig& cfg, double core_mhz);

  double bytes_per_cycle = 0;  // one channel's data bus
  uint64_t ctrl = 0, cl = 0, trcd = 0, trp = 0, tras = 0, burst = 0;
  uint64_t twtr = 0, trtw = 0;  // write-to-read (to the read command), read-to-write (idle bus)
  uint64_t trrd = 0, tfaw = 0;  // activate to activate (other bank), four-activate window; 0 = none
  // Bank groups (dram.bank_groups > 1; MEMORY.md "Bank groups"): inside a
  // group activates are trrd_l apart, column commands tccd_l, a read waits
  // twtr_l after the group's write data (each at least its _S value: trrd,
  // tccd_s, twtr; equal when the configuration makes no distinction).
  unsigned bank_groups = 1;
  uint64_t trrd_l = 0, twtr_l = 0;
  // Data starts on one channel at least `ccd_s` apart (max(burst, tCCD_S)),
  // in one bank group `ccd_l` apart (max(ccd_s, tCCD_L)); a run's bursts
  // (one bank) follow each other every ccd_l. Without bank groups and
  // tCCD_S both are the burst: the bus alone spaces the data.
  uint64_t ccd_s = 0, ccd_l = 0;
  // The data span of a run of n bursts (from its first burst's start to its last one's end).
  uint64_t runSpan(uint64_t n) const { return (n - 1) * ccd_l + burst; }

  // Refresh (dram.trefi_ns > 0): channel c refreshes all its banks in the
  // windows [w, w + rfc) at w = off_c + k * period, k >= 1, off_c = c * period /
  // channels (staggered). period 0: no refresh.
  uint64_t refresh_period = 0, refresh_rfc = 0;
  std::vector<uint64_t> refresh_off;  // per channel
  // The most bursts one run may hold: a run is placed whole between two
  // refresh windows (on a bank a refresh left closed: tRCD + CL, then its
  // data), a longer one is booked in parts. No limit without refresh.
  uint64_t max_run_bursts = ~uint64_t(0);
  // Start of the latest window at or before t (0: none).
  uint64_t lastRefreshStart(unsigned ch, uint64_t t) const {
    const uint64_t off = refresh_off[ch];
    if (t < off + refresh_period) return 0;
    return off + (t - off) / refresh_period * refresh_period;
  }
  // End of the first window meeting [from, end) (0: none).
  uint64_t refreshOverlapEnd(unsigned ch, uint64_t from, uint64_t end) const {
    const uint64_t off = refresh_off[ch];
    uint64_t w = off + std::max<uint64_t>(1, from > off ? (from - off) / refresh_period : 0) * refresh_period;
    if (w + refresh_rfc <= from) w += refresh_period;
    return w < end ? w + refresh_rfc : 0;
  }

  // "" when dram.trefi_ns / trfc_ns are usable at core_mhz, else what is wrong
  // (the time between two refreshes must hold an activate, CL and one burst).
  static std::string refreshProblem(const DramConfig& cfg, double core_mhz);
  // "" when dram.trrd / tfaw are consistent, else what is wrong: a tFAW below
  // 4 x tRRD could never bind (four activates tRRD apart already span it), as
  // in no JEDEC part; it is refused as a likely mistake (0 turns it off).
  static std::string activateProblem(const DramConfig& cfg);
  // The bank-group rules broken (empty: none), one line each naming the
  // parameter: dram.bank_groups a power of two dividing dram.banks; an _L
  // timing 0 or at least its _S value, and only with bank_groups > 1.
  static std::vector<std::string> bankGroupProblems(const DramConfig& cfg);
};

}  // namespace oit::rop
