#include "apps/RunMemory.hpp"

#include <fmt/format.h>
#include "oit_rop/memory/CacheLevel.hpp"
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "apps/Progress.hpp"
#include "model/FunctionalRenderer.hpp"

namespace oit::cli {

namespace {

constexpr uint64_t kMiB = uint64_t(1) << 20;
constexpr double kGiB = double(uint64_t(1) << 30);

// A number in a cgroup file: "max" (v2) and v1's "no limit" (about 2^63) are 0.
uint64_t cgroupLimit(const std::string& file) {
  std::ifstream in(file);
  std::string v;
  if (!(in >> v) || v == "max") return 0;
  uint64_t n = 0;
  try {
    n = std::stoull(v);
  } catch (const std::exception&) {
    return 0;
  }
  return n >= (uint64_t(1) << 62) ? 0 : n;
}

// The memory limit of this process's cgroup (v2 memory.max, v1
// memory.limit_in_bytes), 0 when there is none or it cannot be read.
uint64_t cgroupMemoryLimit() {
  std::ifstream in("/proc/self/cgroup");
  uint64_t limit = 0;
  auto take = [&](uint64_t v) {
    if (v != 0 && (limit == 0 || v < limit)) limit = v;
  };
  for (std::string line; std::getline(in, line);) {
    const size_t a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1), path = line.substr(b + 1);
    if (controllers.empty()) {  // v2
      take(cgroupLimit("/sys/fs/cgroup" + path + "/memory.max"));
    } else if (("," + controllers + ",").find(",memory,") != std::string::npos) {  // v1
      take(cgroupLimit("/sys/fs/cgroup/memory" + path + "/memory.limit_in_bytes"));
      take(cgroupLimit("/sys/fs/cgroup/memory/memory.limit_in_bytes"));  // a namespaced mount
    }
  }
  return limit;
}

std::string gib(uint64_t bytes) { return humanBytes(double(bytes)); }

}  // namespace

uint64_t physicalMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  uint64_t bytes = pages > 0 && page > 0 ? uint64_t(pages) * uint64_t(page) : 0;
  const uint64_t cg = cgroupMemoryLimit();
  if (cg != 0 && (bytes == 0 || cg < bytes)) bytes = cg;
  return bytes;
}

void returnLargeBlocksToTheSystem() {
#ifdef __GLIBC__
  mallopt(M_MMAP_THRESHOLD, 256 * 1024);  // a fixed threshold also stops the adjustment
#endif
}

MemoryBudget parseMemoryBudget(const std::string& text) {
  const uint64_t physical = physicalMemoryBytes();
  auto share = [&](double percent, const std::string& source) {
    if (physical == 0)
      throw std::invalid_argument(fmt::format(
          "--memory-budget {}: the physical memory of this machine is unknown; give the budget in bytes, e.g. 8G",
          text.empty() ? std::to_string(kDefaultBudgetPercent) + "%" : text));
    return MemoryBudget{uint64_t(double(physical) * percent / 100.0),
                        fmt::format("{}{} of {} physical memory", source, fmt::format("{:g}%", percent), gib(physical))};
  };
  if (text.empty()) return share(kDefaultBudgetPercent, "");
  auto bad = [&] {
    return std::invalid_argument(fmt::format(
        "--memory-budget {}: expected bytes with an optional unit (512M, 8G, 1.5GiB; K, M, G, T are powers of "
        "1024) or a share of physical memory (60%)",
        text));
  };
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    throw bad();
  }
  if (!std::isfinite(v) || v <= 0 || text.find_first_of("+-xXpPnN") != std::string::npos ||
      !std::isdigit(static_cast<unsigned char>(text[0])))
    throw bad();
  std::string unit = text.substr(used);
  if (unit == "%") {
    if (v > 100) throw std::invalid_argument(fmt::format("--memory-budget {}: a share of at most 100%", text));
    return share(v, "--memory-budget ");
  }
  for (const char* tail : {"iB", "B"})
    if (unit.size() > std::string(tail).size() && unit.ends_with(tail)) unit.resize(unit.size() - std::string(tail).size());
  double scale = 1;
  if (unit == "K" || unit == "k") scale = 1024.0;
  else if (unit == "M") scale = 1024.0 * 1024;
  else if (unit == "G") scale = 1024.0 * 1024 * 1024;
  else if (unit == "T") scale = 1024.0 * 1024 * 1024 * 1024;
  else if (!unit.empty() && unit != "B") throw bad();
  const double bytes = v * scale;
  if (bytes < double(kMiB))
    throw std::invalid_argument(fmt::format("--memory-budget {}: expected at least 1M", text));
  if (bytes > 9.0e18) throw bad();
  return {uint64_t(bytes), "--memory-budget " + text};
}

