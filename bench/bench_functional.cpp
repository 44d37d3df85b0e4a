// Throughput of the functional golden model (FunctionalRenderer::render) per
// OIT algorithm on a synthetic in-memory scene: W x H pixels x L full-screen
// transparent layers with random depth and alpha (no opaque draws).
// Two submission orders of the same fragments (identical per-pixel order, so
// identical images):
//   layered - L full-screen draws one after the other, each in raster order
//             (what a GPU submits; every pixel's state is revisited L times);
//   raster  - pixel after pixel, all L fragments of a pixel back to back
//             (best cache locality for the per-pixel state).
// Best of N timed renders after nothing else (the scene is generated first).
// `layered` is what the issue calls a raster-order trace: every draw covers
// the screen in row order, one draw after another (e.g. --width 1280
// --height 720 --layers 8 --order layered: 7.4 M fragments).
//
// --trace FILE renders a trace file (openTrace) instead of the synthetic
// scene, two ways: `file` re-reads and decodes the trace in every render
// (end to end, as oitsim run does) and `memory` reads it once into a
// MemorySource first (the model alone). Mfrag/s counts all records of the
// trace (opaque ones included) per render.
//
//   bench_functional [--algos all|a,b,...] [--k 4] [--format fp32|fp16|rgba8t8z32]
//                    [--size 256] [--width W] [--height H] [--layers 40] [--bits 32]
//                    [--order both|layered|raster] [--reps 3]
//                    [--trace FILE] [--trace-mode both|file|memory]
#include <chrono>
#include <cstdio>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "bench/BenchCommon.hpp"
#include "model/FunctionalRenderer.hpp"
#include "model/MemorySource.hpp"
#include "model/OitAlgorithm.hpp"

using namespace oit;
using namespace oit::model;

namespace {

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  size_t start = 0;
  while (start <= s.size()) {
    const size_t comma = s.find(',', start);
    const size_t end = comma == std::string::npos ? s.size() : comma;
    if (end > start) out.push_back(s.substr(start, end - start));
    start = end + 1;
  }
  return out;
}

// Layer-major order; the raster variant is a stable per-pixel regrouping.
std::vector<Fragment> scene(uint32_t w, uint32_t h, unsigned layers, bool raster) {
  std::vector<Fragment> fs;
  fs.reserve(size_t(w) * h * layers);
  uint32_t s = 12345;
  auto rnd = [&] { return (s = s * 1664525u + 1013904223u) >> 8; };
  for (unsigned layer = 0; layer < layers; ++layer)
    for (uint32_t y = 0; y < h; ++y)
      for (uint32_t x = 0; x < w; ++x) {
        const float z = float(rnd() % 1000000) / 1e6f;
        const float a = 0.1f + float(rnd() % 100) / 200.0f;
        fs.push_back(Fragment{uint16_t(x), uint16_t(y), z, float(rnd() % 256) / 255.0f,
                              float(rnd() % 256) / 255.0f, float(rnd() % 256) / 255.0f, a,
                              uint32_t(y * w + x), 1 + layer});
      }
  if (!raster) return fs;
  std::vector<Fragment> out(fs.size());
  const size_t px = size_t(w) * h;
  for (size_t i = 0; i < fs.size(); ++i) out[(i % px) * layers + i / px] = fs[i];
  return out;
}

// Order-independent checksum of the image (same scene -> same value in both orders).
double checksum(const Image& img) {
  double c = 0;
  for (const Rgb& p : img.pixels) c += p.r + 2.0 * p.g + 3.0 * p.b;
  return c;
}

