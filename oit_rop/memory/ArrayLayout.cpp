// Addresses of the per-pixel arrays and the lines/sectors an access touches (MEMORY.md).
#include "oit_rop/memory/ArrayLayout.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <map>
#include <stdexcept>

#include "model/StorageFormat.hpp"

namespace oit::rop {

ArrayLayout::ArrayLayout(const model::StateLayout& layout, uint32_t bytes_per_pixel, uint32_t tile_pixels,
                         ArrayLayoutKind kind, uint32_t line_bytes, uint32_t sector_bytes)
    : bytes_per_pixel_(bytes_per_pixel),
      tile_pixels_(tile_pixels),
      row_bytes_(model::rowBytes(layout.format)),
      rows_(layout.rows),
      line_bytes_(line_bytes),
      sector_bytes_(sector_bytes ? sector_bytes : line_bytes),
      kind_(kind) {
  if (line_bytes_ == 0 || tile_pixels_ == 0 || bytes_per_pixel_ == 0)
    throw std::invalid_argument("ArrayLayout: line, tile and pixel sizes must be > 0");
  if (sector_bytes_ > line_bytes_ || line_bytes_ % sector_bytes_ != 0 || line_bytes_ / sector_bytes_ > 32)
    throw std::invalid_argument(fmt::format(
        "ArrayLayout: the sector ({} bytes) must divide the line ({} bytes) into at most 32 sectors", sector_bytes_,
        line_bytes_));
  if (uint64_t(rows_) * row_bytes_ > bytes_per_pixel_)
    throw std::invalid_argument("ArrayLayout: the layout's rows exceed the bytes per pixel");
  const uint64_t stride = (uint64_t(tile_pixels_) * bytes_per_pixel_ + line_bytes_ - 1) / line_bytes_ * line_bytes_;
  if (stride > UINT32_MAX) throw std::invalid_argument("ArrayLayout: one tile's arrays exceed 4 GiB");
  stride_ = uint32_t(stride);
  const uint32_t sectors = line_bytes_ / sector_bytes_;
  all_sectors_ = sectors == 32 ? ~0u : (1u << sectors) - 1;
}

uint32_t ArrayLayout::offsetOf(uint32_t pixel, uint32_t byte) const {
  if (kind_ == ArrayLayoutKind::PixelMajor) return pixel * bytes_per_pixel_ + byte;
  const uint32_t row_part = rows_ * row_bytes_;
  if (byte < row_part) {
    const uint32_t r = byte / row_bytes_;
    return r * tile_pixels_ * row_bytes_ + pixel * row_bytes_ + byte % row_bytes_;
  }
  return row_part * tile_pixels_ + pixel * (bytes_per_pixel_ - row_part) + (byte - row_part);
}

template <class Fn>
void ArrayLayout::pieces(uint32_t pixel, uint32_t begin, uint32_t end, Fn&& fn) const {
  if (end <= begin) return;
  if (kind_ == ArrayLayoutKind::PixelMajor) {
    fn(offsetOf(pixel, begin), end - begin);
    return;
  }
  // Row-major: each row is contiguous (R bytes), the extra words too.
  const uint32_t row_part = rows_ * row_bytes_;
  uint32_t b = begin;
  while (b < end) {
    const uint32_t piece_end = b < row_part ? std::min(end, (b / row_bytes_ + 1) * row_bytes_) : end;
    fn(offsetOf(pixel, b), piece_end - b);
    b = piece_end;
  }
}

std::vector<LineTouch> ArrayLayout::touches(uint32_t pixel, const model::StateRanges& read,
                                            const model::StateRanges& write) const {
  // Per line: sectors read, sectors written and the bytes written in each sector.
  struct Acc {
    uint32_t read = 0, written = 0;
    std::vector<uint32_t> written_bytes;
  };
  std::map<uint32_t, Acc> lines;
  const auto mark = [&](uint32_t off, uint32_t len, bool is_write) {
    for (uint32_t o = off; o < off + len;) {
      const uint32_t line = o / line_bytes_, in_line = o % line_bytes_;
      const uint32_t sector = in_line / sector_bytes_;
      const uint32_t n = std::min(off + len - o, sector_bytes_ - in_line % sector_bytes_);
      Acc& a = lines[line];
      if (is_write) {
        a.written |= 1u << sector;
        a.written_bytes.resize(line_bytes_ / sector_bytes_, 0);
        a.written_bytes[sector] += n;
      } else {
        a.read |= 1u << sector;
      }
      o += n;
    }
  };
  for (unsigned i = 0; i < read.count; ++i)
    pieces(pixel, read.range[i].begin, read.range[i].end, [&](uint32_t off, uint32_t len) { mark(off, len, false); });
  for (unsigned i = 0; i < write.count; ++i)
    pieces(pixel, write.range[i].begin, write.range[i].end, [&](uint32_t off, uint32_t len) { mark(off, len, true); });
  std::vector<LineTouch> out;
  for (const auto& [line, a] : lines) {
    uint32_t partial = 0;  // written sectors not wholly overwritten: the rest must be fetched
    for (uint32_t s = 0; s < a.written_bytes.size(); ++s)
      if ((a.written >> s & 1) && a.written_bytes[s] < sector_bytes_) partial |= 1u << s;
    out.push_back({line, a.read | partial, a.written});
  }
  return out;
}

void ArrayLayout::addPrefixRead(uint32_t pixel, uint32_t bytes, uint32_t* fill_by_line) const {
  pieces(pixel, 0, std::min(bytes, bytes_per_pixel_), [&](uint32_t off, uint32_t len) {
    for (uint32_t o = off; o < off + len;) {
      const uint32_t in_line = o % line_bytes_;
      fill_by_line[o / line_bytes_] |= 1u << (in_line / sector_bytes_);
      o += std::min(off + len - o, sector_bytes_ - in_line % sector_bytes_);
    }
  });
}

FragmentLines::FragmentLines(const model::OitAlgorithm& algo, const ArrayLayout& layout, uint32_t tile_pixels)
    : tile_pixels_(tile_pixels) {
  const unsigned passes = algo.passes();
  index_.resize(size_t(passes) * kKinds * tile_pixels);
  for (unsigned pass = 0; pass < passes; ++pass)
    for (unsigned kind = 0; kind < kKinds; ++kind) {
      // Kinds 3, 5, 6, 7 never occur (InRec: outcome 0..2, culled 4); they get no lines.
      model::StateRanges read, write;
      if (kind < model::kOutcomeCount) {
        read = algo.readRanges(pass, model::InsertOutcome(kind));
        write = algo.writeRanges(pass, model::InsertOutcome(kind));
      } else if (kind == 4) {
        read = algo.readRanges(pass, model::InsertOutcome::Stored);  // a late cull reads, then drops
      }
      for (uint32_t px = 0; px < tile_pixels; ++px) {
        const std::vector<LineTouch> t = layout.touches(px, read, write);
        index_[(size_t(pass) * kKinds + kind) * tile_pixels + px] = {uint32_t(touches_.size()), uint32_t(t.size())};
        touches_.insert(touches_.end(), t.begin(), t.end());
        max_lines_ = std::max(max_lines_, uint32_t(t.size()));
      }
    }
}

uint32_t FragmentLines::maxLinesInOneSet(uint32_t sets) const {
  // Two lines of one access share a set when their numbers differ by a
  // multiple of `sets` (the tile's base line shifts both alike).
  uint32_t worst = 0;
  std::map<uint32_t, uint32_t> per_set;
  for (const Index& ix : index_) {
    per_set.clear();
    for (uint32_t i = 0; i < ix.count; ++i) worst = std::max(worst, ++per_set[touches_[ix.first + i].line % sets]);
  }
  return worst;
}

}  // namespace oit::rop
