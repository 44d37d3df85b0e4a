// The two hardware presets (sources: /work/shared/notes/hardware.md; every
// mapping decision is explained in oit_rop/config/CONFIG.md). igpu is RopConfig's
// default, so its preset is the default-constructed struct.
#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

#include "oit_rop/config/ConfigTree.hpp"

namespace oit::rop {
namespace {

RopConfig igpu() {
  RopConfig c;  // RopConfig's defaults are the igpu preset
  c.preset = "igpu";
  return c;
}

// GTX 980-like: 4 ROP partitions x 16 px/clk, 4 x 64-bit GDDR5 at 7 Gbps.
RopConfig dgpu() {
  RopConfig c;
  c.preset = "dgpu";
  c.clock.core_mhz = 1216.0;  // boost clock
  c.partitions.count = 4;
  c.input.fragments_per_clock = 16.0;  // one raster engine (16 px/clk) per partition
  // Little's law: 16 fragments/clock x up to 120 cycles of shader latency in flight.
  c.lock.capacity = 2048;
  // One level for the 4 x 16 KiB ROP caches + the 512 KiB L2 slice of the
  // partition's controller, taken as inclusive: capacity of the L2 slice, a
  // latency near the L2's (66 ns ~ 80 cycles at 1216 MHz).
  c.cache.size_bytes = 512 * 1024;
  c.cache.ways = 16;
  c.cache.miss_queue = 32;
  c.cache.hit_latency = 80;
  c.alu.blends_per_clock = 16;
  c.dram.channels = 4;
  c.dram.channel_gbps = 56.0;  // 7 Gbps x 64 bit / 8 = 56 GB/s; x 4 = 224 GB/s
  c.dram.tck_ns = 0.667;       // as in the notes (a 6 Gbps bin; 7 Gbps would be 0.571 ns)
  c.dram.cl = 24;
  c.dram.trcd = 24;  // read; write tRCD 20 is not modelled separately
  c.dram.trp = 24;
  c.dram.tras = 56;
  c.dram.twtr = 8;  // tWTR 5 ns (Ramulator's GDDR5 speed table) at tCK 0.667 ns
  c.dram.trtw = 2;  // RD->WR = CL + BL/4 + 2 - WL: 2 tCK of idle data bus
  c.dram.trefi_ns = 1900.0;  // 32 ms / 16,384 refresh commands (4 Gb GDDR5, as on the GTX 980)
  c.dram.trfc_ns = 110.0;    // no GDDR5 datasheet at hand: an 8 Gb GDDR6's 110 ns (CONFIG.md)
  c.dram.banks = 16;
  c.dram.row_bytes = 4096;  // 2 KiB page per x32 chip, two chips per 64-bit channel
  c.dram.burst_bytes = 64;  // BL8 x 64 bit
  c.dram.interleave_bytes = 256;
  c.dram.controller_ns = 100.0;  // L2 miss path + controller queues; DRAM "a few hundred ns" in total
  return c;
}

struct PresetEntry {
  const char* name;
  RopConfig (*make)();
  // Paths whose value is an estimate: marked [inferred] in the notes, or not in
  // the notes at all (our choice, argued in CONFIG.md).
  std::vector<std::string_view> inferred;
};

const std::vector<PresetEntry>& presets() {
  static const std::vector<PresetEntry> list = {
      {"igpu", igpu,
       {"partitions.tile_width", "partitions.tile_height", "input.fragments_per_clock",
        "input.latency_min", "input.latency_max", "early_depth.latency", "lock.capacity",
        "lock.shader_tail", "cache.ways", "cache.miss_queue", "cache.hit_latency", "alu.base_latency",
        "alu.cycles_per_compare", "alu.cycles_per_row_moved", "abuffer.nodes_per_pixel",
        "abuffer.max_sorted", "abuffer.atomics_per_clock", "abuffer.atomic_latency", "abuffer.sort_cycles_per_compare",
        "abuffer.sort_cycles_per_move", "abuffer.spill_cycles_per_node", "alu.fp16_rate", "alu.fp32_rate", "dram.row_bytes",
        "dram.interleave_bytes", "dram.controller_ns", "dram.trfc_ns", "dram.write_queue", "dram.write_high", "dram.write_low"}},
      {"dgpu", dgpu,
       {"partitions.tile_width", "partitions.tile_height", "input.fragments_per_clock",
        "input.latency_min", "input.latency_max", "early_depth.latency", "lock.capacity",
        "lock.shader_tail", "cache.size_bytes", "cache.ways", "cache.miss_queue", "cache.hit_latency",
        "alu.base_latency", "alu.cycles_per_compare", "alu.cycles_per_row_moved", "abuffer.nodes_per_pixel",
        "abuffer.max_sorted", "abuffer.atomics_per_clock", "abuffer.atomic_latency", "abuffer.sort_cycles_per_compare",
        "abuffer.sort_cycles_per_move", "abuffer.spill_cycles_per_node", "alu.fp16_rate", "alu.fp32_rate", "dram.row_bytes",
        "dram.interleave_bytes", "dram.controller_ns", "dram.twtr", "dram.trtw", "dram.trefi_ns", "dram.trfc_ns",
        "dram.write_queue", "dram.write_high", "dram.write_low"}},
  };
  return list;
}

const PresetEntry* findPreset(std::string_view name) {
  for (const auto& p : presets())
    if (name == p.name) return &p;
  return nullptr;
}

}  // namespace

std::vector<std::string> presetNames() {
  std::vector<std::string> names;
  for (const auto& p : presets()) names.emplace_back(p.name);
  return names;
}

RopConfig presetConfig(std::string_view name) {
  const PresetEntry* p = findPreset(name);
  if (!p)
    throw std::invalid_argument(
        fmt::format("unknown preset '{}'; known presets: {}", name, fmt::join(presetNames(), ", ")));
  return p->make();
}

bool presetValueInferred(std::string_view preset, std::string_view path) {
  const PresetEntry* p = findPreset(preset);
  return p && std::find(p->inferred.begin(), p->inferred.end(), path) != p->inferred.end();
}

}  // namespace oit::rop
