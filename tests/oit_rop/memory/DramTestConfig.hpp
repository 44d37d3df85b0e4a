// The DRAM tests' "round" configuration: every timing a whole number of core
// cycles, so expectations can be derived by hand (1000 MHz core, tCK 1 ns,
// 16 GB/s = 16 B per cycle: a 64 B burst is 4 cycles; controller 40,
// CL = tRCD = tRP = 11 cycles).
#pragma once

#include "oit_rop/Types.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop::testutil {

inline DramConfig roundDramConfig(unsigned channels) {
  DramConfig c;
  c.channels = channels;
  c.channel_gbps = 16.0;
  c.tck_ns = 1.0;
  c.cl = c.trcd = c.trp = 11;
  c.banks = 8;
  c.row_bytes = 8192;
  c.burst_bytes = 64;
  c.interleave_bytes = 256;
  c.open_row = true;
  c.controller_ns = 40.0;
  c.bank_hash = false;  // the hand-derived expectations use the plain [row | bank | column] map
  c.tras = 0;           // and no tRAS limit (tRAS has its own tests)
  c.trefi_ns = c.trfc_ns = 0;  // and no refresh (refresh has its own tests)
  return c;
}
inline constexpr double kRoundMhz = 1000.0;

// The dgpu preset the controller tests were derived on (before issue 21 made
// `dgpu` an alias of titan-x-maxwell): titan-x-maxwell's GDDR5 controller
// (the same timings, refresh, write queue and scheduler) on four channels at
// 1216 MHz, without its bank groups (as the figures were derived; their own
// tests: test_dram_bank_groups.cpp).
inline RopConfig gddr5FourChannels() {
  RopConfig c = presetConfig("titan-x-maxwell");
  c.dram.channels = 4;
  c.clock.core_mhz = 1216.0;
  c.dram.bank_groups = 1;
  c.dram.tccd_l = c.dram.trrd_l = c.dram.twtr_l = 0;
  return c;
}
inline constexpr Cycle kCtrl = 40, kCl = 11, kTrcd = 11, kTrp = 11, kBurst = 4;

}  // namespace oit::rop::testutil