namespace {

// Allowances measured, not derived: what the phases' own buffers leave out.
// Pages of the trace's mapping touched by the batch being copied (released
// batch by batch; the copy buffer itself is allocated at open, in the base).
constexpr uint64_t kReaderBytes = 3 * kMiB;
// The timing model's tables beyond the per-pixel state it shares with the
// functional mode (the ordered lock's release table, per-tile cache, depth and
// HiZ entries, the partitions' queues, the DRAM controller's queues, SystemC's
// thread stacks): they grow with the frame's state. Measured on commit
// 16a4d90's tree as timing minus functional peak with --reference none and no
// shared levels (--set l2.size_bytes=0 --set l3.size_bytes=0), glass at
// 1280 x 720: alpha (16 B of state per pixel) 13.6 B per pixel, wboit (20)
// 14.8, mlab k=2 (40) 22.8, k=4 (64) 38.7, k=8 (160) 71.7; mlab k=4 at
// 640 x 360 and 2560 x 1440 gives the same per pixel (+1 MiB). 8 B + half the
// state per pixel covers each (the 7 B per pixel measured before the memory
// hierarchy's tables fell 23 MiB short at 1280 x 720 with mlab k=4).
constexpr uint64_t kTimingBytesPerPixel = 8;
constexpr double kTimingShareOfState = 0.5;
constexpr uint64_t kTimingBytes = 2 * kMiB;
// The exact reference beside its band: the band file's write buffers and one
// read chunk (FunctionalRendererBands.cpp).
constexpr uint64_t kBandBuffers = 10 * kMiB;
// A band may always take this much, however small the frame.
constexpr uint64_t kMinReferenceBand = 64 * kMiB;
// Freed blocks the allocator keeps (glibc returns blocks above 32 MiB at once,
// smaller ones stay in the heap until reused): a share of each phase.
constexpr double kAllocatorSlack = 0.03;

}  // namespace

uint64_t sharedLevelHostBytes(const oit::rop::RopConfig& rc, uint64_t frame_bytes) {
  const bool classify = rc.stats.level_miss_classes;
  uint64_t bytes = 0;
  if (rc.l2.size_bytes)
    bytes += oit::rop::CacheLevel::hostBytesEstimate(rc.l2, classify, frame_bytes / rc.l2.line_bytes);
  if (rc.l3.size_bytes) {
    const uint64_t above = rc.l2.size_bytes ? rc.l2.size_bytes / rc.l2.line_bytes : 0;
    uint64_t lines = frame_bytes / rc.l3.line_bytes;
    if (rc.l3.victim_only) lines = lines > above ? lines - above : 0;
    bytes += oit::rop::CacheLevel::hostBytesEstimate(rc.l3, classify, lines);
  }
  return bytes;
}

uint64_t RunMemoryEstimate::peak() const { return base + peakPhase().bytes; }

const MemoryPhase& RunMemoryEstimate::peakPhase() const {
  return *std::max_element(phases.begin(), phases.end(),
                           [](const MemoryPhase& a, const MemoryPhase& b) { return a.bytes < b.bytes; });
}

