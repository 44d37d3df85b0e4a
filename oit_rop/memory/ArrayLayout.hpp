// Where the per-pixel blending arrays live in memory, and which cache lines
// and sectors an access to some of a pixel's bytes touches (MEMORY.md,
// "Per-pixel arrays in memory").
//
// A screen tile's arrays are one region of tileStride() bytes (the tile's
// pixels x bytes per pixel, rounded up to whole cache lines, so no line holds
// two tiles: tiles of different partitions never share a ROP-cache line);
// tile t's region starts at t x tileStride(). Inside it:
//  - pixel_major: pixel i's array (tile order, i = y_in_tile x tile width +
//    x_in_tile) at i x bytes per pixel;
//  - row_major: row r of every pixel contiguous, row r of pixel i at
//    r x T x R + i x R (T tile pixels, R bytes per row); the extra words form
//    one more row after them (pixel i's at rows x T x R + i x E).
// Byte b of a pixel's array is the state's own order (model::StateRanges).
#pragma once

#include <cstdint>
#include <vector>

#include "model/OitAlgorithm.hpp"
#include "oit_rop/config/RopConfig.hpp"

namespace oit::rop {

// One cache line an access touches: its number inside the tile's region and
// its sectors (bit s = sector s of the line).
struct LineTouch {
  uint32_t line = 0;
  uint32_t fill = 0;   // sectors that must be present: read, or written only in part (the rest is kept)
  uint32_t dirty = 0;  // sectors written
  bool operator==(const LineTouch&) const = default;
};

class ArrayLayout {
 public:
  // Throws std::invalid_argument for a sector that does not divide the line
  // or more than 32 sectors per line (config-checked before).
  ArrayLayout(const model::StateLayout& layout, uint32_t bytes_per_pixel, uint32_t tile_pixels, ArrayLayoutKind kind,
              uint32_t line_bytes, uint32_t sector_bytes);

  uint32_t bytesPerPixel() const { return bytes_per_pixel_; }
  uint32_t tileBytes() const { return tile_pixels_ * bytes_per_pixel_; }
  uint32_t tileStride() const { return stride_; }  // tileBytes() rounded up to whole lines
  uint32_t linesPerTile() const { return stride_ / line_bytes_; }
  uint32_t lineBytes() const { return line_bytes_; }
  uint32_t sectorBytes() const { return sector_bytes_; }
  uint32_t sectorsPerLine() const { return line_bytes_ / sector_bytes_; }
  uint32_t allSectors() const { return all_sectors_; }  // the mask of every sector of a line
  // Where byte `byte` of pixel `pixel`'s array is, from the start of the tile's region.
  uint32_t offsetOf(uint32_t pixel, uint32_t byte) const;
  // The lines (in increasing order) an access of pixel `pixel` touches that
  // reads `read` and writes `write` of its array.
  std::vector<LineTouch> touches(uint32_t pixel, const model::StateRanges& read,
                                 const model::StateRanges& write) const;
  // Ors into fill_by_line[l] (one entry per line of the tile) the sectors
  // holding bytes [0, bytes) of pixel `pixel`'s array (a read, e.g. the resolve's).
  void addPrefixRead(uint32_t pixel, uint32_t bytes, uint32_t* fill_by_line) const;

 private:
  // Calls fn(offset, length) for each contiguous piece of [begin, end) of the pixel's array.
  template <class Fn>
  void pieces(uint32_t pixel, uint32_t begin, uint32_t end, Fn&& fn) const;

  uint32_t bytes_per_pixel_, tile_pixels_, row_bytes_, rows_, line_bytes_, sector_bytes_;
  ArrayLayoutKind kind_;
  uint32_t stride_ = 0, all_sectors_ = 0;
};

// Per (pass, fragment kind, pixel of the tile): the lines one insert touches,
// from the algorithm's read/write ranges. Kind = InRec's: the outcome (0..2),
// or 4 for a fragment culled late (it reads what a Stored insert of the pass
// reads and writes nothing). Built once per run; shared by the partitions.
class FragmentLines {
 public:
  static constexpr unsigned kKinds = 8;  // InRec::outcome & 7
  FragmentLines(const model::OitAlgorithm& algo, const ArrayLayout& layout, uint32_t tile_pixels);
  struct Span {
    const LineTouch* begin;
    uint32_t count;
  };
  Span lines(unsigned pass, unsigned kind, uint32_t pixel) const {
    const Index& ix = index_[(size_t(pass) * kKinds + kind) * tile_pixels_ + pixel];
    return {touches_.data() + ix.first, ix.count};
  }
  // The most lines one insert touches, and the most of them in one set of a
  // cache with `sets` sets whose set index is (tile x lines per tile + line) mod sets.
  uint32_t maxLines() const { return max_lines_; }
  uint32_t maxLinesInOneSet(uint32_t sets) const;

 private:
  struct Index {
    uint32_t first, count;
  };
  uint32_t tile_pixels_;
  std::vector<Index> index_;
  std::vector<LineTouch> touches_;
  uint32_t max_lines_ = 0;
};

}  // namespace oit::rop
