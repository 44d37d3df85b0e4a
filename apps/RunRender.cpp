#include "apps/RunRender.hpp"

#include <fmt/core.h>
#include <unistd.h>

#include <chrono>
#include <sstream>
#include <stdexcept>

#include "apps/Progress.hpp"
#include "traces/InputFile.hpp"

namespace oit::cli {

TimedRender renderWith(FragmentSource& src, model::OitAlgorithm& algo, const model::Rgb& clear,
                       bool show_progress, const std::string& label) {
  Progress progress(label, show_progress);
  model::RenderOptions ro;
  ro.clear_colour = clear;
  ro.progress = [&](const model::RenderProgress& p) {
    const double within = p.fragments_total ? double(p.fragments_done) / double(p.fragments_total) : 0.0;
    progress.update((double(p.pass) + within) / double(p.passes),
                    fmt::format("pass {}/{} {}", p.pass + 1, p.passes, p.what));
  };
  model::FunctionalRenderer renderer(ro);
  const auto t0 = std::chrono::steady_clock::now();
  TimedRender t{renderer.render(src, algo), 0.0};
  t.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.finish();
  return t;
}

model::BandedRender renderReference(FragmentSource& src, const model::Rgb& clear, uint64_t band_bytes,
                                    const std::string& spill_dir, bool show_progress, double& seconds) {
  Progress progress("reference", show_progress);
  model::RenderOptions ro;
  ro.clear_colour = clear;
  ro.progress = [&](const model::RenderProgress& p) {
    const double within = p.fragments_total ? double(p.fragments_done) / double(p.fragments_total) : 0.0;
    progress.update((double(p.pass) + within) / double(p.passes), std::string(p.what));
  };
  auto abuffer = model::makeAlgorithm("abuffer", {});
  const auto t0 = std::chrono::steady_clock::now();
  model::BandedRender r = model::FunctionalRenderer(ro).renderInBands(src, *abuffer, {band_bytes, spill_dir});
  seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  progress.finish();
  return r;
}

void checkReferenceFile(const std::string& path, uint32_t width, uint32_t height) {
  const InputFile in = openInputFile(path);
  if (!in) throw std::invalid_argument(fmt::format("--reference {}: {} (expected a PFM image)", path, in.problem));
  const uint64_t payload = uint64_t(width) * height * 12;  // RGB floats; a grey "Pf" is a third of it
  if (in.size > payload + 1024)
    throw std::invalid_argument(fmt::format(
        "--reference {}: is {} bytes, more than a {} x {} PFM image takes ({} bytes of pixels): not the reference of "
        "this trace",
        path, in.size, width, height, payload));
  char head[64] = {};
  const ssize_t n = ::pread(in.fd.get(), head, sizeof head - 1, 0);
  std::istringstream tokens(std::string(head, n > 0 ? size_t(n) : 0));
  std::string magic;
  uint64_t w = 0, hgt = 0;
  if (!(tokens >> magic >> w >> hgt) || (magic != "PF" && magic != "Pf"))
    throw std::invalid_argument(
        fmt::format("--reference {}: not a PFM image (expected the header PF <width> <height>)", path));
  if (w != width || hgt != height)
    throw std::invalid_argument(fmt::format("--reference {}: is a {} x {} image, the trace's frame is {} x {}", path,
                                            w, hgt, width, height));
}

model::Image readReferenceFile(const std::string& path) {
  try {
    return model::readPfm(path);
  } catch (const std::runtime_error& e) {
    throw std::runtime_error(fmt::format("--reference {}", e.what()));
  }
}

}  // namespace oit::cli