// Best-of-reps render of one algorithm; `source` makes a fresh (rewound) source per rep.
struct Timed {
  double best = 1e300;
  RenderResult r;
};
Timed timeRenders(unsigned reps, OitAlgorithm& algo, const std::function<FragmentSource&()>& source) {
  Timed t;
  for (unsigned rep = 0; rep < reps; ++rep) {
    FragmentSource& src = source();
    const auto t0 = std::chrono::steady_clock::now();
    t.r = FunctionalRenderer().render(src, algo);
    t.best = std::min(t.best, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return t;
}

int runTrace(const std::string& path, const std::string& mode, const std::vector<std::string>& names,
             const AlgorithmParams& params, unsigned reps, const std::string& format) {
  std::unique_ptr<FragmentSource> file;
  std::unique_ptr<MemorySource> mem;
  try {
    file = openTrace(path);
    if (mode != "file") mem = bench::loadTrace(path);  // read once, untimed
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  const TraceHeader hdr = file->header();
  std::printf("# trace %s: %ux%u, %llu records, k=%u, format %s, bits %u, best of %u\n", path.c_str(), hdr.width,
              hdr.height, static_cast<unsigned long long>(hdr.fragment_count), params.layers, format.c_str(),
              params.bits, reps);
  std::printf("%-10s %-8s %7s %6s %9s %12s %14s %14s\n", "algorithm", "source", "passes", "B/px", "best s",
              "Mfrag/s", "Mfrag-pass/s", "checksum");
  for (const std::string m : {"file", "memory"}) {
    if (mode != "both" && mode != m) continue;
    for (const std::string& name : names) {
      std::unique_ptr<OitAlgorithm> algo;
      try {
        algo = makeAlgorithm(name, params);
      } catch (const std::invalid_argument& e) {
        std::printf("%-10s %-8s n/a (%s)\n", name.c_str(), m.c_str(), e.what());
        continue;
      }
      FragmentSource& src = m == "file" ? *file : static_cast<FragmentSource&>(*mem);
      const Timed t = timeRenders(reps, *algo, [&]() -> FragmentSource& { return src; });  // render() rewinds
      const double n = double(t.r.counts.fragments_in);
      std::printf("%-10s %-8s %7u %6u %9.3f %12.2f %14.2f %14.6f\n", name.c_str(), m.c_str(),
                  t.r.counts.source_passes, algo->bytesPerPixel(), t.best, n / t.best / 1e6,
                  n * t.r.counts.source_passes / t.best / 1e6, checksum(t.r.image));
      std::fflush(stdout);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string algos = "all", format = "fp32", order = "both", trace, traceMode = "both";
  unsigned k = 4, size = 256, width = 0, height = 0, layers = 40, bits = 32, reps = 3;
  CLI::App app{"Throughput of the functional golden model per OIT algorithm"};
  app.add_option("--algos", algos, "all, or a comma-separated list of algorithm names")->capture_default_str();
  app.add_option("--k", k, "Layers (k) of the layered algorithms")->check(CLI::Range(1u, 64u))->capture_default_str();
  app.add_option("--format", format, "Storage format: fp32, fp16 or rgba8t8z32")->capture_default_str();
  app.add_option("--size", size, "Width and height of the synthetic scene")->check(CLI::Range(1u, 4096u))
      ->capture_default_str();
  app.add_option("--width", width, "Synthetic scene width (default --size)")->check(CLI::Range(1u, 4096u));
  app.add_option("--height", height, "Synthetic scene height (default --size)")->check(CLI::Range(1u, 4096u));
  app.add_option("--layers", layers, "Full-screen transparent layers")->check(CLI::Range(1u, 100000u))
      ->capture_default_str();
  app.add_option("--bits", bits, "Virtual bits (slab) / mask bits (mlcb)")->check(CLI::Range(1u, 1024u))
      ->capture_default_str();
  app.add_option("--order", order, "Submission order")->check(CLI::IsMember({"both", "layered", "raster"}))
      ->capture_default_str();
  app.add_option("--reps", reps, "Renders per algorithm; the best is reported")->check(CLI::Range(1u, 1000u))
      ->capture_default_str();
  app.add_option("--trace", trace, "Render this trace file instead of the synthetic scene")->check(CLI::ExistingFile);
  app.add_option("--trace-mode", traceMode, "file: decode the trace in every render; memory: read it once first")
      ->check(CLI::IsMember({"both", "file", "memory"}))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  if (width == 0) width = size;
  if (height == 0) height = size;
  std::vector<std::string> names;
  if (algos == "all")
    for (const AlgorithmInfo& info : algorithmNames()) names.emplace_back(info.name);
  else
    names = split(algos);

  AlgorithmParams params;
  params.layers = k;
  params.bits = bits;   // slab (virtual bits) and mlcb (mask bits)
  params.samples = 8;   // stochastic
  try {
    params.format = parseStorageFormat(format);
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "--format: %s\n", e.what());
    return 2;
  }

  if (!trace.empty()) return runTrace(trace, traceMode, names, params, reps, format);

  TraceHeader hdr;
  hdr.width = width;
  hdr.height = height;
  for (unsigned l = 0; l < layers; ++l) hdr.draws.push_back({1 + l, DrawClass::Transparent, "layer"});

  std::printf("# %ux%u x %u layers = %zu fragments, k=%u, format %s, bits %u, best of %u\n", width, height, layers,
              size_t(width) * height * layers, k, format.c_str(), bits, reps);
  std::printf("%-10s %-8s %7s %6s %9s %12s %14s %14s\n", "algorithm", "order", "passes", "B/px", "best s",
              "Mfrag/s", "Mfrag-pass/s", "checksum");
  for (const std::string ord : {"layered", "raster"}) {
    if (order != "both" && order != ord) continue;
    const std::vector<Fragment> fs = scene(width, height, layers, ord == "raster");
    for (const std::string& name : names) {
      std::unique_ptr<OitAlgorithm> algo;
      try {
        algo = makeAlgorithm(name, params);
      } catch (const std::invalid_argument& e) {
        std::printf("%-10s %-8s n/a (%s)\n", name.c_str(), ord.c_str(), e.what());
        continue;
      }
      MemorySource src(hdr, fs);
      const Timed t = timeRenders(reps, *algo, [&]() -> FragmentSource& { return src; });  // render() rewinds
      const double best = t.best;
      const RenderResult& r = t.r;
      const double n = double(fs.size());
      std::printf("%-10s %-8s %7u %6u %9.3f %12.2f %14.2f %14.6f\n", name.c_str(), ord.c_str(),
                  r.counts.source_passes, algo->bytesPerPixel(), best, n / best / 1e6,
                  n * r.counts.source_passes / best / 1e6, checksum(r.image));
      std::fflush(stdout);
    }
  }
  return 0;
}
