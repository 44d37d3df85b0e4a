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
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

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
  // A miss that allocates is neither before its victim was accepted below.
  Cycle access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) override;
  // An eviction of the level above: the sectors `valid` of its line at `addr`
  // (a line of `line_bytes` bytes, `sector_bytes` each), those in `dirty`
  // dirty (victim_only levels). Returns the cycle the line was accepted: its
  // bytes crossed this level's port, and what this level wrote below for it
  // (its own evictions, the bytes it does not hold) was accepted there. The
  // evicting level's way is not free before (MEMORY.md, "Shared cache
  // levels": who waits for a write-back).
  Cycle insertVictim(Cycle now, uint64_t addr, uint32_t line_bytes, uint32_t sector_bytes, uint32_t valid,
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
  // The LRU clock's next stamp (tests: its 32-bit wrap renumbers the stamps).
  void setLruClock(uint32_t next) { stamp_ = next - 1; }

 private:
  // A way's state apart from its tag, LRU stamp and surface. A set is one
  // 64-byte-aligned block of the tag store: its ways' tags (32 bits: line
  // number + 1), then their stamps (32 bits), then their surfaces (a byte),
  // then these records, so a lookup compares the set's tags in one host
  // cache line for 16 ways (the l2's and l3's tag lookups miss the host's
  // caches in stores of megabytes: most of the engines' time,
  // bench/RESULTS-timing.md sessions 17 and 20), and a set still occupies
  // one stretch of memory (arrays apart touch a page each per set: +1 MB of
  // resident memory on a 1024x512 frame). All zero = an invalid way, so the
  // store can be allocated zeroed by the system (calloc): the pages of sets
  // never used are never touched (a 128 MB level has 2 M lines; a frame uses
  // a fraction of them).
  struct Line {
    // Its latest fill: the cycle its data is there (the low 40 bits) and how
    // long after its request to the level below (the high 24, saturated):
    // a reader whose lookup came before that request (a partition behind
    // the one that missed) waits as long from its own lookup (readyFor).
    uint64_t fill = 0;
    uint32_t valid = 0, dirty = 0;
    static constexpr unsigned kReadyBits = 40;
    static constexpr uint64_t kReadyMask = (uint64_t(1) << kReadyBits) - 1, kMaxLatency = (uint64_t(1) << 24) - 1;
    Cycle ready() const { return fill & kReadyMask; }
    // When the data is there for a lookup done at `looked_up`.
    Cycle readyFor(Cycle looked_up) const {
      const Cycle r = ready(), latency = fill >> kReadyBits;
      return r - latency > looked_up ? looked_up + latency : r;
    }
  };
  static_assert(sizeof(Line) == 16);
  // A fill of `l` asked below at `asked` whose data is there at `ready`: it
  // becomes the line's fill when it is there later than the one it has.
  void recordFill(Line& l, Cycle asked, Cycle ready) const {
    if (ready <= l.ready()) return;
    if (ready > Line::kReadyMask) [[unlikely]] cycleOutOfRange(ready);
    l.fill = ready | std::min<uint64_t>(ready - std::min(asked, ready), Line::kMaxLatency) << Line::kReadyBits;
  }
  [[noreturn]] void cycleOutOfRange(Cycle c) const;
  static constexpr size_t kNoWay = ~size_t(0);
  // Where a set's records start in its block, and the block's size (a
  // multiple of the host's 64-byte cache line, so that a set's tags never
  // straddle two).
  static constexpr size_t recordsOffset(unsigned ways) { return (size_t(ways) * 9 + 15) & ~size_t(15); }
  static constexpr size_t blockBytes(unsigned ways) {
    return (recordsOffset(ways) + size_t(ways) * sizeof(Line) + 63) & ~size_t(63);
  }
  // The largest line number a 32-bit tag holds (tags are line number + 1).
  static constexpr uint64_t kMaxLine = 0xFFFFFFFEull;
  struct FreeDeleter {
    void operator()(void* p) const { std::free(p); }
  };
  // A way is named by (set number << way_shift_) + way in the set; a set by
  // its way 0.
  uint32_t setIndex(uint64_t line) const;            // the line's set inside its slice
  size_t setOfLine(uint64_t line, unsigned& slice) const;  // the line's set (its way 0), and its slice
  uint32_t* tagsOf(size_t way) const {  // the tags of the way's set (then its stamps, surfaces, records)
    return reinterpret_cast<uint32_t*>(blocks_ + (way >> way_shift_) * block_bytes_);
  }
  uint32_t& tag(size_t way) const { return tagsOf(way)[way & way_mask_]; }  // line number + 1; 0 = invalid
  uint32_t& stamp(size_t way) const { return tagsOf(way)[cfg_.ways + (way & way_mask_)]; }  // LRU: larger = more recent
  Surface& surface(size_t way) const {  // of the line's last writer (write-backs count by it)
    return reinterpret_cast<Surface*>(tagsOf(way) + 2 * size_t(cfg_.ways))[way & way_mask_];
  }
  Line& record(size_t way) const {
    return reinterpret_cast<Line*>(reinterpret_cast<unsigned char*>(tagsOf(way)) + records_offset_)[way & way_mask_];
  }
  // The line number a valid way holds.
  uint64_t lineOf(size_t way) const { return uint64_t(tag(way)) - 1; }
  // Refuses a line number a 32-bit tag cannot hold (an address past 2^32
  // lines: 256 GiB with 64-byte lines; the model's address maps stay far
  // below). Inline: one compare per access.
  void checkLine(uint64_t line) const {
    if (line > kMaxLine) [[unlikely]] lineOutOfRange(line);
  }
  [[noreturn]] void lineOutOfRange(uint64_t line) const;
  // The way holding `line` in the set `set`, or kNoWay.
  size_t find(size_t set, uint64_t line) const {
    const uint32_t* const t = tagsOf(set);
    const uint32_t want = uint32_t(line + 1);
    unsigned w = 0;
#if defined(__SSE2__)
    // Four tags per compare (a set's tags start on a 64-byte boundary; a
    // line is in one way at most, so the first match is the match).
    const __m128i k = _mm_set1_epi32(int(want));
    for (; w + 4 <= cfg_.ways; w += 4) {
      const __m128i four = _mm_load_si128(reinterpret_cast<const __m128i*>(t + w));
      const unsigned m = unsigned(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(four, k))));
      if (m) return set + w + unsigned(std::countr_zero(m));
    }
