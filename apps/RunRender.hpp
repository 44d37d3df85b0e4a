// `oitsim run`'s renders and its reference: the image under test rendered
// with progress and timed, the exact A-buffer reference built in bands that
// fit the memory budget, and --reference FILE.pfm checked before any work and
// read after the run. Kept apart from RunReplay.cpp, which calls these.
#pragma once

#include <cstdint>
#include <string>

#include "model/FunctionalRenderer.hpp"
#include "model/Image.hpp"
#include "model/OitAlgorithm.hpp"
#include "traces/TraceIO.hpp"

namespace oit::cli {

struct TimedRender {
  model::RenderResult result;
  double wall_seconds = 0.0;
};

// `algo` over the whole trace, with a progress line labelled `label`.
TimedRender renderWith(FragmentSource& src, model::OitAlgorithm& algo, const model::Rgb& clear, bool show_progress,
                       const std::string& label);

// The exact reference in bands of at most `band_bytes` (heads + nodes); the
// band file, when there is more than one band, goes to `spill_dir`.
model::BandedRender renderReference(FragmentSource& src, const model::Rgb& clear, uint64_t band_bytes,
                                    const std::string& spill_dir, bool show_progress, double& seconds);

// --reference FILE.pfm, before any work: a regular file whose PFM header
// gives the frame's size and whose length fits it (readPfm checks the rest
// when the file is read, after the run). Throws std::invalid_argument naming
// the option.
void checkReferenceFile(const std::string& path, uint32_t width, uint32_t height);
// Reads it; an error names the option.
model::Image readReferenceFile(const std::string& path);

}  // namespace oit::cli
