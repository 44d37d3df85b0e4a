// Warm read speed of binary traces: writes a synthetic trace to /tmp, then
// times full validated reads through openTrace (best of 3, after one warm-up
// pass that brings the file into the page cache).
//   bench_trace_read [RECORDS=50000000] [fp32|unorm8] [BATCH=65536]
#include <fmt/format.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "traces/TraceIO.hpp"

namespace {

struct Pass {
  double seconds;
  uint64_t records;
  uint64_t checksum;
};

Pass readOnce(const std::string& path, size_t batch) {
  const auto t0 = std::chrono::steady_clock::now();
  auto src = oit::openTrace(path, {.batch_records = batch});
  uint64_t records = 0, checksum = 0;
  for (auto b = src->next(); !b.empty(); b = src->next()) {
    records += b.size();
    checksum += b.back().prim;  // keeps the loop honest without adding per-record work
  }
  const auto t1 = std::chrono::steady_clock::now();
  return {std::chrono::duration<double>(t1 - t0).count(), records, checksum};
}

}  // namespace

int main(int argc, char** argv) {
  uint64_t count = 50'000'000ull;
  std::string enc_name = "fp32";
  size_t batch = size_t{1} << 16;
  CLI::App app{"Warm read speed of binary traces (openTrace, validated)"};
  app.add_option("records", count, "Records in the synthetic trace")->check(CLI::Range(uint64_t{1}, uint64_t{1} << 40))
      ->capture_default_str();
  app.add_option("encoding", enc_name, "Colour encoding")->check(CLI::IsMember({"fp32", "unorm8"}))
      ->capture_default_str();
  app.add_option("batch", batch, "Records per next() batch")->check(CLI::Range(size_t{1}, size_t{1} << 30))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  const auto enc = enc_name == "fp32" ? oit::ColourEncoding::Fp32 : oit::ColourEncoding::Unorm8;
  const std::string path = fmt::format("/tmp/oitsim-bench-read-{}.oitt", ::getpid());
  try {
    oit::TraceHeader h;
    h.width = 1920;
    h.height = 1080;
    h.encoding = enc;
    for (uint32_t d = 0; d < 64; ++d)
      h.draws.push_back({d, d < 8 ? oit::DrawClass::Opaque : oit::DrawClass::Transparent,
                         fmt::format("draw{}", d)});
    const auto tw0 = std::chrono::steady_clock::now();
    {
      auto w = oit::createTraceWriter(path, h);
      std::vector<oit::Fragment> chunk(1 << 16);
      for (uint64_t base = 0; base < count; base += chunk.size()) {
        const size_t n = static_cast<size_t>(std::min<uint64_t>(chunk.size(), count - base));
        for (size_t k = 0; k < n; ++k) {
          const uint64_t i = base + k;
          chunk[k] = {static_cast<uint16_t>(i % 1920), static_cast<uint16_t>((i / 1920) % 1080),
                      static_cast<float>(i % 4096) / 4096.0f, 0.5f, 0.25f, 0.125f, 0.5f,
                      static_cast<uint32_t>(i), static_cast<uint32_t>((i / 5000) % 64)};
        }
        w->write(std::span<const oit::Fragment>(chunk.data(), n));
      }
      w->commit();
    }
    const double write_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - tw0).count();
    const double mib = static_cast<double>(count * (enc == oit::ColourEncoding::Fp32 ? 32 : 20)) /
                       (1 << 20);
    fmt::print("trace: {} records, {}, {:.0f} MiB, batch {}; write {:.1f} M records/s\n", count,
               enc_name, mib, batch, static_cast<double>(count) / write_s / 1e6);

    readOnce(path, batch);  // warm-up: page cache
    Pass best{1e30, 0, 0};
    for (int i = 0; i < 3; ++i) {
      const Pass p = readOnce(path, batch);
      fmt::print("  pass {}: {:.3f} s, {:.0f} M records/s\n", i + 1, p.seconds,
                 static_cast<double>(p.records) / p.seconds / 1e6);
      if (p.records != count) throw std::runtime_error("short read");
      if (p.seconds < best.seconds) best = p;
    }
    fmt::print("warm read (open + validate every record), best of 3: {:.0f} M records/s, {:.2f} GiB/s\n",
               static_cast<double>(count) / best.seconds / 1e6, mib / 1024 / best.seconds);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_trace_read: %s\n", e.what());
    ::unlink(path.c_str());
    return 1;
  }
  ::unlink(path.c_str());
  return 0;
}