#endif
    for (; w < cfg_.ways; ++w)
      if (t[w] == want) return set + w;
    return kNoWay;
  }
  // A way for `line` in its set (invalid first, else LRU), the old line
  // evicted; `freed`: the cycle the way is free (below).
  size_t allocate(Cycle now, size_t set, uint64_t line, Cycle& freed) {
    return install(now, set, pickVictim(set), line, freed);
  }
  size_t pickVictim(size_t set) const;  // the way allocate() would take
  // `line` into `way`, its old line evicted; `freed`: the cycle the level
  // below accepted the old line (evict()), `now` when it left nothing to write.
  size_t install(Cycle now, size_t set, size_t way, uint64_t line, Cycle& freed);
  // Asks the host to bring the tags and stamps of the set `line` maps to
  // into its caches (a hint: no state changes). The level above calls it
  // for its victim before its own fill, so the two host cache misses overlap.
  void prefetchSet(uint64_t line) const {
    unsigned slice;
    const unsigned char* const b = reinterpret_cast<const unsigned char*>(tagsOf(setOfLine(line, slice)));
    __builtin_prefetch(b, 1);
    __builtin_prefetch(b + 64, 1);
  }
  // Empties `way`: its dirty sectors written below, or the whole line handed
  // to the victim level. Returns the cycle the level below accepted them
  // (`now` when nothing went below): the way is not free before. No
  // write-back buffer is modelled apart from the level below's own: the DRAM
  // controller's write queue (dram.write_queue) is the buffer between the
  // last level and DRAM, and pushes back when full (MEMORY.md).
  Cycle evict(Cycle now, size_t way);
  // Stamps are 32 bits: when the clock wraps, every used set's stamps are
  // renumbered 1..ways in their order (only the order inside a set matters).
  void touchLru(size_t way) {
    if (++stamp_ == 0) [[unlikely]] renumberStamps();
    stamp(way) = stamp_;
  }
  void renumberStamps();
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
  // The tag store: a block of block_bytes_ per set, slice-major (slice x
  // sets + set); calloc'd, blocks_ its first 64-byte boundary.
  std::unique_ptr<unsigned char[], FreeDeleter> store_;
  unsigned char* blocks_ = nullptr;
  size_t block_bytes_ = 0, records_offset_ = 0;
  unsigned way_shift_ = 0;  // log2 of ways rounded up to a power of two
  size_t way_mask_ = 0;
  std::vector<uint64_t> set_used_;  // a bit per set (slice x sets + set) ever allocated into: dirtyRanges scans those
  std::vector<PortCalendar> ports_;  // per slice
  uint32_t stamp_ = 0;
  std::unique_ptr<MissClassifier> classes_;  // null: misses not classified
  LevelStats stats_;
};

}  // namespace oit::rop
