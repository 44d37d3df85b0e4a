#include "oit_rop/memory/DramTimings.hpp"

#include <fmt/format.h>

#include <stdexcept>

namespace oit::rop {

void requireDramConfig(bool ok, const char* what) {
  if (!ok) throw std::invalid_argument(std::string("DramConfig: ") + what);
}

uint64_t DramTimings::ticks(double cycles) {
  const double t = std::ldexp(cycles, static_cast<int>(kTickShift));
  const double r = std::round(t);
  if (std::fabs(t - r) <= 1e-9 * std::max(1.0, r)) return static_cast<uint64_t>(r);
  return static_cast<uint64_t>(std::ceil(t));
}

DramTimings::DramTimings(const DramConfig& cfg, double core_mhz) {
  requireDramConfig(core_mhz > 0, "core_mhz must be > 0");
  requireDramConfig(cfg.channels >= 1, "channels must be >= 1");
  requireDramConfig(cfg.channel_gbps > 0, "channel_gbps must be > 0");
  requireDramConfig(cfg.tck_ns > 0, "tck_ns must be > 0");
  requireDramConfig(cfg.controller_ns >= 0, "controller_ns must be >= 0");
  requireDramConfig(cfg.burst_bytes >= 1, "burst_bytes must be >= 1");
  const double cycles_per_ns = core_mhz / 1000.0;
  const auto tck = [&](unsigned n) { return ticks(n * cfg.tck_ns * cycles_per_ns); };
  // GB/s / (cycles/s): channel_gbps * 1e9 / (core_mhz * 1e6)
  bytes_per_cycle = cfg.channel_gbps * 1000.0 / core_mhz;
  ctrl = ticks(cfg.controller_ns * cycles_per_ns);
  cl = tck(cfg.cl);
  trcd = tck(cfg.trcd);
  trp = tck(cfg.trp);
  tras = tck(cfg.tras);
  twtr = tck(cfg.twtr);
  trtw = tck(cfg.trtw);
  {
    const std::string problem = activateProblem(cfg);
    requireDramConfig(problem.empty(), problem.c_str());
  }
  trrd = tck(cfg.trrd);
  tfaw = tck(cfg.tfaw);
  {
    const std::vector<std::string> problems = bankGroupProblems(cfg);
    requireDramConfig(problems.empty(), problems.empty() ? "" : problems.front().c_str());
  }
  bank_groups = cfg.bank_groups;
  trrd_l = std::max(trrd, tck(cfg.trrd_l));
  twtr_l = std::max(twtr, tck(cfg.twtr_l));
  const double burst_cycles = cfg.burst_bytes / bytes_per_cycle;
  // (A non-finite or huge value would not convert to ticks: channel_gbps or core_mhz out of range.)
  requireDramConfig(burst_cycles < 1e12, "channel_gbps too low for core_mhz: one burst would take over 10^12 core cycles");
  burst = ticks(burst_cycles);
  requireDramConfig(burst >= 1, "channel_gbps too high for core_mhz: one burst would take under 2^-16 core cycles");
  ccd_s = std::max(burst, tck(cfg.tccd_s));
  ccd_l = std::max(ccd_s, tck(cfg.tccd_l));
  if (cfg.trefi_ns > 0) {
    const std::string problem = refreshProblem(cfg, core_mhz);
    requireDramConfig(problem.empty(), problem.c_str());
    refresh_period = ticks(cfg.trefi_ns * cycles_per_ns);
    refresh_rfc = ticks(cfg.trfc_ns * cycles_per_ns);
    for (unsigned c = 0; c < cfg.channels; ++c) refresh_off.push_back(refresh_period * c / cfg.channels);
    // The first burst and then one per ccd_l (the bursts back to back: (room) / burst).
    const uint64_t room = refresh_period - refresh_rfc - trcd - cl;  // >= one burst: refreshProblem
    max_run_bursts = room >= burst ? (room - burst) / ccd_l + 1 : 1;
  }
}

std::string DramTimings::activateProblem(const DramConfig& cfg) {
  if (cfg.tfaw == 0 || cfg.tfaw >= 4 * uint64_t(cfg.trrd)) return {};
  return fmt::format(
      "dram.tfaw ({} tCK) is below 4 x dram.trrd ({} tCK): four activates tRRD apart already span {} tCK, so the "
      "window could never bind (JEDEC parts have tFAW >= 4 tRRD); set dram.tfaw to 0 (no window) or at least {}",
      cfg.tfaw, cfg.trrd, 4 * uint64_t(cfg.trrd), 4 * uint64_t(cfg.trrd));
}

std::vector<std::string> DramTimings::bankGroupProblems(const DramConfig& cfg) {
  std::vector<std::string> p;
  const unsigned g = cfg.bank_groups;
  if (g == 0 || (g & (g - 1)) != 0 || cfg.banks % g != 0)
    p.push_back(fmt::format("dram.bank_groups ({}) must be a power of two dividing dram.banks ({}): each group "
                            "holds the same number of banks",
                            g, cfg.banks));
  const auto longer = [&](const char* l_name, unsigned l, const char* s_name, unsigned s) {
    if (l == 0) return;
    if (g <= 1)
      p.push_back(fmt::format("dram.{} ({} tCK) needs dram.bank_groups > 1: without bank groups every bank "
                              "keeps dram.{} ({} tCK); set dram.{} to 0 or dram.bank_groups to the part's groups",
                              l_name, l, s_name, s, l_name));
    else if (l < s)
      p.push_back(fmt::format("dram.{} ({} tCK) is below dram.{} ({} tCK): inside a bank group the spacing is at "
                              "least the one between groups; set dram.{} to 0 (no distinction) or at least {}",
                              l_name, l, s_name, s, l_name, s));
  };
  longer("tccd_l", cfg.tccd_l, "tccd_s", cfg.tccd_s);
  longer("trrd_l", cfg.trrd_l, "trrd", cfg.trrd);
  longer("twtr_l", cfg.twtr_l, "twtr", cfg.twtr);
  return p;
}

std::string DramTimings::refreshProblem(const DramConfig& cfg, double core_mhz) {
  if (cfg.trefi_ns == 0) return {};
  if (!(cfg.trefi_ns > 0) || !(cfg.trfc_ns > 0) || !(cfg.tck_ns > 0) || !(cfg.channel_gbps > 0) || !(core_mhz > 0))
    return "dram.trefi_ns > 0 needs dram.trfc_ns > 0 (and a valid clock, tCK and bandwidth)";
  // A run of bursts is placed whole between two refreshes, on a bank the
  // refresh left closed (MEMORY.md); longer runs are booked in parts, but one
  // burst must fit.
  const double cycles_per_ns = core_mhz / 1000.0;
  const auto ns = [&](double v) { return ticks(v * cycles_per_ns); };
  const uint64_t cl = ns(cfg.cl * cfg.tck_ns), trcd = ns(cfg.trcd * cfg.tck_ns);
  const uint64_t burst = ns(cfg.burst_bytes / cfg.channel_gbps);  // bytes / (GB/s) = ns
  const uint64_t run = trcd + cl + burst;
  const uint64_t period = ns(cfg.trefi_ns), rfc = ns(cfg.trfc_ns);
  if (rfc < period && period - rfc >= run) return {};
  return fmt::format(
      "dram.trefi_ns ({} ns) minus dram.trfc_ns ({} ns) must hold an activate, CL and one burst of {} bytes "
      "({:.1f} ns here)",
      cfg.trefi_ns, cfg.trfc_ns, cfg.burst_bytes, cycles(run) / cycles_per_ns);
}

}  // namespace oit::rop
