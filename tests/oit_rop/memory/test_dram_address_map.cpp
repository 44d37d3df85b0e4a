// DramAddressMap: channel, bank and row of a byte address (MEMORY.md,
// "address mapping"), by hand on the round configuration (8 KiB rows, 8
// banks, 256 B channel interleave).
#include <gtest/gtest.h>

#include <vector>

#include "oit_rop/memory/DramAddressMap.hpp"
#include "oit_rop/memory/DramTestConfig.hpp"

namespace oit::rop {
namespace {

using testutil::roundDramConfig;

TEST(DramAddressMap, ChannelBankAndRowByHand) {
  const DramAddressMap m(roundDramConfig(4));
  // Channel from the interleave bits.
  EXPECT_EQ(m.locate(0).channel, 0u);
  EXPECT_EQ(m.locate(255).channel, 0u);
  EXPECT_EQ(m.locate(256).channel, 1u);
  EXPECT_EQ(m.locate(3 * 256 + 17).channel, 3u);
  EXPECT_EQ(m.locate(4 * 256).channel, 0u);
  // Channel-local address 8192 (bank 1) = global chunk 32 * 4 -> 32768.
  EXPECT_EQ(m.locate(32767).bank, 0u);
  EXPECT_EQ(m.locate(32768).bank, 1u);
  EXPECT_EQ(m.locate(32768).row, 0u);
  // Local 8 banks * 8 KiB = 64 KiB -> row 1 of bank 0 at global 256 KiB.
  EXPECT_EQ(m.locate(256 * 1024).bank, 0u);
  EXPECT_EQ(m.locate(256 * 1024).row, 1u);
  EXPECT_EQ(m.locate(256 * 1024).channel, 0u);
  EXPECT_TRUE(m.pow2);
  EXPECT_EQ(m.chunk_bursts.d, 4u);
  EXPECT_EQ(m.row_bursts.d, 128u);
}

TEST(DramAddressMap, NonPowerOfTwoGeometry) {
  DramConfig c = roundDramConfig(3);
  c.banks = 6;
  const DramAddressMap m(c);
  EXPECT_FALSE(m.pow2);
  EXPECT_EQ(m.locate(5 * 256).channel, 2u);
  // Local 6 * 8 KiB = 48 KiB per row index; global = local * 3.
  EXPECT_EQ(m.locate(3 * 48 * 1024).row, 1u);
  EXPECT_EQ(m.locate(3 * 48 * 1024).bank, 0u);
  EXPECT_EQ(m.locate(3 * 8 * 1024).bank, 1u);
}

// dram.bank_hash: for a fixed row the bank map stays a bijection (a stream
// still walks every bank), and the row's bits move the bank.
TEST(DramAddressMap, BankHashPermutesTheBanksOfEveryRow) {
  for (unsigned banks : {8u, 6u}) {
    DramConfig c = roundDramConfig(1);
    c.banks = banks;
    c.bank_hash = true;
    const DramAddressMap m(c);
    const uint64_t row_group = uint64_t(banks) * c.row_bytes;  // one row index across the banks
    for (uint64_t row : {uint64_t(0), uint64_t(1), uint64_t(5), uint64_t(1) << 20, (uint64_t(1) << 27) + 3}) {
      std::vector<int> seen(banks, 0);
      for (unsigned b = 0; b < banks; ++b) {
        const uint64_t addr = row * row_group + uint64_t(b) * c.row_bytes;
        ASSERT_EQ(m.locate(addr).row, row);
        ++seen[m.locate(addr).bank];
      }
      for (unsigned b = 0; b < banks; ++b) EXPECT_EQ(seen[b], 1) << banks << " banks, row " << row << ", bank " << b;
    }
  }
  // By hand: 8 banks, row 1 -> bank index XOR 1; row 2^20 -> XOR (1 << (20 % 3)) = 4.
  DramConfig c = roundDramConfig(1);
  c.bank_hash = true;
  const DramAddressMap m(c);
  EXPECT_EQ(m.locate(65536).bank, 1u);
  EXPECT_EQ(m.locate(65536 + 3 * 8192).bank, 2u);
  EXPECT_EQ(m.locate(uint64_t(65536) << 20).bank, 4u);
  // 6 banks (digit sum): row 7 = digits 1, 1 -> bank index + 2 (mod 6).
  c.banks = 6;
  const DramAddressMap six(c);
  EXPECT_EQ(six.locate(7 * 6 * 8192 + 5 * 8192).bank, (5u + 2u) % 6u);
}

TEST(DramDivisor, ShiftsForPowersOfTwoAndDividesOtherwise) {
  DramDivisor d;
  d.set(64);
  EXPECT_EQ(d.shift, 6);
  EXPECT_EQ(d.div(130), 2u);
  EXPECT_EQ(d.mod(130), 2u);
  EXPECT_EQ(d.div<true>(130), 2u);
  d.set(6);
  EXPECT_EQ(d.shift, -1);
  EXPECT_EQ(d.div(130), 21u);
  EXPECT_EQ(d.mod(130), 4u);
  EXPECT_EQ(d.div<false>(130), 21u);
}

}  // namespace
}  // namespace oit::rop
