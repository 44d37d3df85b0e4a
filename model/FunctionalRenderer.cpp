#include "model/FunctionalRenderer.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <new>
#include <stdexcept>

#if defined(__linux__)
#include <sys/mman.h>
#endif

namespace oit::model {

namespace {
constexpr uint32_t kDenseLimit = 1u << 20;

[[noreturn]] void badFragment(const FragmentSource& src, uint64_t index, const Fragment& f,
                              const std::string& why) {
  throw std::runtime_error(fmt::format("{}: fragment {} (x {}, y {}, draw {}): {}", src.path(), index,
                                       f.x, f.y, f.draw, why));
}

size_t pixelOf(const FragmentSource& src, uint64_t index, const Fragment& f, uint32_t w, uint32_t h) {
  if (f.x >= w || f.y >= h) detail::fragmentOutsideFrame(src, index, f, w, h);
  return size_t(f.y) * w + f.x;
}
}  // namespace

StateBuffer::StateBuffer(size_t words) : size_(words) {
  constexpr size_t kHuge = size_t(2) << 20;
  const size_t bytes = std::max<size_t>(words * sizeof(uint32_t), 1);
  const bool huge = bytes >= 2 * kHuge;  // small frames (tests): a plain cache-line-aligned block
  const size_t align = huge ? kHuge : 64;
  const size_t rounded = (bytes + align - 1) / align * align;
  p_ = static_cast<uint32_t*>(std::aligned_alloc(align, rounded));
  if (!p_) throw std::bad_alloc();
#ifdef MADV_HUGEPAGE
  if (huge) madvise(p_, rounded, MADV_HUGEPAGE);  // a hint; ignored where unsupported
#endif
}

StateBuffer::~StateBuffer() { std::free(p_); }

DrawClassifier::DrawClassifier(const TraceHeader& header) {
  for (const DrawInfo& d : header.draws) {
    const bool opaque = d.cls == DrawClass::Opaque;
    any_opaque_ |= opaque;
    if (d.id < kDenseLimit) {
      if (d.id >= dense_.size()) dense_.resize(size_t(d.id) + 1, kUnknown);
      dense_[d.id] = opaque ? kOpaque : kTransparent;
    } else {
      sparse_[d.id] = opaque;
    }
  }
}

bool DrawClassifier::lookupSparse(uint32_t draw) const {
  auto it = sparse_.find(draw);
  if (it == sparse_.end())
    throw std::runtime_error(fmt::format("draw {} is not in the trace header's draw table", draw));
  return it->second;
}

OpaqueLayer buildOpaqueLayer(FragmentSource& src, const DrawClassifier& classes) {
  return buildOpaqueLayerWith(src, classes, [](const Fragment&) {});
}

namespace detail {
void fragmentOutsideFrame(const FragmentSource& src, uint64_t index, const Fragment& f, uint32_t w, uint32_t h) {
  badFragment(src, index, f, fmt::format("outside the {}x{} frame", w, h));
}
}  // namespace detail

RenderResult FunctionalRenderer::render(FragmentSource& src, OitAlgorithm& algo) const {
  const TraceHeader& h = src.header();
  const DrawClassifier classes(h);
  algo.beginFrame(h);

  const unsigned algoPasses = algo.passes();
  const unsigned totalPasses = algoPasses + (classes.anyOpaque() ? 1 : 0);
  RenderCounts counts;
  counts.pass_outcomes.assign(algoPasses, {});

  auto report = [&](unsigned pass, std::string_view what, uint64_t done) {
    if (opt_.progress) opt_.progress({pass, totalPasses, what, done, h.fragment_count});
  };

  // Opaque pre-pass (skipped when the draw table has no opaque draw).
  OpaqueLayer opaque = buildOpaqueLayer(src, classes);
  if (classes.anyOpaque()) {
    ++counts.source_passes;
    report(0, "opaque", src.position());
  }

  const unsigned words = algo.stateWords();
  const size_t pixels = size_t(h.width) * h.height;
  // Per-pixel state: every word is written by clear() before use, so no
  // zero fill.
  StateBuffer state(pixels * words);
  algo.clearFrame(state.data(), pixels);

  for (unsigned pass = 0; pass < algoPasses; ++pass) {
    src.rewind();
    ++counts.source_passes;
    auto& outcomes = counts.pass_outcomes[pass];
    uint64_t index = 0, culled = 0, opaqueSeen = 0, nextReport = opt_.progress_every;
    InsertContext ctx;
    const OitAlgorithm::InsertFn insert = algo.insertFn();
    DrawRun draws(classes);
    for (auto batch = src.next(); !batch.empty(); batch = src.next()) {
      for (const Fragment& f : batch) {
        const size_t p = pixelOf(src, index, f, h.width, h.height);
        ++index;
        if (draws.isOpaque(f.draw)) {
          ++opaqueSeen;
          continue;
        }
        const float oz = opaque.depth[p];
        if (f.z >= oz) {  // at or behind the opaque surface
          ++culled;
          continue;
        }
        ctx.opaque_z = oz;
        ++outcomes[size_t(insert(algo, state.data() + p * words, f, pass, ctx))];
      }
      if (opt_.progress && index >= nextReport) {
        report(totalPasses - algoPasses + pass, algo.passName(pass), index);
        nextReport = index + opt_.progress_every;
      }
    }
    report(totalPasses - algoPasses + pass, algo.passName(pass), index);
    if (pass == 0) {
      counts.fragments_in = index;
      counts.opaque = opaqueSeen;
      counts.culled = culled;
      counts.stored = outcomes[size_t(InsertOutcome::Stored)];
      counts.merged = outcomes[size_t(InsertOutcome::Merged)];
      counts.discarded = outcomes[size_t(InsertOutcome::Discarded)];
    }
    for (unsigned o = 0; o < kOutcomeCount; ++o) {
      counts.bytes_read += outcomes[o] * algo.readBytes(pass, InsertOutcome(o));
      counts.bytes_written += outcomes[o] * algo.writeBytes(pass, InsertOutcome(o));
    }
  }

  RenderResult r;
  r.image = Image(h.width, h.height);
  for (size_t p = 0; p < pixels; ++p) {
    const Rgb bg = opaque.landed(p) ? opaque.colour[p] : opt_.clear_colour;
    r.image.pixels[p] = algo.resolve(state.data() + p * words, bg);
  }
  r.counts = std::move(counts);
  r.state_bytes = uint64_t(pixels) * algo.bytesPerPixel() + algo.poolBytes();
  return r;
}

}  // namespace oit::model
