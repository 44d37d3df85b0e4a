#include "apps/CaptureVerify.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

#include "model/FunctionalRenderer.hpp"
#include "traces/capture/ApiOrder.hpp"
#include "model/MemorySource.hpp"
#include "model/OitAlgorithm.hpp"

namespace oit::capture {

uint32_t ulpDistance(float a, float b) {
  // Map the sign-magnitude bit patterns onto a monotonic integer line.
  auto key = [](float f) {
    const int32_t i = std::bit_cast<int32_t>(f);
    return i < 0 ? static_cast<int64_t>(INT32_MIN) - i : static_cast<int64_t>(i);
  };
  const int64_t d = key(a) - key(b);
  return static_cast<uint32_t>(std::min<int64_t>(d < 0 ? -d : d, UINT32_MAX));
}

namespace {

// Compares the model's image with GL's RGBA (rgb only: the model keeps no alpha).
void compareImages(const model::Image& image, const float* gl_rgba, uint32_t width, VerifyResult& v) {
  for (size_t p = 0; p < v.pixels; ++p) {
    const float model_rgb[3] = {image.pixels[p].r, image.pixels[p].g, image.pixels[p].b};
    for (int c = 0; c < 3; ++c) {
      const float gl = gl_rgba[4 * p + c];
      ++v.channels_compared;
      if (model_rgb[c] == gl) continue;
      ++v.channels_differing;
      v.max_ulps = std::max(v.max_ulps, ulpDistance(model_rgb[c], gl));
      v.max_abs = std::max(v.max_abs, std::fabs(static_cast<double>(model_rgb[c]) - gl));
      if (v.first_difference.empty())
        v.first_difference = fmt::format("pixel ({}, {}) channel {}: model {:.9g}, GL {:.9g}", p % width,
                                         p / width, "rgb"[c], model_rgb[c], gl);
    }
  }
}

}  // namespace

namespace {

std::string describe(const Fragment& f) {
  return fmt::format("draw {} primitive {} pixel ({}, {}) depth {:.9g} rgba {:.9g} {:.9g} {:.9g} {:.9g}", f.draw, f.prim,
                     f.x, f.y, f.z, f.r, f.g, f.b, f.a);
}

// Check 3: the application's drawing (the trace) against the check drawing, one to
// one: fragments grouped by (draw, pixel), each list keeping its own order within a
// group (a stable radix sort), so that a pixel both drawings give to another
// primitive of the draw (a window draw's horizontal shared edges: llvmpipe's fill
// rule runs in y-down coordinates there) does not shift every later pair.
void compareDrawings(const std::vector<Fragment>& trace, const std::vector<Fragment>& check,
                     const std::vector<uint32_t>& window_draws, TransparentVerifyResult& v) {
  auto inWindow = [&](uint32_t draw) {
    return std::find(window_draws.begin(), window_draws.end(), draw) != window_draws.end();
  };
  auto byPixel = [](const std::vector<Fragment>& f) {
    return apiOrder(f.size(), [&](size_t i) { return RecordKey{f[i].draw, uint32_t(f[i].x) | uint32_t(f[i].y) << 16}; });
  };
  const std::vector<uint32_t> ta = byPixel(trace), tb = byPixel(check);
  const size_t n = std::min(trace.size(), check.size());
  v.drawing_mismatches = std::max(trace.size(), check.size()) - n;
  for (size_t i = 0; i < n; ++i) {
    const Fragment& a = trace[ta[i]];
    const Fragment& b = check[tb[i]];
    const bool window = inWindow(a.draw);
    const bool same_depth = std::bit_cast<uint32_t>(a.z) == std::bit_cast<uint32_t>(b.z);
    const double depth_diff = std::fabs(double(a.z) - b.z);
    const bool near_depth = !same_depth && window && depth_diff <= TransparentVerifyResult::kWindowDepthBound;
    const bool edge = a.prim != b.prim && window;
    if (!same_depth && window) {
      ++v.depth_differing;
      v.max_depth_diff = std::max(v.max_depth_diff, depth_diff);
    }
    if (edge) ++v.primitive_differing;
    if (a.draw != b.draw || (a.prim != b.prim && !edge) || a.x != b.x || a.y != b.y || !(same_depth || near_depth)) {
      if (v.drawing_mismatches++ == 0)
        v.first_drawing_difference = fmt::format("fragment {}: {} in the trace, {} in the check drawing", ta[i],
                                                 describe(a), describe(b));
      continue;
    }
    const float da[4] = {a.r, a.g, a.b, a.a}, db[4] = {b.r, b.g, b.b, b.a};
    double worst = 0;
    for (int c = 0; c < 4; ++c) worst = std::max(worst, std::fabs(double(da[c]) - db[c]));
    if (std::memcmp(da, db, sizeof da) != 0) ++v.colour_differing;
    if (worst > v.max_colour_diff) {
      v.max_colour_diff = worst;
      if (worst > TransparentVerifyResult::kDrawingColourBound && v.first_drawing_difference.empty())
        v.first_drawing_difference = fmt::format("fragment {}: {} in the trace, {} in the check drawing", ta[i],
                                                 describe(a), describe(b));
    }
  }
  if (v.first_drawing_difference.empty() && trace.size() != check.size())
    v.first_drawing_difference =
        fmt::format("{} fragments in the trace, {} in the check drawing", trace.size(), check.size());
}

}  // namespace

TransparentVerifyResult verifyTransparentDraws(const FrameCapture& frame) {
  if (!frame.reference) throw std::logic_error("verifyTransparentDraws: the frame has no GL reference");
  const GlTransparentReference& ref = *frame.reference;
  const TraceHeader& h = frame.header;
  if (ref.width != h.width || ref.height != h.height)
    throw std::runtime_error(fmt::format("frame {}: GL's reference is {}x{}, the trace {}x{}", frame.frame,
                                         ref.width, ref.height, h.width, h.height));
  TransparentVerifyResult v;
  v.pixels = static_cast<uint64_t>(h.width) * h.height;
  TraceHeader th = h;
  th.draws.clear();
  for (const DrawInfo& d : h.draws)
    if (d.cls == DrawClass::Transparent && d.state && d.state->recorded()) {
      th.draws.push_back(d);
      v.premultiplied = v.premultiplied || d.state->blend == BlendMode::PremultipliedOver;
    }
  std::vector<Fragment> frags;
  std::vector<uint32_t> counts(v.pixels, 0);
  for (const Fragment& f : frame.fragments)
    if (th.findDraw(f.draw)) {
      frags.push_back(f);
      ++counts[static_cast<size_t>(f.y) * h.width + f.x];
    }
  v.fragments = frags.size();
  v.check_fragments = ref.fragments.size();
  v.clamped = frame.premultiplied_clamped + frame.premultiplied_zero_alpha;
  for (size_t p = 0; p < v.pixels; ++p)
    if (counts[p] != ref.count[p] && v.count_pixels_differing++ == 0)
      v.first_difference = fmt::format("pixel ({}, {}): {} records, GL counted {}", p % h.width, p / h.width,
                                       counts[p], ref.count[p]);
  compareDrawings(frags, ref.fragments, frame.window_draws, v);
  // GL blended the check drawing's fragments: replay those.
  model::MemorySource src(th, std::vector<Fragment>(ref.fragments));
  auto algo = model::makeAlgorithm("alpha", {});
  const model::RenderResult r = model::FunctionalRenderer().render(src, *algo);
  compareImages(r.image, ref.rgba.data(), h.width, v);
  return v;
}

VerifyResult verifyTrace(const std::string& path, const GlReference& ref) {
  auto src = openTrace(path);
  const TraceHeader& h = src->header();
  if (h.width != ref.width || h.height != ref.height)
    throw std::invalid_argument(fmt::format("trace {} is {}x{}, the GL reference {}x{}", path, h.width,
                                            h.height, ref.width, ref.height));
  VerifyResult v;
  v.pixels = static_cast<uint64_t>(h.width) * h.height;
  for (const DrawInfo& d : h.draws) v.opaque_draws = v.opaque_draws || d.cls == DrawClass::Opaque;

  std::vector<uint32_t> counts(v.pixels, 0);
  for (auto batch = src->next(); !batch.empty(); batch = src->next())
    for (const Fragment& f : batch) ++counts[static_cast<size_t>(f.y) * h.width + f.x];
  v.fragments = src->position();
  for (size_t p = 0; p < v.pixels; ++p)
    if (static_cast<float>(counts[p]) != ref.count[p]) {
      if (v.count_pixels_differing++ == 0 && v.first_difference.empty())
        v.first_difference = fmt::format("pixel ({}, {}): {} records, GL counted {}", p % h.width,
                                         p / h.width, counts[p], ref.count[p]);
    }

  // The functional model over a black clear colour: resolve = accumulated colour
  // + 0 * transmittance, i.e. exactly the blend sequence GL performs from 0.
  auto algo = model::makeAlgorithm("alpha", {});
  model::FunctionalRenderer renderer;
  const model::RenderResult r = renderer.render(*src, *algo);
  compareImages(r.image, ref.rgba.data(), h.width, v);
  return v;
}

}  // namespace oit::capture
