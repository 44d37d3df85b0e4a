// The hardware presets: documented GPUs, every value with its public source
// or marked as an estimate (the table and the sources: oit_rop/config/CONFIG.md).
// `igpu` and `dgpu`, the first two presets, are aliases of the closest
// documented part (iris-pro-5200, titan-x-maxwell).
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "oit_rop/config/ConfigTree.hpp"

namespace oit::rop {
namespace {

// Intel Iris Pro 5200 (Haswell GT3e), the MLAB paper's GPU: 2 slices, 4 px/clk,
// a 6 MB LLC shared with the CPU and 128 MB of eDRAM (Crystalwell) as a victim
// cache of the LLC, dual-channel DDR3-1600.
RopConfig irisPro5200() {
  RopConfig c;  // the struct's defaults hold this part's partition, input, lock, ALU and DRAM values
  c.preset = "iris-pro-5200";
  // DDR3-1600 x8 devices (1 KB page: 8 of them make the channel's 8 KiB row):
  // tRRD max(4 nCK, 6 ns) = 5 tCK, tFAW 30 ns = 24 tCK (JESD79-3 speed bins).
  c.dram.trrd = 5;
  c.dram.tfaw = 24;
  c.cache.line_bytes = 64;
  // LLC: 6 MB in 4 ring-stop slices (one per core), 12 ways; the GPU reaches it
  // through its GTI port (64 B/clk read in the Gen8/9 whitepapers): 16 B/clk per slice.
  c.l2.size_bytes = 6u << 20;
  c.l2.ways = 12;
  c.l2.line_bytes = 64;
  c.l2.slices = 4;
  c.l2.hit_latency = 50;
  c.l2.bytes_per_clock = 16.0;
  // eDRAM: 128 MB, filled only with the LLC's evictions.
  c.l3.size_bytes = 128u << 20;
  c.l3.ways = 16;
  c.l3.line_bytes = 64;
  c.l3.slices = 1;
  c.l3.hit_latency = 80;
  c.l3.bytes_per_clock = 43.5;  // ~50 GB/s per direction at 1150 MHz
  c.l3.victim_only = true;
  return c;
}

// NVIDIA GeForce GTX Titan X (GM200, Maxwell), the continuum paper's GPU: six
// 64-bit memory controllers, each with 16 ROPs and 512 KB of L2.
RopConfig titanXMaxwell() {
  RopConfig c;
  c.preset = "titan-x-maxwell";
  c.clock.core_mhz = 1075.0;  // boost clock
  c.partitions.count = 6;
  c.input.fragments_per_clock = 16.0;  // one raster engine (16 px/clk) per GPC, six GPCs
  c.lock.capacity = 2048;              // 16 fragments/clock x up to 120 cycles of shader latency
  c.cache.size_bytes = 64 * 1024;      // 4 x 16 KiB ROP cache per partition (GTX 980, notes)
  c.cache.ways = 16;
  c.cache.miss_queue = 32;
  c.cache.hit_latency = 10;
  c.cache.line_bytes = 128;
  c.cache.sector_bytes = 0;  // whole lines (CONFIG.md: 32 B sectors, one pixel's array each, lose the lines' spatial hits)
  c.alu.blends_per_clock = 16;
  c.l2.size_bytes = 3u << 20;
  c.l2.ways = 16;
  c.l2.line_bytes = 128;
  c.l2.sector_bytes = 32;
  c.l2.slices = 6;
  c.l2.hit_latency = 70;  // the notes' 66 ns L2 latency at 1075 MHz
  c.l2.bytes_per_clock = 64.0;
  c.dram.channels = 6;
  c.dram.channel_gbps = 56.0;  // 7 Gbps x 64 bit / 8; x 6 = 336 GB/s
  c.dram.tck_ns = 0.667;
  c.dram.cl = 24;
  c.dram.trcd = 24;
  c.dram.trp = 24;
  c.dram.tras = 56;
  c.dram.twtr = 8;  // tWTR 5 ns (Ramulator's GDDR5 speed table) at tCK 0.667 ns
  c.dram.trtw = 2;  // RD->WR = CL + BL/4 + 2 - WL: 2 tCK of idle data bus
  c.dram.trrd = 9;   // 5.7 ns and 23.4 ns (Ramulator's GDDR5-7000 speed table) at tCK 0.667 ns
  c.dram.tfaw = 36;
  // Bank groups: GDDR5's 16 banks are 4 groups (column commands 3 tCK apart inside
  // a group: Ramulator's GDDR5 table, nCCDL 3, nCCDS 2), but they stay off here
  // (`dram.bank_groups` 1): the controller books a run's bursts back to back and
  // cannot put another group's burst into the tCCD_L gaps as a real one with both
  // in its queue does, so with them on the frames are upper estimates, 12-20 %
  // slower (MEMORY.md "Bank groups"). `--set dram.bank_groups=4 --set
  // dram.tccd_l=3` studies them. t32AW does not bind (MEMORY.md).
  c.dram.trefi_ns = 1900.0;  // 32 ms / 16,384 refresh commands (4 Gb GDDR5, as on the GTX 980)
  c.dram.trfc_ns = 110.0;    // no GDDR5 datasheet at hand: an 8 Gb GDDR6's 110 ns (CONFIG.md)
  c.dram.banks = 16;
  c.dram.row_bytes = 4096;
  c.dram.burst_bytes = 64;
  c.dram.interleave_bytes = 256;
  c.dram.controller_ns = 100.0;
  return c;
}

// AMD Radeon RX 6900 XT (Navi 21, RDNA 2): 128 ROPs, 4 MB L2, 128 MB Infinity
// Cache, 256-bit GDDR6 at 16 Gbps (16 channels of 16 bit, 512 GB/s).
RopConfig navi21() {
  RopConfig c;
  c.preset = "navi21";
  c.clock.core_mhz = 2015.0;  // game clock
  c.partitions.count = 8;     // one render backend pair per shader array (4 engines x 2 arrays)
  c.input.fragments_per_clock = 16.0;
  c.lock.capacity = 2048;
  c.cache.size_bytes = 64 * 1024;
  c.cache.ways = 16;
  c.cache.miss_queue = 32;
  c.cache.hit_latency = 10;
  c.cache.line_bytes = 64;
  c.alu.blends_per_clock = 16;  // 128 ROPs / 8
  c.l2.size_bytes = 4u << 20;
  c.l2.ways = 16;
  c.l2.line_bytes = 128;
  c.l2.slices = 16;
  c.l2.hit_latency = 150;
  c.l2.bytes_per_clock = 64.0;
  c.l3.size_bytes = 128u << 20;
  c.l3.ways = 16;
  c.l3.line_bytes = 128;
  c.l3.slices = 16;
  c.l3.hit_latency = 100;
  c.l3.bytes_per_clock = 64.0;
  c.dram.channels = 16;
  c.dram.channel_gbps = 32.0;  // 16 Gbps x 16 bit / 8; x 16 = 512 GB/s
  c.dram.tck_ns = 0.5;         // CK = data rate / 8
  c.dram.cl = 32;
  c.dram.trcd = 32;
  c.dram.trp = 32;
  c.dram.tras = 74;
  // GDDR6 16 Gbps, 8 Gb (MEMORY.md, "Refresh"): tWTR 4 ns + 2 tCK; read-to-write
  // spacing RL + 4 - WL leaves 2 tCK of idle data bus; refresh 32 ms / 16k
  // commands; tRFCab 110 ns.
  c.dram.twtr = 10;
  c.dram.trtw = 2;
  // tRRD 4 ns, tFAW 16 ns (Ramulator 2's GDDR6-16000 1.35 V table; no datasheet read).
  c.dram.trrd = 8;
  c.dram.tfaw = 32;
  // Bank groups: 4 groups of 4 banks per channel (Ramulator 2's GDDR6
  // organisations); tCCD_L 3 tCK against one BL16 burst's 2 (the GDDR5 ratio,
  // and Ramulator 2's nCCDL / nCCDS = 6 / 4), tWTR_L 13 tCK (its nWTRL - nWTRS
  // = 2 tCK of 0.57 ns added to tWTR). Off here for the reason titan-x-maxwell
  // gives; `--set dram.bank_groups=4 --set dram.tccd_l=3 --set dram.twtr_l=13`.
  c.dram.trefi_ns = 1900.0;
  c.dram.trfc_ns = 110.0;
  c.dram.banks = 16;
  c.dram.row_bytes = 2048;
  c.dram.burst_bytes = 32;  // BL16 x 16 bit
  c.dram.interleave_bytes = 256;
  c.dram.controller_ns = 100.0;
  return c;
}

struct PresetEntry {
  const char* name;
  RopConfig (*make)();
  // Paths whose value is an estimate (not a reading of a public source;
  // argued in CONFIG.md).
  std::vector<std::string_view> inferred;
};

// Estimates every preset shares: the model's own abstractions and timings no
// source gives.
#define OITSIM_COMMON_ESTIMATES                                                                                  \
  "partitions.tile_width", "partitions.tile_height", "input.latency_min", "input.latency_max",                 \
      "early_depth.latency", "lock.shader_tail", "cache.ways", "cache.miss_queue", "cache.hit_latency",       \
      "alu.base_latency", "alu.cycles_per_compare", "alu.cycles_per_row_moved", "alu.fp16_rate",               \
      "alu.fp32_rate", "abuffer.nodes_per_pixel", "abuffer.max_sorted", "abuffer.atomics_per_clock",                \
      "abuffer.atomic_latency", "abuffer.sort_cycles_per_compare", "abuffer.sort_cycles_per_move",                  \
      "abuffer.spill_cycles_per_node", "dram.row_bytes",                                                           \
      "dram.interleave_bytes", "dram.controller_ns", "dram.write_queue", "dram.write_high", "dram.write_low"

const std::vector<PresetEntry>& presets() {
  static const std::vector<PresetEntry> list = {
      {"iris-pro-5200", irisPro5200,
       {OITSIM_COMMON_ESTIMATES, "input.fragments_per_clock", "lock.capacity", "cache.size_bytes", "cache.line_bytes",
        "l2.ways", "l2.slices", "l2.hit_latency", "l2.bytes_per_clock", "l3.ways", "l3.line_bytes", "l3.hit_latency",
        "l3.bytes_per_clock", "dram.trfc_ns"}},
      {"titan-x-maxwell", titanXMaxwell,
       {OITSIM_COMMON_ESTIMATES, "input.fragments_per_clock", "lock.capacity", "cache.size_bytes", "cache.line_bytes",
        "cache.sector_bytes", "l2.ways", "l2.line_bytes", "l2.sector_bytes", "l2.hit_latency", "l2.bytes_per_clock",
        "dram.tck_ns", "dram.cl", "dram.trcd", "dram.trp", "dram.tras", "dram.twtr", "dram.trtw", "dram.trefi_ns",
        "dram.trfc_ns", "dram.trrd", "dram.tfaw"}},
      {"navi21", navi21,
       {OITSIM_COMMON_ESTIMATES, "partitions.count", "input.fragments_per_clock", "lock.capacity", "cache.size_bytes",
        "cache.line_bytes", "alu.blends_per_clock", "l2.size_bytes", "l2.ways", "l2.line_bytes", "l2.slices", "l2.hit_latency",
        "l2.bytes_per_clock", "l3.ways", "l3.line_bytes", "l3.slices", "l3.hit_latency", "l3.bytes_per_clock",
        "l3.victim_only", "dram.tck_ns", "dram.cl", "dram.trcd", "dram.trp", "dram.tras", "dram.banks", "dram.twtr",
        "dram.trtw", "dram.trfc_ns", "dram.trrd", "dram.tfaw"}},
  };
  return list;
}
#undef OITSIM_COMMON_ESTIMATES

// The first presets' names, kept: each names the closest documented part.
struct PresetAlias {
  const char* alias;
  const char* preset;
};
constexpr PresetAlias kAliases[] = {{"igpu", "iris-pro-5200"}, {"dgpu", "titan-x-maxwell"}};

const PresetEntry* findPreset(std::string_view name) {
  const std::string canonical = canonicalPresetName(name);
  for (const auto& p : presets())
    if (canonical == p.name) return &p;
  return nullptr;
}

}  // namespace

std::vector<std::string> presetNames() {
  std::vector<std::string> names;
  for (const auto& p : presets()) names.emplace_back(p.name);
  return names;
}

std::vector<std::pair<std::string, std::string>> presetAliases() {
  std::vector<std::pair<std::string, std::string>> v;
  for (const auto& a : kAliases) v.emplace_back(a.alias, a.preset);
  return v;
}

std::string canonicalPresetName(std::string_view name) {
  for (const auto& a : kAliases)
    if (name == a.alias) return a.preset;
  return std::string(name);
}

RopConfig presetConfig(std::string_view name) {
  const PresetEntry* p = findPreset(name);
  if (!p)
    throw std::invalid_argument(fmt::format("unknown preset '{}'; known presets: {} (aliases: igpu = iris-pro-5200, "
                                            "dgpu = titan-x-maxwell)",
                                            name, fmt::join(presetNames(), ", ")));
  return p->make();
}

bool presetValueInferred(std::string_view preset, std::string_view path) {
  const PresetEntry* p = findPreset(preset);
  return p && std::find(p->inferred.begin(), p->inferred.end(), path) != p->inferred.end();
}

}  // namespace oit::rop
