// Every parameter of the timing model, typed. The named property tree
// (oit_rop/config/ConfigTree.hpp: defaults, units, descriptions, presets, JSON files,
// --set a.b.c=value) reads and writes these fields; the model reads only this.
// The struct's defaults are a base the presets start from (the old `igpu`
// values, no L2 or L3); every preset sets its values (Presets.cpp, CONFIG.md).
#pragma once

#include <cstdint>
#include <string>

namespace oit::rop {

enum class LockGranularity : uint8_t { Pixel, Quad, Tile };  // quad = 2x2 pixels
enum class LockRelease : uint8_t { EndOfBlend, EndOfShader };
// What the interlock guarantees (oit_rop/DESIGN.md, "Ordering"): ordered = each
// lock address's fragments enter in submission order (ROV, PixelSync);
// unordered = one at a time, in the order the timing model lets them in;
// none = no interlock, racing read-modify-writes (lost updates counted).
enum class LockMode : uint8_t { Ordered, Unordered, None };
enum class LatencyModel : uint8_t { Fixed, Uniform };
// cycle: stages evaluated cycle by cycle (the reference); approximate: one visit per fragment (DESIGN.md).
enum class SimEngine : uint8_t { CycleStepped, Approximate };
// Where a tile's per-pixel arrays live (MEMORY.md): pixel_major = each pixel's
// array contiguous, pixels in tile order; row_major = row i of every pixel of
// the tile contiguous (the extra words form one more row).
enum class ArrayLayoutKind : uint8_t { PixelMajor, RowMajor };
// The DRAM controller's read scheduling: fcfs = first come first served; frfcfs
// = a request whose data can go now may pass older ones (MEMORY.md).
enum class DramScheduler : uint8_t { Fcfs, FrFcfs };

struct ClockConfig {
  double core_mhz = 1150.0;  // ROP / core clock
  bool operator==(const ClockConfig&) const = default;
};

struct PartitionConfig {
  unsigned count = 2;         // ROP partitions; the screen is split into interleaved tiles
  unsigned tile_width = 8;    // pixels; tiles: partition interleave, HiZ, tile locks, resolve
  unsigned tile_height = 8;
  bool operator==(const PartitionConfig&) const = default;
};

struct InputConfig {
  double fragments_per_clock = 2.0;  // per partition, into the pixel shader
  LatencyModel latency_model = LatencyModel::Uniform;
  unsigned latency_min = 40;  // cycles of pixel-shader latency (fixed model: latency_min)
  unsigned latency_max = 120;
  unsigned warp_size = 1;     // consecutive fragments (by sequence number) sharing one latency draw; power of two
  uint64_t seed = 1;          // latency distribution seed
  bool operator==(const InputConfig&) const = default;
};

struct EarlyDepthConfig {
  bool enabled = true;        // cull transparent fragments at/behind the opaque depth before the lock
  bool hierarchical = true;   // per-tile max opaque depth culls without reading the depth buffer
  unsigned latency = 4;       // cycles
  bool operator==(const EarlyDepthConfig&) const = default;
};

struct LockConfig {
  unsigned capacity = 256;                // scoreboard entries (fragments in flight between issue and release)
  LockGranularity granularity = LockGranularity::Pixel;
  LockMode mode = LockMode::Ordered;      // ordered, unordered or no interlock
  bool per_primitive = true;              // quad/tile: one primitive's fragments hold the lock together
  LockRelease release = LockRelease::EndOfBlend;
  unsigned shader_tail = 20;              // cycles from end of blend to end of shader (EndOfShader release)
  bool operator==(const LockConfig&) const = default;
};

struct CacheConfig {
  uint64_t size_bytes = 64 * 1024;   // the ROP's blending-array cache, per partition
  unsigned ways = 8;
  unsigned miss_queue = 16;          // outstanding line fills
  unsigned hit_latency = 10;         // cycles
  unsigned line_bytes = 64;          // cache line (tag); power of two
  unsigned sector_bytes = 0;         // fill / write-back unit inside a line (0 = the whole line)
  bool operator==(const CacheConfig&) const = default;
};

struct MemoryLayoutConfig {
  ArrayLayoutKind array_layout = ArrayLayoutKind::PixelMajor;
  bool operator==(const MemoryLayoutConfig&) const = default;
};

// A shared cache level between the partitions and DRAM (l2; l3 behind it).
struct SharedCacheConfig {
  uint64_t size_bytes = 0;        // 0 = no such level
  unsigned ways = 16;
  unsigned line_bytes = 64;
  unsigned sector_bytes = 0;      // 0 = the whole line
  unsigned slices = 1;            // address-hashed, each with its own port
  unsigned hit_latency = 50;      // cycles
  double bytes_per_clock = 64.0;  // per slice
  bool victim_only = false;       // fills only with the level above's evictions
  bool operator==(const SharedCacheConfig&) const = default;
};

struct AluConfig {
  unsigned blends_per_clock = 2;  // RGBA8-rate blends per clock per partition
  unsigned base_latency = 8;      // cycles of one insert (read, blend, write of one row)
  unsigned cycles_per_compare = 1;    // per row whose depth the insert compares (model::InsertWork)
  unsigned cycles_per_row_moved = 2;  // per row the insert writes: new, shifted, rescaled, merged
  double fp16_rate = 0.5;         // throughput relative to 8-bit rows
  double fp32_rate = 0.25;
  bool operator==(const AluConfig&) const = default;
};

// The A-buffer under test (algorithm abuffer; CONFIG.md): its pool, its
// resolve's local array, and the global node counter's atomic.
enum class ABufferOverflowPolicy : uint8_t { Spill, Truncate };
struct ABufferConfig {
  uint64_t pool_bytes = 0;           // heads + node pool; 0 = nodes_per_pixel x W x H nodes (+ heads)
  double nodes_per_pixel = 16.0;     // pool size when pool_bytes = 0 [inferred]
  unsigned max_sorted = 64;          // resolve's local array (nodes per pixel sorted in registers) [inferred]
  ABufferOverflowPolicy overflow = ABufferOverflowPolicy::Spill;
  double atomics_per_clock = 1.0;    // node-counter increments per clock for the whole GPU [inferred]
  unsigned atomic_latency = 100;     // cycles of one counter atomic at the L2 [inferred]
  unsigned sort_cycles_per_compare = 1;  // resolve's insertion sort
  unsigned sort_cycles_per_move = 1;
  unsigned spill_cycles_per_node = 20;   // a node beyond max_sorted: written out and read back [inferred]
  bool operator==(const ABufferConfig&) const = default;
};

struct DramConfig {
  unsigned channels = 2;
  double channel_gbps = 12.8;       // GB/s per channel (DDR3-1600, 64-bit)
  double tck_ns = 1.25;             // DRAM clock period
  unsigned cl = 11, trcd = 11, trp = 11;  // in DRAM clocks
  unsigned tras = 28;                     // activate to precharge, DRAM clocks (0: no limit)
  // Activate-rate limits per channel (one rank), DRAM clocks, 0 = no limit. The
  // struct leaves them off (the presets set them: DDR3-1600 x8 has 5 and 24).
  unsigned trrd = 0;                      // activate to activate, different banks
  unsigned tfaw = 0;                      // at most four activates in any window this long
  unsigned twtr = 6;                      // end of write data to a read command, DRAM clocks
  unsigned trtw = 2;                      // idle data bus from read data to write data, DRAM clocks
  // Bank groups (GDDR5, GDDR6; MEMORY.md "Bank groups"): the channel's banks in
  // bank_groups groups (1 = none, as DDR3; group = bank mod bank_groups after
  // dram.bank_hash). The _L timings hold inside a group, the _S ones (tccd_s,
  // trrd, twtr) between groups; DRAM clocks, 0 = no distinction.
  unsigned bank_groups = 1;
  unsigned tccd_s = 0;  // column command to column command, any bank (0: the burst's bus time)
  unsigned tccd_l = 0;  // column to column in one bank group
  unsigned trrd_l = 0;  // activate to activate in one bank group (dram.trrd: other groups)
  unsigned twtr_l = 0;  // end of write data to a read command in the same bank group (dram.twtr: the channel)
  unsigned banks = 8;
  unsigned row_bytes = 8192;        // row-buffer size per bank
  unsigned burst_bytes = 64;        // access granularity
  unsigned interleave_bytes = 256;  // channel interleave
  bool open_row = true;             // keep rows open (hits pay CL only); false: closed page
  bool bank_hash = true;            // XOR-fold the row into the bank index (MEMORY.md)
  double controller_ns = 40.0;      // fixed controller + interconnect latency
  double trefi_ns = 7800.0;         // refresh interval per channel (0: no refresh); DDR3, <= 85 C
  double trfc_ns = 260.0;           // refresh cycle time: no data moves, rows close; DDR3 4 Gb
  unsigned write_queue = 64;        // posted-write entries (bursts) per channel
  unsigned write_high = 56;         // waiting write bursts that start a drain
  unsigned write_low = 32;          // a drain stops at or below this
  DramScheduler scheduler = DramScheduler::FrFcfs;
  unsigned queue_depth = 64;        // bursts per channel the FR-FCFS scheduler looks over
  bool operator==(const DramConfig&) const = default;
};

struct StatsConfig {
  uint64_t interval_cycles = 10000;  // time-series sample period
  uint64_t max_samples = 16384;      // more: the period doubles (pairs of samples merge)
  bool miss_classes = true;          // classify the ROP cache's misses (compulsory / capacity / conflict)
  bool level_miss_classes = false;   // classify the shared levels' (l2, l3) misses too: a costly shadow per level
  bool operator==(const StatsConfig&) const = default;
};

struct SkipConfig {
  bool early_depth = true;   // cull before the lock (else culled fragments pass through lock and cache)
  bool fast_clear = true;    // untouched tiles neither read from DRAM, cleared nor resolved
  bool lazy_merge = true;    // no merge work while a pixel's array is not full
  bool idle_cycles = true;   // the simulator jumps over cycles where nothing can move
  bool operator==(const SkipConfig&) const = default;
};

struct SimConfig {
  // tlm_quantumkeeper quantum: 16 keeps every frame of bench/quantum_check.sh
  // within 1.4 % of lockstep, where 200 was off by up to 9 % and 32 by up to
  // 5.9 % (DESIGN.md, "Structure (SystemC)").
  uint64_t quantum_cycles = 16;
  SimEngine engine = SimEngine::CycleStepped;
  bool operator==(const SimConfig&) const = default;
};

struct RopConfig {
  std::string preset = "iris-pro-5200";
  ClockConfig clock;
  PartitionConfig partitions;
  InputConfig input;
  EarlyDepthConfig early_depth;
  LockConfig lock;
  CacheConfig cache;
  MemoryLayoutConfig memory;
  SharedCacheConfig l2, l3;
  AluConfig alu;
  ABufferConfig abuffer;
  DramConfig dram;
  StatsConfig stats;
  SkipConfig skip;
  SimConfig sim;
  bool operator==(const RopConfig&) const = default;
};

}  // namespace oit::rop
