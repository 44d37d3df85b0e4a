// Where the per-pixel arrays' bytes are (pixel_major / row_major) and which
// cache lines and sectors an insert touches; every expected value is worked
// out by hand in the comments (MEMORY.md, "Per-pixel arrays in memory").
#include <gtest/gtest.h>

#include "model/OitAlgorithm.hpp"
#include "model/StorageFormat.hpp"
#include "oit_rop/memory/ArrayLayout.hpp"

using namespace oit;
using namespace oit::rop;

namespace {

// mlab k = 4 rgba8t8z32: 4 rows of 8 B, 32 B per pixel; 8x8 tiles.
model::StateLayout rgba8Rows(unsigned rows) { return {rows, model::StorageFormat::Rgba8T8Z32, 0, ""}; }

}  // namespace

TEST(ArrayLayout, PixelMajorAndRowMajorAddresses) {
  const ArrayLayout pm(rgba8Rows(4), 32, 64, ArrayLayoutKind::PixelMajor, 64, 0);
  const ArrayLayout rm(rgba8Rows(4), 32, 64, ArrayLayoutKind::RowMajor, 64, 0);
  EXPECT_EQ(pm.tileStride(), 2048u);  // 64 px x 32 B, already whole lines
  EXPECT_EQ(pm.linesPerTile(), 32u);
  // Pixel 5, byte 20 (row 2, byte 4): pixel-major 5 x 32 + 20; row-major row 2
  // of the tile at 2 x 64 x 8 = 1024, pixel 5's at + 40, byte 4 of it.
  EXPECT_EQ(pm.offsetOf(5, 20), 180u);
  EXPECT_EQ(rm.offsetOf(5, 20), 1024u + 40 + 4);
  // Extra words after the rows (hybrid rgba8 k = 4: 3 rows + an 8-byte tail):
  // row-major keeps them as one more row, pixel i's at 3 x 64 x 8 + 8 i.
  const ArrayLayout hy({3, model::StorageFormat::Rgba8T8Z32, 2, "tail"}, 32, 64, ArrayLayoutKind::RowMajor, 64, 0);
  EXPECT_EQ(hy.offsetOf(5, 24), 1536u + 40);
  // A tile that is not whole lines is rounded up: 64 px x 36 B = 2304 B -> 2304 (36 lines of 64 B);
  // with 1024-byte lines 3 lines (3072 B).
  EXPECT_EQ(ArrayLayout({0, model::StorageFormat::Fp32, 9, ""}, 36, 64, ArrayLayoutKind::PixelMajor, 1024, 0)
                .tileStride(),
            3072u);
}

TEST(ArrayLayout, AnInsertTouchesTheLinesHoldingItsBytes) {
  const ArrayLayout pm(rgba8Rows(4), 32, 64, ArrayLayoutKind::PixelMajor, 64, 0);
  const ArrayLayout rm(rgba8Rows(4), 32, 64, ArrayLayoutKind::RowMajor, 64, 0);
  const model::StateRanges all = model::StateRanges::one(0, 32);
  // Pixel-major: pixel 5's 32 bytes are [160, 192): line 2, read and written whole.
  EXPECT_EQ(pm.touches(5, all, all), (std::vector<LineTouch>{{2, 1, 1}}));
  // Row-major: row r of pixel 5 at r x 512 + 40: lines 0, 8, 16, 24 (8 pixels' row r per line).
  EXPECT_EQ(rm.touches(5, all, all), (std::vector<LineTouch>{{0, 1, 1}, {8, 1, 1}, {16, 1, 1}, {24, 1, 1}}));
  // A k-buffer rejection reads the last row only: one line in row-major.
  EXPECT_EQ(rm.touches(5, model::StateRanges::one(24, 32), {}), (std::vector<LineTouch>{{24, 1, 0}}));
}

