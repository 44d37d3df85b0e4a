#include "traces/capture/Verify.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

#include "model/FunctionalRenderer.hpp"
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
  for (size_t p = 0; p < v.pixels; ++p) {
    const float model_rgb[3] = {r.image.pixels[p].r, r.image.pixels[p].g, r.image.pixels[p].b};
    for (int c = 0; c < 3; ++c) {
      const float gl = ref.rgba[4 * p + c];
      ++v.channels_compared;
      if (model_rgb[c] == gl) continue;
      ++v.channels_differing;
      v.max_ulps = std::max(v.max_ulps, ulpDistance(model_rgb[c], gl));
      v.max_abs = std::max(v.max_abs, std::fabs(static_cast<double>(model_rgb[c]) - gl));
      if (v.first_difference.empty())
        v.first_difference = fmt::format("pixel ({}, {}) channel {}: model {:.9g}, GL {:.9g}", p % h.width,
                                         p / h.width, "rgb"[c], model_rgb[c], gl);
    }
  }
  return v;
}

}  // namespace oit::capture