RunMemoryEstimate estimateRunMemory(const RunShape& s, uint64_t base, uint64_t budget) {
  const uint64_t px = uint64_t(s.width) * s.height;
  const uint64_t image = 12 * px;    // model::Image: three floats per pixel
  const uint64_t opaque = 16 * px;   // OpaqueLayer: depth + colour
  const uint64_t png = 3 * px;       // writePng's 8-bit RGB rows
  // The A-buffer under test keeps its pool (one node per stored fragment, at
  // most one per record counted) until the run ends.
  const uint64_t pool = s.fragments * s.pool_bytes_per_fragment;
  auto slack = [](uint64_t b) { return b + uint64_t(double(b) * kAllocatorSlack); };
  RunMemoryEstimate e;
  e.base = base;  // with the trace reader's batch buffers, allocated at open

  // The run: opaque layer, per-pixel state, pool, its image; the timing
  // model's own tables.
  uint64_t render = opaque + s.bytes_per_pixel * px + pool + image + kReaderBytes;
  if (s.timing)
    render += (kTimingBytesPerPixel + uint64_t(kTimingShareOfState * double(s.bytes_per_pixel))) * px + kTimingBytes +
              s.timing_level_bytes;
  // --seeds N: children simulate (each a whole run, in its own process, a
  // fork of this one) and send back their images, which this process keeps to
  // the end (and seed 0's once more as the run's own); flicker's sRGB8 codes
  // (3 B per pixel and image) and its grey image come with the outputs.
  const uint64_t seed_images = s.seeds * image;
  if (s.seeds > 0) render = s.seed_processes * render + seed_images + image;
  e.phases.push_back({"render", slack(render)});

  // The images compared: luma of both (2 x 8 B per pixel), SSIM's five
  // horizontal moment planes (5 x 8 B); then LDR-FLIP (model/Flip.cpp): both
  // images as sRGB8 (2 x 3 B), seven float scratch planes, five per image
  // perceived (2 x 5 x 4 B), the error map (4 B, kept for flip.png) and its
  // sorted copy for the quartiles (4 B); the PNG/PFM writing after them.
  const bool compare = s.reference != ReferenceKind::None;
  const uint64_t kept = pool + seed_images;
  if (compare) {
    const uint64_t flip_map = 4 * px;
    e.phases.push_back({"metrics", slack(kept + 2 * image + 16 * px + 40 * px)});
    e.phases.push_back({"flip", slack(kept + 2 * image + 6 * px + 28 * px + 40 * px + 2 * flip_map)});
    const uint64_t flicker = s.seeds > 0 ? s.seeds * 3 * px + image : 0;
    e.phases.push_back({"outputs", slack(kept + 3 * image + flip_map + flicker + png)});
  } else {
    e.phases.push_back({"outputs", slack(kept + image + png)});
  }

  if (s.reference == ReferenceKind::File) {
    // readPfm holds the file's bytes and the decoded image at once.
    e.phases.push_back({"reference", slack(kept + image + 2 * image)});
  } else if (s.reference == ReferenceKind::Exact && !s.run_is_reference) {
    // The run's image, the reference's opaque layer and image, then either the
    // counting pass's per-pixel counts or one band: heads (4 B per pixel) and
    // nodes (24 B per fragment that reaches the A-buffer, at most one per record).
    const uint64_t fixed = seed_images + image + opaque + image + kBandBuffers + kReaderBytes;
    uint64_t others = 0;
    for (const MemoryPhase& p : e.phases) others = std::max(others, p.bytes);
    uint64_t band = std::max(others > slack(fixed) ? others - slack(fixed) : 0, kMinReferenceBand);
    const uint64_t room = budget > base + slack(fixed) ? budget - base - slack(fixed) : 0;
    band = std::min(band, std::max<uint64_t>(room, 4 * px));  // at least the heads: else over budget, refused
    e.reference_band_bytes = band;
    const uint64_t needed = 4 * px + s.fragments * 24;  // the whole frame in one band
    e.phases.push_back({"reference", slack(fixed + std::max(std::min(band, needed), 4 * px))});
  }
  return e;
}

void checkRunFitsBudget(const RunMemoryEstimate& e, const MemoryBudget& budget, const std::string& trace,
                        const RunShape& s, const std::string& algo) {
  if (e.peak() <= budget.bytes) return;
  const MemoryPhase& p = e.peakPhase();
  std::string hint;
  if (s.reference != ReferenceKind::None && p.name != "render" && s.seeds == 0)
    hint = "; --reference none skips the reference and the metrics";
  throw std::invalid_argument(fmt::format(
      "{}: a {} x {} frame with {}{} needs about {} at its peak ({}), more than the memory budget of {} ({}){}; "
      "nothing was run",
      trace, s.width, s.height, algo, s.seeds > 0 ? fmt::format(" and {} seeds' images", s.seeds) : "",
      gib(e.peak()), p.name, gib(budget.bytes), budget.source, hint));
}

std::string outOfMemoryMessage(const RunMemoryEstimate& e, const MemoryBudget& budget, const std::string& trace,
                               const RunShape& s, const std::string& algo) {
  return fmt::format(
      "{}: out of memory: the {} x {} frame with {} ({} mode) needs about {} at its peak ({}); an allocation "
      "failed (memory budget {}, {}; check `ulimit -v` and other processes)",
      trace, s.width, s.height, algo, s.timing ? "timing" : "functional", gib(e.peak()), e.peakPhase().name,
      gib(budget.bytes), budget.source);
}

uint64_t transparentFragments(FragmentSource& src) {
  const model::DrawClassifier classes(src.header());
  src.rewind();
  uint64_t n = 0;
  model::DrawRun draws(classes);
  for (auto b = src.next(); !b.empty(); b = src.next())
    for (const Fragment& f : b) n += draws.isOpaque(f.draw) ? 0 : 1;
  src.rewind();
  return n;
}


}  // namespace oit::cli
