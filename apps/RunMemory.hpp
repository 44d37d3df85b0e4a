// Memory of `oitsim run`: the budget (--memory-budget), the estimate of the
// run's peak that the pre-check compares with it, and the one-line message of
// an allocation that fails anyway.
//
// The estimate sums, phase by phase, the buffers the run allocates (opaque
// layer, per-pixel state, images, the reference's band, the metrics' planes,
// the output encoders), on top of the process's resident memory measured when
// the estimate is made. What it leaves out (timing-model tables, allocator
// slack) is a measured allowance; the test CliMemory.EstimateCoversTheMeasuredPeak
// compares the estimate with the peak resident set of real runs.
#pragma once

#include "oit_rop/config/RopConfig.hpp"
#include "traces/ResidentMemory.hpp"
#include "traces/TraceIO.hpp"
#include <cstdint>
#include <string>
#include <vector>

namespace oit::cli {

// Physical memory: the machine's RAM, or the memory limit of the cgroup this
// process runs in (a container, a Slurm job) when that is less; 0 unknown.
uint64_t physicalMemoryBytes();
// residentBytes() and peakResidentBytes(): traces/ResidentMemory.hpp.

// Makes every block of 256 KiB or more come from the kernel and go back to it
// when freed. glibc otherwise raises that threshold to the size of the last
// large block freed (up to 32 MiB), after which a frame's freed buffers stay
// in the heap and a later phase takes fresh memory beside them: 12 MiB more
// than the estimate at 1024 x 1024 (alpha: the reference's opaque layer
// and nodes, kept while the metrics ran). No effect outside glibc.
void returnLargeBlocksToTheSystem();

// The default budget: this share of physical memory.
inline constexpr unsigned kDefaultBudgetPercent = 75;

struct MemoryBudget {
  uint64_t bytes = 0;
  std::string source;  // "--memory-budget 8G", "75% of 22.9 GiB physical memory"
};
// --memory-budget: bytes with an optional binary unit (512M, 8G, 1.5GiB, 2T;
// K/M/G/T = 2^10/20/30/40) or a share of physical memory (60%). Empty: the
// default. Throws std::invalid_argument naming the option.
MemoryBudget parseMemoryBudget(const std::string& text);

enum class ReferenceKind { Exact, File, None };

struct RunShape {
  uint32_t width = 0, height = 0;
  uint64_t fragments = 0;  // fragments an A-buffer may store: records of transparent draws, or all records (a bound)
  uint64_t bytes_per_pixel = 0;  // the algorithm's per-pixel state
  uint64_t pool_bytes_per_fragment = 0;  // the A-buffer's node, 0 for the bounded algorithms
  bool timing = false;
  uint64_t timing_level_bytes = 0;  // the shared cache levels' host tables (CacheLevel::hostBytesBound)
  ReferenceKind reference = ReferenceKind::Exact;
  bool run_is_reference = false;  // --algo abuffer: the run is its own reference
  unsigned seeds = 0;           // --seeds N: the parent keeps every seed's image (0: one run, in this process)
  unsigned seed_processes = 0;  // the children that simulate at once (each a whole run)
};

// The host memory of the shared cache levels (l2, l3) of `rc` for a frame
// that puts `frame_bytes` through them (its per-pixel state, depth and colour):
// their tag-store pages and miss-class shadows (CacheLevel::hostBytesEstimate);
// a victim level holds what the level above cannot.
uint64_t sharedLevelHostBytes(const oit::rop::RopConfig& rc, uint64_t frame_bytes);

struct MemoryPhase {
  std::string name;   // "render", "reference", "metrics", "outputs"
  uint64_t bytes = 0; // above the base
};

struct RunMemoryEstimate {
  uint64_t base = 0;  // resident when estimated
  std::vector<MemoryPhase> phases;
  // Bytes one band of the exact reference may take (its per-pixel heads and
  // node pool): what the other phases need anyway, at least 64 MiB, within the
  // budget. 0 when the run builds no separate reference.
  uint64_t reference_band_bytes = 0;
  uint64_t peak() const;                // base + the largest phase
  const MemoryPhase& peakPhase() const;
};

// `base`: the resident memory now (residentBytes()).
RunMemoryEstimate estimateRunMemory(const RunShape& shape, uint64_t base, uint64_t budget);

// Throws std::invalid_argument "<trace>: a W x H frame with <algo> needs about
// X at its peak (<phase>), more than the memory budget Y (<source>) ..." when
// the estimate exceeds the budget.
void checkRunFitsBudget(const RunMemoryEstimate& e, const MemoryBudget& budget, const std::string& trace,
                        const RunShape& shape, const std::string& algo);

// The one line for an allocation that failed anyway (std::bad_alloc).
std::string outOfMemoryMessage(const RunMemoryEstimate& e, const MemoryBudget& budget, const std::string& trace,
                               const RunShape& shape, const std::string& algo);

// Counts the fragments of transparent draws (one pass over `src`, rewound
// before and after): the most the A-buffer under test can store, for its
// reservation and RunShape::fragments (the record count bounds it less tightly).
uint64_t transparentFragments(FragmentSource& src);

}  // namespace oit::cli
