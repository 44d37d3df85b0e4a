// Throughput of the timing mode (runTiming) against the functional golden
// model (FunctionalRenderer::render) on the same trace, best of N each.
//
// The trace is read into memory once (MemorySource) before anything is timed:
// --trace FILE (openTrace), or by default a synthetic 1280x720 particle trace
// (an opaque backdrop covering every pixel, then --quads 16x16 transparent
// quads at random positions and depths: 921,600 + 5,248,000 = 6.17 M records).
// M fragments/s counts every record of the trace (opaque ones included).
//
// SystemC elaborates once per process, so every timing run happens in a forked
// child (copy-on-write view of the fragments) that sends back its wall time
// (TimingResult::wall_seconds: opaque pre-pass, front end, simulation, resolve
// and stats), an image hash and, with --stats, the stats JSON. The timing
// image is checked bit for bit against the functional one (lock.mode=ordered;
// the other modes' images follow the timing and are not compared).
//
//   bench_timing [--mode both|functional|timing] [--reps 3] [--trace FILE]
//                [--width 1280] [--height 720] [--quads 20500] [--quad 16] [--seed 7]
//                [--algo mlab] [--k 4] [--format rgba8t8z32] [--preset igpu]
//                [--set path=value]... [--stats FILE]
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "bench/BenchCommon.hpp"
#include "model/FunctionalRenderer.hpp"
#include "model/MemorySource.hpp"
#include "model/OitAlgorithm.hpp"
#include "oit_rop/config/ConfigTree.hpp"
#include "oit_rop/TimingRun.hpp"

using namespace oit;
using bench::cpuSeconds;

namespace {

constexpr uint32_t kOpaque = 0, kTransparent = 1;

// The synthetic particle trace (the former TimingRun.DISABLED_Throughput scene).
model::MemorySource synthetic(uint32_t w, uint32_t h, unsigned quads, unsigned quad, uint32_t seed) {
  TraceHeader hdr;
  hdr.width = w;
  hdr.height = h;
  hdr.draws = {{kOpaque, DrawClass::Opaque, "backdrop"}, {kTransparent, DrawClass::Transparent, "particles"}};
  std::vector<Fragment> fs;
  fs.reserve(size_t(w) * h + size_t(quads) * quad * quad);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (uint32_t y = 0; y < h; ++y)
    for (uint32_t x = 0; x < w; ++x)
      fs.push_back(Fragment{uint16_t(x), uint16_t(y), 0.8f + 0.2f * u(rng), 0.2f, 0.2f, 0.2f, 1.0f, 0, kOpaque});
  for (uint32_t q = 0; q < quads; ++q) {
    const uint32_t x0 = rng() % (w - quad), y0 = rng() % (h - quad);
    const float z = 0.85f * u(rng), r = u(rng), g = u(rng), b = u(rng), a = 0.2f + 0.6f * u(rng);
    for (uint32_t y = y0; y < y0 + quad; ++y)
      for (uint32_t x = x0; x < x0 + quad; ++x)
        fs.push_back(Fragment{uint16_t(x), uint16_t(y), z, r, g, b, a, q, kTransparent});
  }
  return model::MemorySource(hdr, std::move(fs));
}

uint64_t imageHash(const model::Image& img) {  // FNV-1a over the raw float bits
  uint64_t hsh = 1469598103934665603ull;
  const auto* p = reinterpret_cast<const unsigned char*>(img.pixels.data());
  for (size_t i = 0, n = img.pixels.size() * sizeof(model::Rgb); i < n; ++i) hsh = (hsh ^ p[i]) * 1099511628211ull;
  return hsh;
}

// One runTiming in a forked child; returns {"wall", "hash", "stats"?} or {"error"}.
nlohmann::json timingInChild(model::MemorySource& src, const model::AlgorithmParams& params, const std::string& algo,
                             const rop::RopConfig& cfg, bool want_stats) {
  int fd[2];
  if (pipe(fd) != 0) return {{"error", "pipe failed"}};
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid == 0) {
    close(fd[0]);
    nlohmann::json out;
    try {
      auto a = model::makeAlgorithm(algo, params);
      const double c0 = cpuSeconds();
      rop::TimingResult r = rop::runTiming(src, *a, cfg, {});
      const double cpu = cpuSeconds() - c0;
      out = {{"wall", r.wall_seconds}, {"cpu", cpu}, {"hash", imageHash(r.image)}, {"cycles", r.stats["timing"]["cycles"]}};
      if (want_stats) out["stats"] = r.stats;
    } catch (const std::exception& e) {
      out = {{"error", e.what()}};
    }
    const std::string s = out.dump();
    for (size_t off = 0; off < s.size();) {
      const ssize_t n = write(fd[1], s.data() + off, s.size() - off);
      if (n <= 0) break;
      off += size_t(n);
    }
    close(fd[1]);
    _exit(0);
  }
  close(fd[1]);
  std::string in;
  char buf[1 << 16];
  for (ssize_t n; (n = read(fd[0], buf, sizeof buf)) > 0;) in.append(buf, size_t(n));
  close(fd[0]);
  int status = 0;
  waitpid(pid, &status, 0);
  if (in.empty()) return {{"error", "child died, status " + std::to_string(status)}};
  return nlohmann::json::parse(in);
}

}  // namespace

