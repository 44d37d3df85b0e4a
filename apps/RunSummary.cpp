#include "apps/RunSummary.hpp"

#include <fmt/core.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

#include "apps/Progress.hpp"
#include "model/AlgorithmSettings.hpp"

namespace oit::cli {
namespace {

// j[a][b], 0 when the report has no such value.
uint64_t num(const nlohmann::json& j, const char* a, const char* b) {
  if (!j.contains(a) || !j[a].contains(b)) return 0;
  return j[a][b].get<uint64_t>();
}

}  // namespace

nlohmann::json metricsJson(const model::ImageMetrics& m) {
  return {{"rmse", m.rmse},         {"psnr", m.psnr},         {"ssim", m.ssim},
          {"mean_abs", m.mean_abs}, {"max_abs", m.max_abs}, {"pixels_over_1_255", m.pixels_over_1_255}};
}

nlohmann::json flipJson(const model::FlipMap& f, double ppd) {
  return {{"mean", f.stats.mean},
          {"weighted_median", f.stats.weighted_median},
          {"weighted_q1", f.stats.weighted_q1},
          {"weighted_q3", f.stats.weighted_q3},
          {"max", f.stats.max},
          {"ppd", ppd}};
}

std::string algorithmWithSettings(const std::string& algo, const model::AlgorithmParams& p) {
  const model::AlgorithmSettings u = model::algorithmSettings(algo);
  std::vector<std::string> parts;
  if (u.layers) parts.push_back(fmt::format("k={}", p.layers));
  if (u.format) parts.push_back(fmt::format("format {}", model::toString(p.format)));
  if (u.bits) parts.push_back(fmt::format("bits {}", p.bits));
  if (u.samples) parts.push_back(fmt::format("samples {}", p.samples));
  if (u.weight) parts.push_back(fmt::format("weight eq. {}", p.weight));
  if (u.seed) parts.push_back(fmt::format("seed {}", p.seed));
  std::string s;
  for (const auto& part : parts) s += (s.empty() ? "" : ", ") + part;
  return s.empty() ? algo : algo + " (" + s + ")";
}

void printTimingSummary(const nlohmann::json& j) {
  const auto& t = j["timing"];
  // The first line answers "what bounds this frame?" and where its time went.
  const auto& ph = t["phase_cycles"];
  std::string passes;
  for (const auto& c : ph["transparent"]) passes += (passes.empty() ? "" : " + ") + std::to_string(c.get<uint64_t>());
  fmt::print("timing      {} cycles = {:.1f} us at {} MHz, {}, bound by {} ({:.1f} % of partition-cycles); "
             "phases: opaque {}, transparent {}, resolve {} cycles; {} idle cycles skipped\n",
             t["cycles"].get<uint64_t>(), t["frame_time_us"].get<double>(), t["clock_mhz"].get<double>(),
             counted(t["partitions"].get<uint64_t>(), "partition", "partitions"), t["bound_by"]["resource"].get<std::string>(),
             100.0 * t["bound_by"]["share"].get<double>(), ph["opaque"].get<uint64_t>(), passes.empty() ? "0" : passes,
             ph["resolve"].get<uint64_t>(), t["skipped_idle_cycles"].get<uint64_t>());
  // Root causes in descending order (those above 0.05 %), utilisation per resource.
  std::vector<std::pair<uint64_t, std::string>> causes;
  uint64_t charged = 0;
  for (auto it = t["root_cause_cycles"].begin(); it != t["root_cause_cycles"].end(); ++it) {
    causes.push_back({it.value().get<uint64_t>(), it.key()});
    charged += causes.back().first;
  }
  std::stable_sort(causes.begin(), causes.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::string root;
  for (const auto& [c, k] : causes)
    if (charged && double(c) / double(charged) >= 0.0005)
      root += fmt::format("{}{} {:.1f} %", root.empty() ? "" : ", ", k, 100.0 * double(c) / double(charged));
  fmt::print("root causes {}\n", root.empty() ? "none" : root);
  std::string util;
  for (auto it = t["utilization"].begin(); it != t["utilization"].end(); ++it)
    util += fmt::format("{}{} {:.1f} %", util.empty() ? "" : ", ", it.key(), 100.0 * it.value().get<double>());
  fmt::print("utilisation {}\n", util);
  fmt::print("stalls      {:<13} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12}\n", "stage", "busy", "lock wait",
             "sb full", "miss wait", "dram bw", "alu busy", "starved");
  for (auto it = t["stages"].begin(); it != t["stages"].end(); ++it) {
    const auto& st = it.value();
    const auto& c = st["stalls"];
    fmt::print("            {:<13} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12} {:>12}\n", it.key(),
               st["busy"].get<uint64_t>(), c["lock_wait"].get<uint64_t>(), c["scoreboard_full"].get<uint64_t>(),
               c["cache_miss_wait"].get<uint64_t>(), c["dram_bandwidth"].get<uint64_t>(),
               c["alu_busy"].get<uint64_t>(), c["input_starved"].get<uint64_t>());
  }
  // The A-buffer's own waits (stall causes atomic_wait, list_walk, sort), when it had any.
  const auto& ss = t["stages"];
  const uint64_t atomic = ss["blend_alu"]["stalls"].value("atomic_wait", uint64_t(0));
  const uint64_t walk = ss["resolve"]["stalls"].value("list_walk", uint64_t(0));
  const uint64_t sort = ss["resolve"]["stalls"].value("sort", uint64_t(0));
  if (atomic + walk + sort != 0)
    fmt::print("            blend_alu atomic wait {}, resolve list walk {}, sort {} cycles\n", atomic, walk, sort);
  const auto& m = j["memory"];
  fmt::print("dram        read {} (arrays {}, depth {}, colour {}, resolve {}), written {}, peak {:.1f} GB/s, mean {:.1f} GB/s\n",
             humanBytes(double(num(m, "dram_read_bytes", "total"))),
             humanBytes(double(num(m, "dram_read_bytes", "blend_arrays"))),
             humanBytes(double(num(m, "dram_read_bytes", "depth"))), humanBytes(double(num(m, "dram_read_bytes", "colour"))),
             humanBytes(double(num(m, "dram_read_bytes", "resolve"))),
             humanBytes(double(num(m, "dram_write_bytes", "total"))), m["peak_gbps"].get<double>(),
             m["mean_gbps"].get<double>());
  // Beside the DRAM line: the traffic against what a perfect cache would move
  // (what the frame left dirty in the caches counts: it leaves later).
  std::string rates;
  for (const auto& l : m["levels"])
    rates += fmt::format("{}{} {:.1f}%", rates.empty() ? "" : ", ", l["name"].get<std::string>(),
                         100.0 * l["hit_rate"].get<double>());
  fmt::print("compulsory  {}; moved {:.2f}x that (DRAM {} + left dirty in the caches {}); hit rate {}\n",
             humanBytes(double(num(m, "compulsory_bytes", "total"))), m["traffic_over_compulsory"].get<double>(),
             humanBytes(double(num(m, "dram_read_bytes", "total") + num(m, "dram_write_bytes", "total"))),
             humanBytes(double(num(m, "end_dirty_bytes", "total"))), rates);
  const auto& fa = m["footprint"]["allocated"];
  const auto& ft = m["footprint"]["touched"];
  auto total = [](const nlohmann::json& o) {
    uint64_t sum = 0;
    for (const auto& v : o) sum += v.get<uint64_t>();
    return sum;
  };
  fmt::print("footprint   allocated {} (blend arrays {}), touched {}\n", humanBytes(double(total(fa))),
             humanBytes(double(fa.value("blend_arrays", uint64_t(0)))), humanBytes(double(total(ft))));
  const auto& l = j["lock"];
  const auto& ca = j["cache"];
  fmt::print("lock/cache  {} conflicts, {} wait cycles, longest {}, peak occupancy {}; cache hit rate {:.1f}%\n",
             l["conflicts"].get<uint64_t>(), l["wait_cycles"].get<uint64_t>(), l["longest_wait"].get<uint64_t>(),
             l["peak_occupancy"].get<uint64_t>(), 100.0 * ca["hit_rate"].get<double>());
}

}  // namespace oit::cli
