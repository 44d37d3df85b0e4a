// CacheLevel: a shared cache level between the partitions and DRAM (l2, and
// an l3 of the same kind behind it): set-associative per slice, LRU,
// write-back and write-allocate, with valid and dirty bits per sector, lines
// spread over address-hashed slices, each slice a port of
// `bytes_per_clock`. Optionally a victim cache (`victim_only`): it is filled
// only with the evictions of the level above and reads that miss it do not
// allocate. Reservation style, as the DRAM (MEMORY.md, "Shared cache levels"):
// an access books its slice's port and the level below and returns the cycle
// its data is there (read) or accepted (write); no event queue.
#pragma once

#include <array>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "oit_rop/config/RopConfig.hpp"
#include "oit_rop/memory/PortCalendar.hpp"
#include "oit_rop/stages/PipelineQueues.hpp"
#include "oit_rop/Types.hpp"

namespace oit::rop {

// What a level did, per surface where it says so. Counts are per line an
// access touched (an access spanning two lines counts two).
struct LevelStats {
  using PerSurface = std::array<uint64_t, kSurfaceCount>;
  PerSurface accesses{}, hits{}, misses{};
  PerSurface read_bytes{}, write_bytes{};      // requested by the level above (or its victims, written in)
  PerSurface fill_bytes{}, writeback_bytes{};  // moved to / from the level below
  PerSurface writebacks{};                     // lines written back (or handed to a victim level)
  // Misses by cause (the 3 C's): compulsory = a sector the level never held
  // before; conflict = a fully associative LRU cache of the same capacity
  // would have hit; capacity = it would have missed too.
  uint64_t compulsory_misses = 0, capacity_misses = 0, conflict_misses = 0;
  uint64_t victims_in = 0;  // lines written in by the level above's evictions (victim_only)
  static uint64_t total(const PerSurface& v) {
    uint64_t n = 0;
    for (uint64_t x : v) n += x;
    return n;
  }
};

// Fully associative LRU of a fixed number of lines, plus the sectors of every
// line ever held: classifies a real cache's misses (LevelStats's 3 C's).
class MissClassifier {
 public:
  explicit MissClassifier(uint64_t lines);
  ~MissClassifier();
  MissClassifier(const MissClassifier&) = delete;
  MissClassifier& operator=(const MissClassifier&) = delete;
  // Every access of the real cache, in its order: `line` (an address / line
  // size) needing `sectors`. Returns what a miss of the real cache is.
  enum class Kind : uint8_t { Compulsory, Capacity, Conflict };
  Kind access(uint64_t line, uint32_t sectors);
  // The line's sectors arrived without an access (a victim written in).
  void install(uint64_t line, uint32_t sectors);

 private:
  struct Impl;
  Impl* impl_;
};

class CacheLevel final : public MemoryPort {
 public:
  // `lower`: the level below (a CacheLevel or the DRAM). `victim_sink`: the
  // level below when it is victim_only (its CacheLevel), which then receives
  // every eviction of this level, clean or dirty; null otherwise (dirty
  // evictions are written to `lower`). `lookback`: how far behind the latest
  // request another may come (callers a quantum apart: PortCalendar).
  // `classify_misses`: keep LevelStats's 3 C's (a fully associative shadow of
  // as many lines as the level: stats.level_miss_classes); without it they
  // stay 0 and nothing else changes.
  CacheLevel(std::string name, const SharedCacheConfig& cfg, Cycle lookback, MemoryPort& lower,
             CacheLevel* victim_sink = nullptr, bool classify_misses = true);
  ~CacheLevel() override;

  // Read: the cycle the bytes are there. Write: the cycle the level accepted
  // them (posted: a write-back of the level above does not wait for its fill).
  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) override;
  // An eviction of the level above: the sectors `valid` of its line at `addr`
  // (a line of `line_bytes` bytes, `sector_bytes` each), those in `dirty`
  // dirty (victim_only levels).
  void insertVictim(Cycle now, uint64_t addr, uint32_t line_bytes, uint32_t sector_bytes, uint32_t valid,
                    uint32_t dirty, Surface s);
  // Every dirty sector still held (frame end), merged into runs per line.
  void dirtyRanges(std::vector<DirtyRange>& out) const;

  // The host memory a level of configuration `cfg` takes when a frame puts
  // `lines_touched` distinct lines through it: the pages of its tag store
  // those lines' sets occupy (sets are taken in address order, so a frame
  // touches min(sets, lines) of them) and, with `classify_misses`, the
  // shadow's entries. For oitsim run's memory pre-check (apps/RunMemory),
  // which checks it against measured peaks.
  static uint64_t hostBytesEstimate(const SharedCacheConfig& cfg, bool classify_misses, uint64_t lines_touched);

  const std::string& name() const { return name_; }
  const SharedCacheConfig& config() const { return cfg_; }
  const LevelStats& stats() const { return stats_; }
  bool classifiesMisses() const { return classes_ != nullptr; }
  uint32_t sets() const { return sets_; }
  uint32_t lineBytes() const { return cfg_.line_bytes; }
  uint32_t sectorBytes() const { return sector_bytes_; }
  unsigned sliceOf(uint64_t addr) const;
  uint32_t setOf(uint64_t addr) const;
  bool resident(uint64_t addr) const;  // the line holding addr is in the cache (any sector)

