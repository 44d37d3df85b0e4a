#include "oit_rop/memory/DramAddressMap.hpp"

namespace oit::rop {

void DramDivisor::set(uint64_t v) {
  d = v;
  mask = v - 1;
  shift = -1;
  if (v != 0 && (v & (v - 1)) == 0) {
    shift = 0;
    while ((uint64_t(1) << shift) != v) ++shift;
  }
}

DramAddressMap::DramAddressMap(const DramConfig& cfg) {
  burst.set(cfg.burst_bytes);
  interleave.set(cfg.interleave_bytes);
  channel.set(cfg.channels);
  row.set(cfg.row_bytes);
  bank.set(cfg.banks);
  chunk_bursts.set(cfg.burst_bytes ? cfg.interleave_bytes / cfg.burst_bytes : 1);
  row_bursts.set(cfg.burst_bytes ? cfg.row_bytes / cfg.burst_bytes : 1);
  multi_channel = cfg.channels > 1;
  hash = cfg.bank_hash && cfg.banks > 1;
  pow2 = burst.shift >= 0 && chunk_bursts.shift >= 0 && channel.shift >= 0 && row_bursts.shift >= 0 &&
         bank.shift >= 0;
}

DramLocation DramAddressMap::locate(uint64_t addr) const {
  // addr = [row | bank | column-high | channel | column-low(interleave)]
  const uint64_t chunk = interleave.div(addr);
  const uint64_t local = channel.div(chunk) * interleave.d + interleave.mod(addr);
  DramLocation loc{static_cast<unsigned>(channel.mod(chunk)), 0, 0};
  bankRow<false>(row.div(local), loc.bank, loc.row);
  return loc;
}

}  // namespace oit::rop