extern "C" int sc_main(int argc, char* argv[]) {
  std::string mode = "both", trace, algo = "mlab", format = "rgba8t8z32", preset = "igpu", stats_path;
  std::vector<std::string> sets;
  unsigned reps = 3, width = 1280, height = 720, quads = 20500, quad = 16, seed = 7, k = 4;
  CLI::App app{"Timing-mode throughput (runTiming) against the functional model on the same trace"};
  app.add_option("--mode", mode, "What to time")->check(CLI::IsMember({"both", "functional", "timing"}))
      ->capture_default_str();
  app.add_option("--reps", reps, "Runs of each mode; the best is reported")->check(CLI::Range(1u, 1000u))
      ->capture_default_str();
  app.add_option("--trace", trace, "Trace file (read into memory first) instead of the synthetic scene")
      ->check(CLI::ExistingFile);
  app.add_option("--width", width, "Synthetic scene width")->check(CLI::Range(2u, 65535u))->capture_default_str();
  app.add_option("--height", height, "Synthetic scene height")->check(CLI::Range(2u, 65535u))->capture_default_str();
  app.add_option("--quads", quads, "Synthetic transparent quads")->check(CLI::Range(0u, 100000000u))
      ->capture_default_str();
  app.add_option("--quad", quad, "Synthetic quad edge in pixels")->check(CLI::Range(1u, 4096u))->capture_default_str();
  app.add_option("--seed", seed, "Synthetic scene seed")->capture_default_str();
  app.add_option("--algo", algo, "OIT algorithm (oitsim run --help lists them)")->capture_default_str();
  app.add_option("--k", k, "Layers (k) of the layered algorithms")->check(CLI::Range(1u, 64u))->capture_default_str();
  app.add_option("--format", format, "Storage format of the blending arrays")->capture_default_str();
  app.add_option("--preset", preset, "Configuration preset (igpu, dgpu)")->capture_default_str();
  app.add_option("--set", sets, "Configuration override path=value (repeatable)");
  app.add_option("--stats", stats_path, "Write the first timing run's stats JSON here");
  try {
    app.parse(argc, argv);
    if (trace.empty() && (width <= quad || height <= quad))
      throw CLI::ValidationError("--width/--height", "must exceed --quad (" + std::to_string(quad) + ")");
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  }

  model::AlgorithmParams params;
  params.layers = k;
  rop::RopConfig cfg;
  try {
    params.format = model::parseStorageFormat(format);
    cfg = rop::resolveConfig(preset, "", sets);
    (void)model::makeAlgorithm(algo, params);  // unknown names and bad parameters fail here, not in a child
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 2;
  }

  std::unique_ptr<model::MemorySource> src;
  std::string what;
  if (!trace.empty()) {
    try {
      src = bench::loadTrace(trace);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s\n", e.what());
      return 1;
    }
    what = "trace " + trace;
  } else {
    src = std::make_unique<model::MemorySource>(synthetic(width, height, quads, quad, seed));
    what = "synthetic particles, " + std::to_string(quads) + " quads of " + std::to_string(quad) + "x" +
           std::to_string(quad) + ", seed " + std::to_string(seed);
  }
  const TraceHeader& hdr = src->header();
  const double n = double(hdr.fragment_count);
  std::printf("# %s: %ux%u, %.3f M records; %s k=%u %s, preset %s", what.c_str(), hdr.width, hdr.height, n / 1e6,
              algo.c_str(), k, format.c_str(), preset.c_str());
  for (const auto& s : sets) std::printf(" --set %s", s.c_str());
  std::printf("; best of %u\n", reps);

  double func_best = 0, timing_best = 0, func_cpu = 0, timing_cpu = 0;
  uint64_t func_hash = 0, timing_hash = 0;
  if (mode != "timing") {
    func_best = func_cpu = 1e300;
    for (unsigned r = 0; r < reps; ++r) {
      auto a = model::makeAlgorithm(algo, params);
      const auto t0 = std::chrono::steady_clock::now();
      const double c0 = cpuSeconds();
      const model::RenderResult res = model::FunctionalRenderer().render(*src, *a);
      const double cpu = cpuSeconds() - c0;
      const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      func_best = std::min(func_best, s);
      func_cpu = std::min(func_cpu, cpu);
      func_hash = imageHash(res.image);
      std::printf("functional rep %u: %.3f s = %.2f M frag/s (cpu %.3f s)\n", r + 1, s, n / s / 1e6, cpu);
      std::fflush(stdout);
    }
  }
  if (mode != "functional") {
    timing_best = timing_cpu = 1e300;
    for (unsigned r = 0; r < reps; ++r) {
      const nlohmann::json res = timingInChild(*src, params, algo, cfg, r == 0 && !stats_path.empty());
      if (res.contains("error")) {
        std::fprintf(stderr, "timing run failed: %s\n", res["error"].get<std::string>().c_str());
        return 1;
      }
      const double s = res["wall"], cpu = res["cpu"];
      timing_best = std::min(timing_best, s);
      timing_cpu = std::min(timing_cpu, cpu);
      timing_hash = res["hash"];
      std::printf("timing rep %u: %.3f s = %.2f M frag/s (cpu %.3f s; %llu cycles)\n", r + 1, s, n / s / 1e6, cpu,
                  static_cast<unsigned long long>(res["cycles"].get<uint64_t>()));
      std::fflush(stdout);
      if (res.contains("stats")) std::ofstream(stats_path) << res["stats"].dump(1) << "\n";
    }
  }
  if (mode != "timing")
    std::printf("functional: best %.3f s = %.2f M frag/s; cpu %.3f s = %.2f M frag/s\n", func_best,
                n / func_best / 1e6, func_cpu, n / func_cpu / 1e6);
  if (mode != "functional")
    std::printf("timing:     best %.3f s = %.2f M frag/s; cpu %.3f s = %.2f M frag/s\n", timing_best,
                n / timing_best / 1e6, timing_cpu, n / timing_cpu / 1e6);
  if (mode == "both") {
    std::printf("ratio timing/functional: %.3f (cpu %.3f)\n", func_best / timing_best, func_cpu / timing_cpu);
    // Only an ordered interlock inserts in the functional model's order; the
    // other modes' images follow the timing (oit_rop/DESIGN.md, "Ordering").
    if (cfg.lock.mode != rop::LockMode::Ordered) {
      std::printf("image: lock.mode=%s follows the timing run's order, not compared\n", rop::lockModeName(cfg.lock.mode));
      return 0;
    }
    const bool same = func_hash == timing_hash;
    std::printf("image bit-identical: %s\n", same ? "yes" : "NO");
    if (!same) return 1;
  }
  return 0;
}
