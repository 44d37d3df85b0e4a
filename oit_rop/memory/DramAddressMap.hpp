// Where a byte address lives in the DRAM: channel, bank and row
// (addr = [row | bank | column-high | channel | column-low], optionally with
// the row XOR-folded into the bank: dram.bank_hash). Formulas in MEMORY.md.
// The controller (MemorySystem) works on bursts: a request's bursts on one
// channel are one range of that channel's local bursts, so it needs the
// divisors below more than locate().
#pragma once

#include <cstdint>

#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

// Division by a configuration constant; a shift/mask when it is a power of two.
struct DramDivisor {
  uint64_t d = 1;
  uint64_t mask = 0;  // d - 1
  int shift = 0;      // -1: not a power of two
  void set(uint64_t v);
  uint64_t div(uint64_t x) const { return shift >= 0 ? x >> shift : x / d; }
  uint64_t mod(uint64_t x) const { return shift >= 0 ? x & mask : x % d; }
  // Pow2: the caller knows d is a power of two (no test per operation).
  template <bool Pow2>
  uint64_t div(uint64_t x) const { return Pow2 ? x >> shift : div(x); }
  template <bool Pow2>
  uint64_t mod(uint64_t x) const { return Pow2 ? x & mask : mod(x); }
};

struct DramLocation {
  unsigned channel;
  unsigned bank;
  uint64_t row;
};

struct DramAddressMap {
  DramDivisor burst, interleave, channel, row, bank;
  // In bursts: an interleave chunk, a row (the controller works on burst numbers).
  DramDivisor chunk_bursts, row_bursts;
  bool multi_channel = false;  // chunks rotate over several channels
  bool hash = false;           // DramConfig::bank_hash and more than one bank
  bool pow2 = false;           // burst, chunk, channels, row and banks all powers of two

  // Needs interleave_bytes and row_bytes multiples of burst_bytes (checked by MemorySystem).
  explicit DramAddressMap(const DramConfig& cfg);
  DramLocation locate(uint64_t addr) const;

  // Bank (hashed when `hash`, dram.bank_hash) and row of a channel's row line
  // (its local address / row_bytes); the channel is the caller's.
  template <bool Pow2>
  void bankRow(uint64_t row_line, unsigned& bank_out, uint64_t& row_out) const {
    uint64_t bk = bank.mod<Pow2>(row_line);
    const uint64_t rw = bank.div<Pow2>(row_line);
    // Permutation interleaving (dram.bank_hash): the row's bank-sized digit
    // groups are XORed into the bank (banks a power of two; else their sum is
    // added, mod banks). For a fixed row the map stays a bijection of the banks,
    // so a sequential stream still walks all of them, but streams whose
    // addresses differ only in high bits (one region per partition and
    // surface) stop meeting in one bank on different rows.
    if (hash) {
      if (bank.shift > 0) {
        for (uint64_t r = rw; r != 0; r >>= bank.shift) bk ^= r & bank.mask;
      } else {
        uint64_t sum = bk;
        for (uint64_t r = rw; r != 0; r = bank.div(r)) sum += bank.mod(r);
        bk = bank.mod(sum);
      }
    }
    bank_out = static_cast<unsigned>(bk);
    row_out = rw;
  }
};

}  // namespace oit::rop