 private:
  // A way's state apart from its tag and LRU stamp. A set is one block of
  // the tag store: its ways' tags, then their stamps, then these records, so
  // a lookup compares the set's tags, 8 B per way (a 16-way set of a 128 MB
  // level is 2 host cache lines instead of the 10 of whole records: the l3's
  // lookups were most of the engines' time, bench/RESULTS-timing.md session
  // 17), while a set still occupies one stretch of memory (three arrays
  // touched a page each per set: +1 MB of resident memory on a 1024x512
  // frame). All zero = an invalid way, so the store can be allocated zeroed
  // by the system (calloc): the pages of sets never used are never touched (a
  // 128 MB level has 2 M lines; a frame uses a fraction of them).
  struct Line {
    Cycle ready = 0;  // its last fill's data is there
    uint32_t valid = 0, dirty = 0;
    Surface surface = Surface::BlendArrays;  // of its last writer (write-backs count by it)
  };
  static constexpr size_t kNoWay = ~size_t(0);
  // A way's share of its set's block in the tag store: its tag, its stamp, its Line.
  static constexpr size_t kWayBytes = 2 * sizeof(uint64_t) + sizeof(Line);
  struct FreeDeleter {
    void operator()(void* p) const { std::free(p); }
  };
  // A way is named by (set number << way_shift_) + way in the set; a set by
  // its way 0.
  uint32_t setIndex(uint64_t line) const;            // the line's set inside its slice
  size_t setOfLine(uint64_t line, unsigned& slice) const;  // the line's set (its way 0), and its slice
  uint64_t* tagsOf(size_t way) const {  // the tags of the way's set (then its stamps, then its records)
    return reinterpret_cast<uint64_t*>(store_.get() + (way >> way_shift_) * block_bytes_);
  }
  uint64_t& tag(size_t way) const { return tagsOf(way)[way & way_mask_]; }  // line number + 1; 0 = invalid
  uint64_t& stamp(size_t way) const { return tagsOf(way)[cfg_.ways + (way & way_mask_)]; }  // LRU: larger = more recent
  Line& record(size_t way) const { return reinterpret_cast<Line*>(tagsOf(way) + 2 * size_t(cfg_.ways))[way & way_mask_]; }
  // The way holding `line` in the set `set`, or kNoWay.
  size_t find(size_t set, uint64_t line) const {
    const uint64_t* const t = tagsOf(set);
    for (unsigned w = 0; w < cfg_.ways; ++w)
      if (t[w] == line + 1) return set + w;
    return kNoWay;
  }
  // A way for `line` in its set (invalid first, else LRU), the old line evicted.
  size_t allocate(Cycle now, size_t set, uint64_t line);
  void evict(Cycle now, size_t way);
  void touchLru(size_t way) { stamp(way) = ++stamp_; }
  // Port booking: the slice's port moves `bytes` from `now` on, in the
  // earliest capacity free (PortCalendar); returns the cycle the transfer
  // starts, `end` the cycle it is done.
  Cycle bookPort(unsigned slice, Cycle now, uint32_t bytes, Cycle& end) {
    Cycle start;
    ports_[slice].book(now, bytes, start, end);
    return start;
  }
  // Sectors of the line holding [addr, addr + bytes) that the range covers at
  // all / covers wholly. Inline: most accesses are a whole line (a line-sized
  // fill or write-back), the rest a sector loop (partSectorsOf).
  void sectorsOf(uint64_t line_addr, uint64_t addr, uint32_t bytes, uint32_t& any, uint32_t& whole) const {
    if (addr <= line_addr && addr + bytes >= line_addr + cfg_.line_bytes) [[likely]] {
      any = whole = all_sectors_;
      return;
    }
    partSectorsOf(line_addr, addr, bytes, any, whole);
  }
  void partSectorsOf(uint64_t line_addr, uint64_t addr, uint32_t bytes, uint32_t& any, uint32_t& whole) const;
  // Reads the sectors `mask` of `line` from the level below (a run per
  // contiguous group); returns their completion.
  Cycle fetch(Cycle at, uint64_t line, uint32_t mask, Surface s);
  void classify(uint64_t line, uint32_t sectors, bool missed) {  // inline: off by default, a test per line
    if (classes_) classifyMiss(line, sectors, missed);
  }
  void classifyMiss(uint64_t line, uint32_t sectors, bool missed);
  void dirtyRuns(size_t way, std::vector<DirtyRange>& out) const;  // a way's dirty sectors, in runs

  std::string name_;
  SharedCacheConfig cfg_;
  MemoryPort& lower_;
  CacheLevel* victim_sink_;
  uint32_t sector_bytes_, all_sectors_, sets_;
  unsigned line_shift_ = 0;  // log2(line_bytes)
  int slice_shift_ = -1;     // log2(slices), -1 when not a power of two
  bool sets_pow2_ = false;
  // The tag store: a block of block_bytes_ per set, slice-major (slice x sets + set); calloc'd.
  std::unique_ptr<unsigned char[], FreeDeleter> store_;
  size_t block_bytes_ = 0;  // ways x (tag + stamp + Line)
  unsigned way_shift_ = 0;  // log2 of ways rounded up to a power of two
  size_t way_mask_ = 0;
  std::vector<uint64_t> set_used_;  // a bit per set (slice x sets + set) ever allocated into: dirtyRanges scans those
  std::vector<PortCalendar> ports_;  // per slice
  uint64_t stamp_ = 0;
  std::unique_ptr<MissClassifier> classes_;  // null: misses not classified
  LevelStats stats_;
};

}  // namespace oit::rop