TEST(ArrayLayout, SectorsWrittenInPartNeedTheirOtherBytes) {
  // 64-byte lines of 16-byte sectors, pixel-major, 32 B per pixel: pixel 1 is
  // bytes [32, 64) of line 0 = sectors 2 and 3.
  const ArrayLayout pm(rgba8Rows(4), 32, 64, ArrayLayoutKind::PixelMajor, 64, 16);
  // Write [8, 24) of pixel 1 = line bytes [40, 56): sector 2 (32..47) in part,
  // sector 3 (48..63) in part: both must be fetched; nothing else is read.
  EXPECT_EQ(pm.touches(1, {}, model::StateRanges::one(8, 24)), (std::vector<LineTouch>{{0, 0b1100, 0b1100}}));
  // Write [0, 16) = sector 2 wholly: no fetch.
  EXPECT_EQ(pm.touches(1, {}, model::StateRanges::one(0, 16)), (std::vector<LineTouch>{{0, 0, 0b0100}}));
  // Two ranges (adaptive-like): read [0, 8) and [16, 24), write [16, 24): sectors 2 and 3 read, 3 written.
  EXPECT_EQ(pm.touches(1, model::StateRanges::two(0, 8, 16, 24), model::StateRanges::one(16, 24)),
            (std::vector<LineTouch>{{0, 0b1100, 0b1000}}));
}

TEST(ArrayLayout, ResolvePrefixReadsTheLinesOfItsRows) {
  const ArrayLayout rm(rgba8Rows(4), 32, 64, ArrayLayoutKind::RowMajor, 64, 0);
  std::vector<uint32_t> fill(rm.linesPerTile(), 0);
  // Pixel 9 needs two rows (16 bytes): rows 0 and 1 of pixels 8..15: lines 1 and 9.
  rm.addPrefixRead(9, 16, fill.data());
  for (uint32_t l = 0; l < fill.size(); ++l) EXPECT_EQ(fill[l], (l == 1 || l == 9) ? 1u : 0u) << l;
}

TEST(FragmentLines, PerPassKindAndPixel) {
  model::AlgorithmParams p;
  p.layers = 4;
  p.format = model::StorageFormat::Rgba8T8Z32;
  const auto kb = model::makeAlgorithm("kbuffer", p);
  const ArrayLayout rm(kb->layout(), kb->bytesPerPixel(), 64, ArrayLayoutKind::RowMajor, 64, 0);
  const FragmentLines lines(*kb, rm, 64);
  // Stored: four rows read and written; Discarded (a rejection): the last row, read only;
  // culled late (kind 4): what Stored reads, nothing written.
  EXPECT_EQ(lines.lines(0, 0, 5).count, 4u);
  ASSERT_EQ(lines.lines(0, 2, 5).count, 1u);
  EXPECT_EQ(*lines.lines(0, 2, 5).begin, (LineTouch{24, 1, 0}));
  ASSERT_EQ(lines.lines(0, 4, 5).count, 4u);
  EXPECT_EQ(lines.lines(0, 4, 5).begin[3].dirty, 0u);
  EXPECT_EQ(lines.maxLines(), 4u);
  // Lines 0, 8, 16, 24 of one insert: with 8 sets they all share set 0, with 16 two per set.
  EXPECT_EQ(lines.maxLinesInOneSet(8), 4u);
  EXPECT_EQ(lines.maxLinesInOneSet(16), 2u);
  EXPECT_EQ(lines.maxLinesInOneSet(32), 1u);
  // fp32 mlab (80 B per pixel) in pixel-major 64-byte lines: an array spans two lines.
  model::AlgorithmParams f = p;
  f.format = model::StorageFormat::Fp32;
  const auto ml = model::makeAlgorithm("mlab", f);
  const ArrayLayout pm(ml->layout(), ml->bytesPerPixel(), 64, ArrayLayoutKind::PixelMajor, 64, 0);
  EXPECT_EQ(FragmentLines(*ml, pm, 64).maxLines(), 2u);
}
