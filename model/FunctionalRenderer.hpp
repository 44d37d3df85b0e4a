// The functional golden model's frame loop: one rule set for every algorithm.
//  - API order = record order (the per-pixel order an ordered pixel lock keeps).
//  - Opaque draws (header draw table) first build a depth buffer (test LESS,
//    so the first of equal-depth opaque fragments wins) and its colour, in a
//    pre-pass over the opaque fragments. The depth buffer starts at +inf, so
//    every opaque fragment with z in [0,1] lands.
//  - A transparent fragment at or behind the final opaque depth is culled.
//  - The rest go to the algorithm in submission order, once per pass (the
//    source is rewound per pass); equal depths: the later one is in front
//    (each algorithm implements this).
//  - Resolve composites over the opaque colour, or over the clear colour where
//    no opaque fragment landed. All compositing is linear.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "model/Image.hpp"
#include "model/OitAlgorithm.hpp"
#include "traces/TraceIO.hpp"

namespace oit::model {

// Uninitialised, 2 MiB-aligned storage for the per-pixel state words; large
// buffers ask for transparent huge pages (first touch of tens of MB in 4 KiB
// pages was a third of a 1280x720 mlab render, and inserts land per quad all
// over the frame: fewer TLB misses).
class StateBuffer {
 public:
  explicit StateBuffer(size_t words);
  ~StateBuffer();
  StateBuffer(const StateBuffer&) = delete;
  StateBuffer& operator=(const StateBuffer&) = delete;
  uint32_t* data() { return p_; }
  const uint32_t* data() const { return p_; }
  size_t size() const { return size_; }

 private:
  uint32_t* p_ = nullptr;
  size_t size_ = 0;
};

// Opaque / transparent lookup of draw ids from the header's draw table.
class DrawClassifier {
 public:
  explicit DrawClassifier(const TraceHeader& header);
  // Throws std::runtime_error for a draw id missing from the table.
  bool isOpaque(uint32_t draw) const {
    if (draw < dense_.size() && dense_[draw] != kUnknown) return dense_[draw] == kOpaque;
    return lookupSparse(draw);
  }
  bool anyOpaque() const { return any_opaque_; }

 private:
  static constexpr uint8_t kUnknown = 0, kOpaque = 1, kTransparent = 2;
  bool lookupSparse(uint32_t draw) const;
  std::vector<uint8_t> dense_;                    // ids below 2^20
  std::unordered_map<uint32_t, bool> sparse_;     // larger ids
  bool any_opaque_ = false;
};

// DrawClassifier::isOpaque remembered for the last draw id: traces come in
// long runs of one draw, so the per-record loops classify once per run (the
// lookup's loads cannot be hoisted past the loops' stores). Same answers, and
// an unknown draw still throws at its first record.
class DrawRun {
 public:
  explicit DrawRun(const DrawClassifier& classes) : classes_(classes) {}
  bool isOpaque(uint32_t draw) {
    if (!have_ || draw != draw_) {
      opaque_ = classes_.isOpaque(draw);
      draw_ = draw;
      have_ = true;
    }
    return opaque_;
  }

 private:
  const DrawClassifier& classes_;
  uint32_t draw_ = 0;
  bool opaque_ = false, have_ = false;
};

// Result of the opaque pre-pass (also what the timing model needs).
struct OpaqueLayer {
  uint32_t width = 0, height = 0;
  std::vector<float> depth;  // +inf where no opaque fragment landed
  std::vector<Rgb> colour;   // straight rgb of the winning opaque fragment
  uint64_t fragments = 0;    // opaque fragments seen
  bool landed(size_t pixel) const { return depth[pixel] != std::numeric_limits<float>::infinity(); }
};
// Rewinds the source and reads it once. Throws std::runtime_error for a
// fragment outside the frame or of an unknown draw.
OpaqueLayer buildOpaqueLayer(FragmentSource& src, const DrawClassifier& classes);

namespace detail {
// Throws the "outside the WxH frame" error naming the source and the fragment.
[[noreturn]] void fragmentOutsideFrame(const FragmentSource& src, uint64_t index, const Fragment& f, uint32_t w,
                                       uint32_t h);
}
// buildOpaqueLayer() that also calls on_opaque(f) for every opaque fragment of
// the read (the timing model counts its per-partition work there instead of
// reading the trace again). A template, so the call is inlined: the pre-pass
// reads every record, and a std::function call per opaque fragment showed in
// its profile.
template <class OnOpaque>
OpaqueLayer buildOpaqueLayerWith(FragmentSource& src, const DrawClassifier& classes, OnOpaque&& on_opaque) {
  const TraceHeader& hd = src.header();
  const uint32_t w = hd.width, h = hd.height;
  OpaqueLayer o;
  o.width = w;
  o.height = h;
  const size_t n = size_t(w) * h;
  o.depth.assign(n, std::numeric_limits<float>::infinity());
  o.colour.assign(n, Rgb{0, 0, 0});
  if (!classes.anyOpaque()) return o;
  src.rewind();
  float* const depth = o.depth.data();
  Rgb* const colour = o.colour.data();
  uint64_t index = 0, fragments = 0;
  DrawRun draws(classes);
  for (auto batch = src.next(); !batch.empty(); batch = src.next()) {
    for (const Fragment& f : batch) {
      if (f.x >= w || f.y >= h) [[unlikely]]
        detail::fragmentOutsideFrame(src, index, f, w, h);
      ++index;
      if (!draws.isOpaque(f.draw)) continue;
      ++fragments;
      on_opaque(f);
      const size_t p = size_t(f.y) * w + f.x;
      if (f.z < depth[p]) {  // LESS: the first of equal depths wins
        depth[p] = f.z;
        colour[p] = Rgb{f.r, f.g, f.b};
      }
    }
  }
  o.fragments = fragments;
  return o;
}

struct RenderProgress {
  unsigned pass;            // 0 = opaque pre-pass, 1.. = algorithm pass + 1
  unsigned passes;          // total source passes (1 + algorithm passes)
  std::string_view what;    // "opaque" or the algorithm's pass name
  uint64_t fragments_done;  // in this pass
  uint64_t fragments_total; // header fragment count (0 if unknown)
};

struct RenderOptions {
  Rgb clear_colour{0.0f, 0.0f, 0.0f};
  // Called every ~progress_every fragments and at the end of every pass.
  std::function<void(const RenderProgress&)> progress;
  uint64_t progress_every = uint64_t(1) << 22;
};

struct RenderCounts {
  uint64_t fragments_in = 0;  // records read (one pass)
  uint64_t opaque = 0;
  uint64_t culled = 0;        // transparent at or behind the final opaque depth
  // Outcomes of the algorithm's first pass (where storage is decided).
  uint64_t stored = 0, merged = 0, discarded = 0;
  // outcomes[pass][InsertOutcome] for every algorithm pass.
  std::vector<std::array<uint64_t, kOutcomeCount>> pass_outcomes;
  uint64_t bytes_read = 0, bytes_written = 0;  // per-pixel state traffic, all passes
  unsigned source_passes = 0;                  // times the source was read

  bool balanced() const { return opaque + culled + stored + merged + discarded == fragments_in; }
};

struct RenderResult {
  Image image;
  RenderCounts counts;
  uint64_t state_bytes = 0;  // per-pixel state (W x H x bytesPerPixel) + pool
};

// renderInBands(): how much memory one band may take, and where the band
// file goes when there is more than one band.
struct BandOptions {
  // Most bytes of one band's per-pixel words and pool (the A-buffer: 4 B per
  // pixel, 24 B per fragment that reaches it).
  uint64_t limit_bytes = uint64_t(1) << 30;
  // Folder of the unnamed temporary band file (a frame in several bands).
  std::string spill_dir = ".";
};

struct BandedRender {
  RenderResult result;
  unsigned bands = 1;
  uint64_t largest_band_bytes = 0;  // per-pixel words + pool of the largest band
  uint64_t spill_bytes = 0;         // size of the band file (0: one band, read from the trace)
};

// Splits the pixels (row-major) into consecutive ranges whose words
// (bytes_per_pixel each) and pool (bytes_per_fragment per fragment counted at
// the pixel) fit `limit`; returns the first pixel of each range. Throws
// std::runtime_error when one pixel alone does not fit.
std::vector<uint64_t> planBands(const std::vector<uint32_t>& fragments_per_pixel, uint32_t width,
                                uint64_t bytes_per_pixel, uint64_t bytes_per_fragment, uint64_t limit);

class FunctionalRenderer {
 public:
  explicit FunctionalRenderer(RenderOptions options = {}) : opt_(std::move(options)) {}
  // Throws std::runtime_error on a bad fragment (outside the frame, unknown
  // draw) and whatever the algorithm's beginFrame throws.
  RenderResult render(FragmentSource& src, OitAlgorithm& algo) const;

  // render() of a single-pass algorithm (the A-buffer reference) in bands of
  // pixels that each fit BandOptions::limit_bytes, so its pool never holds
  // more than one band's fragments, whatever the trace's length:
  //  - one band, read straight from the trace, when the whole frame fits
  //    (the trace's fragment count bounds the pool; else a counting pass
  //    decides);
  //  - else one pass copies every fragment that reaches the algorithm into
  //    its band's part of an unnamed temporary file in spill_dir (32 B per
  //    fragment; it has no name, so it vanishes when closed, also when the
  //    process is killed), and each band reads only its own part: time stays
  //    linear in the fragments.
  // The image is bit-identical to render()'s: every pixel gets the same
  // fragments in the same order. Throws std::runtime_error when one pixel
  // alone exceeds the limit or the folder lacks the disk space.
  BandedRender renderInBands(FragmentSource& src, OitAlgorithm& algo, const BandOptions& bands) const;

 private:
  RenderOptions opt_;
};

}  // namespace oit::model
