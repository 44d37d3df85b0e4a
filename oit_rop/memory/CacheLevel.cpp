// A shared cache level (l2 / l3); policies and timing in MEMORY.md.
#include "oit_rop/memory/CacheLevel.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>
#include <utility>

namespace oit::rop {

// Named, not anonymous: MissClassifier::Impl (external linkage) holds two, and
// gcc warns (-Wsubobject-linkage) when a unity build includes this file.
namespace cache_level_detail {

// Open-addressing hash map uint64 -> uint32 with linear probing and
// backward-shift erase (the classifier's tables: lines are sparse, e.g. the
// A-buffer's node pools 2^36 bytes apart).
class LineTable {
 public:
  static constexpr uint64_t kEmpty = ~uint64_t(0);
  LineTable() { rehash(64); }
  uint32_t* find(uint64_t key) {
    for (size_t i = slot(key);; i = (i + 1) & mask_) {
      if (keys_[i] == key) return &values_[i];
      if (keys_[i] == kEmpty) return nullptr;
    }
  }
  uint32_t& operator[](uint64_t key) {
    if (uint32_t* v = find(key)) return *v;
    if (2 * (size_ + 1) > keys_.size()) rehash(keys_.size() * 2);
    size_t i = slot(key);
    while (keys_[i] != kEmpty) i = (i + 1) & mask_;
    keys_[i] = key;
    values_[i] = 0;
    ++size_;
    return values_[i];
  }
  void erase(uint64_t key) {
    size_t i = slot(key);
    while (keys_[i] != key) {
      if (keys_[i] == kEmpty) return;
      i = (i + 1) & mask_;
    }
    // Backward shift: move later entries of the probe run into the hole.
    for (size_t j = (i + 1) & mask_; keys_[j] != kEmpty; j = (j + 1) & mask_) {
      const size_t home = slot(keys_[j]);
      // j's entry may fill the hole at i when its home is not in (i, j] (cyclically).
      if (((j - home) & mask_) >= ((j - i) & mask_)) {
        keys_[i] = keys_[j];
        values_[i] = values_[j];
        i = j;
      }
    }
    keys_[i] = kEmpty;
    --size_;
  }

 private:
  size_t slot(uint64_t key) const { return size_t((key * 0x9E3779B97F4A7C15ull) >> 20) & mask_; }
  void rehash(size_t n) {
    std::vector<uint64_t> keys(n, kEmpty);
    std::vector<uint32_t> values(n, 0);
    keys.swap(keys_);
    values.swap(values_);
    mask_ = n - 1;
    size_ = 0;
    for (size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) (*this)[keys[i]] = values[i];
  }
  std::vector<uint64_t> keys_;
  std::vector<uint32_t> values_;
  size_t mask_ = 0, size_ = 0;
};

}  // namespace cache_level_detail

using cache_level_detail::LineTable;

namespace {

// The slice of a line: its number plus (XOR for a power of two) its bits
// from 12, 24 and 36 up, mod the slices: a sequential stream (fixed high
// bits) walks every slice in turn, and regions far apart (the surfaces, the
// A-buffer's node pools 2^36 bytes apart) start at different slices.
unsigned sliceHash(uint64_t line, unsigned slices) {
  if (slices <= 1) return 0;
  if ((slices & (slices - 1)) == 0) return unsigned((line ^ (line >> 12) ^ (line >> 24) ^ (line >> 36)) & (slices - 1));
  return unsigned((line + (line >> 12) + (line >> 24) + (line >> 36)) % slices);
}

}  // namespace

// ---- MissClassifier ---------------------------------------------------------

struct MissClassifier::Impl {
  uint64_t capacity;
  LineTable slot_of;  // line -> slot in the LRU list
  LineTable seen;     // line -> sectors ever held
  std::vector<uint64_t> key;
  std::vector<uint32_t> prev, next;
  std::vector<uint32_t> valid;  // per slot: the sectors the fully associative cache holds of its line
  uint32_t head = kNone, tail = kNone, used = 0;
  static constexpr uint32_t kNone = ~0u;

  void unlink(uint32_t s) {
    (prev[s] == kNone ? head : next[prev[s]]) = next[s];
    (next[s] == kNone ? tail : prev[next[s]]) = prev[s];
  }
  void pushFront(uint32_t s) {
    prev[s] = kNone;
    next[s] = head;
    (head == kNone ? tail : prev[head]) = s;
    head = s;
  }
  // Touches `line`'s `sectors` in the fully associative LRU (it fills the
  // sectors it lacked, as the real cache does); true when it held them all.
  bool touch(uint64_t line, uint32_t sectors) {
    if (uint32_t* s = slot_of.find(line)) {
      const uint32_t slot = *s;
      unlink(slot);
      pushFront(slot);
      const bool held = (sectors & ~valid[slot]) == 0;
      valid[slot] |= sectors;
      return held;
    }
    uint32_t slot;
    if (used < capacity) {
      slot = used++;
      key.push_back(line);
      prev.push_back(kNone);
      next.push_back(kNone);
      valid.push_back(0);
    } else {
      slot = tail;
      unlink(slot);
      slot_of.erase(key[slot]);
      key[slot] = line;
    }
    slot_of[line] = slot;
    valid[slot] = sectors;
    pushFront(slot);
    return false;
  }
};

MissClassifier::MissClassifier(uint64_t lines) : impl_(new Impl) { impl_->capacity = std::max<uint64_t>(1, lines); }
MissClassifier::~MissClassifier() { delete impl_; }

MissClassifier::Kind MissClassifier::access(uint64_t line, uint32_t sectors) {
  uint32_t& seen = impl_->seen[line];
  const bool fresh = (sectors & ~seen) != 0;
  seen |= sectors;
  const bool fa_hit = impl_->touch(line, sectors);
  if (fresh) return Kind::Compulsory;
  return fa_hit ? Kind::Conflict : Kind::Capacity;
}

void MissClassifier::install(uint64_t line, uint32_t sectors) {
  impl_->seen[line] |= sectors;
  impl_->touch(line, sectors);
}

// ---- CacheLevel ---------------------------------------------------------------

CacheLevel::CacheLevel(std::string name, const SharedCacheConfig& cfg, Cycle lookback, MemoryPort& lower,
                       CacheLevel* victim_sink, bool classify_misses)
    : name_(std::move(name)),
      cfg_(cfg),
      lower_(lower),
      victim_sink_(victim_sink),
      sector_bytes_(cfg.sector_bytes ? cfg.sector_bytes : cfg.line_bytes) {
  if (cfg.size_bytes == 0 || cfg.line_bytes == 0 || cfg.ways == 0 || cfg.slices == 0)
    throw std::invalid_argument(name_ + ": size, line, ways and slices must be > 0");
  if (sector_bytes_ > cfg.line_bytes || cfg.line_bytes % sector_bytes_ != 0 || cfg.line_bytes / sector_bytes_ > 32)
    throw std::invalid_argument(name_ + ": the sector must divide the line into at most 32 sectors");
  if (!(cfg.bytes_per_clock > 0)) throw std::invalid_argument(name_ + ": bytes_per_clock must be > 0");
  const uint64_t per_set = uint64_t(cfg.ways) * cfg.line_bytes * cfg.slices;
  if (cfg.size_bytes % per_set != 0 || cfg.size_bytes / per_set == 0)
    throw std::invalid_argument(fmt::format("{}: size_bytes ({}) is not a whole number of sets (slices x ways x "
                                            "line = {})",
                                            name_, cfg.size_bytes, per_set));
  sets_ = uint32_t(cfg.size_bytes / per_set);
  if ((cfg.line_bytes & (cfg.line_bytes - 1)) != 0) throw std::invalid_argument(name_ + ": line_bytes must be a power of two");
  line_shift_ = unsigned(std::countr_zero(cfg.line_bytes));
  slice_shift_ = (cfg.slices & (cfg.slices - 1)) == 0 ? int(std::countr_zero(cfg.slices)) : -1;
  sets_pow2_ = (sets_ & (sets_ - 1)) == 0;
  const uint32_t sectors = cfg.line_bytes / sector_bytes_;
  all_sectors_ = sectors == 32 ? ~0u : (1u << sectors) - 1;
  block_bytes_ = blockBytes(cfg.ways);
  records_offset_ = recordsOffset(cfg.ways);
  way_shift_ = unsigned(std::bit_width(cfg.ways - 1u));
  way_mask_ = (size_t(1) << way_shift_) - 1;
  // 64 bytes more than the blocks, to start them on a host cache line.
  store_.reset(static_cast<unsigned char*>(std::calloc(size_t(cfg.slices) * sets_ * block_bytes_ + 64, 1)));
  if (!store_) throw std::bad_alloc();
  blocks_ = store_.get() + ((64 - reinterpret_cast<uintptr_t>(store_.get()) % 64) % 64);
  set_used_.assign((size_t(cfg.slices) * sets_ + 63) / 64, 0);
  ports_.assign(cfg.slices, PortCalendar(cfg.bytes_per_clock, lookback));
  if (classify_misses) classes_ = std::make_unique<MissClassifier>(cfg.size_bytes / cfg.line_bytes);
}

CacheLevel::~CacheLevel() = default;

uint64_t CacheLevel::hostBytesEstimate(const SharedCacheConfig& cfg, bool classify_misses, uint64_t lines_touched) {
  if (cfg.size_bytes == 0 || cfg.line_bytes == 0 || cfg.ways == 0) return 0;
  const uint64_t lines = cfg.size_bytes / cfg.line_bytes;
  const uint64_t sets = lines / cfg.ways;
  const uint64_t tags = std::min(sets, lines_touched) * blockBytes(cfg.ways) + lines / 8;
  // The shadow per line it holds: its key, LRU links and sectors (20 B) and
  // two hash-table entries at half load (line -> slot, line -> sectors seen).
  constexpr uint64_t kShadowBytesPerLine = 96;
  return tags + (classify_misses ? std::min(lines, lines_touched) * kShadowBytesPerLine : 0);
}

unsigned CacheLevel::sliceOf(uint64_t addr) const { return sliceHash(addr >> line_shift_, cfg_.slices); }
uint32_t CacheLevel::setOf(uint64_t addr) const { return setIndex(addr >> line_shift_); }

[[gnu::always_inline]] inline uint32_t CacheLevel::setIndex(uint64_t line) const {
  const uint64_t in_slice = slice_shift_ >= 0 ? line >> slice_shift_ : line / cfg_.slices;
  return uint32_t(sets_pow2_ ? in_slice & (sets_ - 1) : in_slice % sets_);
}

[[gnu::always_inline]] inline size_t CacheLevel::setOfLine(uint64_t line, unsigned& slice) const {
  slice = sliceHash(line, cfg_.slices);
  return (size_t(slice) * sets_ + setIndex(line)) << way_shift_;
}

bool CacheLevel::resident(uint64_t addr) const {
  if ((addr >> line_shift_) > kMaxLine) return false;  // no tag holds it
  unsigned slice;
  return find(setOfLine(addr >> line_shift_, slice), addr >> line_shift_) != kNoWay;
}

void CacheLevel::lineOutOfRange(uint64_t line) const {
  throw std::runtime_error(fmt::format("{}: address {:#x} is past the {}-bit tags of its tag store (line numbers up "
                                       "to {:#x} with {}-byte lines)",
                                       name_, line * cfg_.line_bytes, 32, kMaxLine, cfg_.line_bytes));
}

void CacheLevel::cycleOutOfRange(Cycle c) const {
  throw std::runtime_error(fmt::format("{}: cycle {} is past the {}-bit fill times of its tag store", name_, c,
                                       Line::kReadyBits));
}

void CacheLevel::renumberStamps() {
  // Only sets ever allocated into hold stamps; in each, the valid ways'
  // stamps (distinct: every touch takes a new one) become 1..n in their
  // order, and the clock continues after the largest n.
  uint32_t top = 0;
  std::vector<std::pair<uint32_t, unsigned>> order;
  for (size_t word = 0; word < set_used_.size(); ++word)
    for (uint64_t bits = set_used_[word]; bits != 0; bits &= bits - 1) {
      const size_t set = (word * 64 + size_t(std::countr_zero(bits))) << way_shift_;
      order.clear();
      for (unsigned w = 0; w < cfg_.ways; ++w)
        if (tag(set + w) != 0) order.push_back({stamp(set + w), w});
      std::sort(order.begin(), order.end());
      for (uint32_t r = 0; r < order.size(); ++r) stamp(set + order[r].second) = r + 1;
      top = std::max(top, uint32_t(order.size()));
    }
  stamp_ = top + 1;
}

Cycle CacheLevel::evict(Cycle now, size_t way) {
  if (tag(way) == 0) return now;
  Cycle accepted = now;
  Line& l = record(way);
  const uint64_t addr = lineOf(way) * cfg_.line_bytes;
  const Surface surf = surface(way);
  const unsigned si = unsigned(surf);
  if (victim_sink_) {
    // A victim level below takes every eviction, clean or dirty.
    ++stats_.writebacks[si];
    stats_.writeback_bytes[si] += uint64_t(sectorCount(l.valid)) * sector_bytes_;
    accepted = victim_sink_->insertVictim(now, addr, cfg_.line_bytes, sector_bytes_, l.valid, l.dirty, surf);
  } else if (l.dirty) {
    ++stats_.writebacks[si];
    forEachRun(l.dirty, [&](uint32_t s, uint32_t e) {  // a write per run of dirty sectors
      const uint32_t bytes = (e - s) * sector_bytes_;
      stats_.writeback_bytes[si] += bytes;
      accepted = std::max(accepted, lower_.access(now, addr + uint64_t(s) * sector_bytes_, bytes, true, surf));
    });
  }
  l = Line{};
  tag(way) = 0;
  stamp(way) = 0;
  surface(way) = Surface::BlendArrays;
  return accepted;
}

size_t CacheLevel::pickVictim(size_t set) const {
  // The first invalid way, else the least recently used (the first of equal
  // stamps); the set's tags and stamps found once, not per way.
  const uint32_t* const tags = tagsOf(set);
  const uint32_t* const stamps = tags + cfg_.ways;
  unsigned v = 0;
  for (unsigned w = 0; w < cfg_.ways; ++w) {
    if (tags[w] == 0) {
      v = w;
      break;
    }
    if (stamps[w] < stamps[v]) v = w;
  }
  return set + v;
}

size_t CacheLevel::install(Cycle now, size_t set, size_t way, uint64_t line, Cycle& freed) {
  const size_t set_no = set >> way_shift_;
  set_used_[set_no / 64] |= uint64_t(1) << (set_no % 64);
  freed = evict(now, way);
  tag(way) = uint32_t(line + 1);
  return way;
}

void CacheLevel::partSectorsOf(uint64_t line_addr, uint64_t addr, uint32_t bytes, uint32_t& any, uint32_t& whole) const {
  const uint64_t b = std::max(addr, line_addr), e = std::min(addr + bytes, line_addr + cfg_.line_bytes);
  any = whole = 0;
  for (uint64_t s = (b - line_addr) / sector_bytes_; s * sector_bytes_ < e - line_addr; ++s) {
    const uint64_t sb = line_addr + s * sector_bytes_, se = sb + sector_bytes_;
    any |= 1u << s;
    if (b <= sb && e >= se) whole |= 1u << s;
  }
}

Cycle CacheLevel::fetch(Cycle at, uint64_t line, uint32_t mask, Surface s) {
  Cycle done = at;
  const uint64_t addr = line * cfg_.line_bytes;
  forEachRun(mask, [&](uint32_t b, uint32_t e) {
    const uint32_t bytes = (e - b) * sector_bytes_;
    stats_.fill_bytes[unsigned(s)] += bytes;
    done = std::max(done, lower_.access(at, addr + uint64_t(b) * sector_bytes_, bytes, false, s));
  });
  return done;
}

void CacheLevel::classifyMiss(uint64_t line, uint32_t sectors, bool missed) {
  const MissClassifier::Kind k = classes_->access(line, sectors);
  if (!missed) return;
  switch (k) {
    case MissClassifier::Kind::Compulsory: ++stats_.compulsory_misses; break;
    case MissClassifier::Kind::Capacity: ++stats_.capacity_misses; break;
    case MissClassifier::Kind::Conflict: ++stats_.conflict_misses; break;
  }
}

Cycle CacheLevel::access(Cycle now, uint64_t addr, uint32_t bytes, bool write, Surface s) {
  if (bytes == 0) return now;
  const unsigned si = unsigned(s);
  (write ? stats_.write_bytes : stats_.read_bytes)[si] += bytes;
  Cycle done = now;
  const uint64_t first = addr >> line_shift_, last = (addr + bytes - 1) >> line_shift_;
  checkLine(last);
  for (uint64_t line = first; line <= last; ++line) {
    const uint64_t line_addr = line * cfg_.line_bytes;
    const uint64_t b = std::max(addr, line_addr), e = std::min(addr + bytes, line_addr + cfg_.line_bytes);
    uint32_t any, whole;
    sectorsOf(line_addr, addr, bytes, any, whole);
    unsigned slice;
    const size_t set = setOfLine(line, slice);
    Cycle moved;
    const Cycle start = bookPort(slice, now, uint32_t(e - b), moved);
    const Cycle after_lookup = start + cfg_.hit_latency;
    ++stats_.accesses[si];
    size_t way = find(set, line);
    Line* l = way != kNoWay ? &record(way) : nullptr;
    if (!write) {
      const uint32_t missing = l ? any & ~l->valid : any;
      classify(line, any, missing != 0);
      if (missing == 0) {
        ++stats_.hits[si];
        touchLru(way);
        // A fill another partition asked after this lookup (it runs up to a
        // quantum ahead) is this reader's own miss in lockstep: as long
        // from its lookup, not the other's future (Line::readyFor).
        done = std::max({done, after_lookup, moved, l->readyFor(after_lookup)});
        continue;
      }
      ++stats_.misses[si];
      // The way the line will take is chosen before the fill (the fill does
      // not touch this level), so the victim level's set for its old line
      // is on its way into the host's caches while the fill looks up its own.
      size_t victim = kNoWay;
      if (!l && !cfg_.victim_only) {
        victim = pickVictim(set);
        if (victim_sink_ && tag(victim) != 0) victim_sink_->prefetchSet(lineOf(victim));
      }
      // The miss goes below once the lookup is done; a victim level does not
      // allocate what it did not have.
      const Cycle got = fetch(start + cfg_.hit_latency, line, missing, s);
      done = std::max({done, after_lookup, moved, got});
      if (!l && cfg_.victim_only) continue;
      Cycle ready = got;
      if (!l) {
        // The old line's write-back (or its hand-over to the victim level)
        // must be accepted below before the fill can take its way.
        Cycle freed;
        way = install(start, set, victim, line, freed);
        l = &record(way);
        surface(way) = s;
        ready = std::max(ready, freed);
        done = std::max(done, freed);
      }
      l->valid |= missing;
      recordFill(*l, start + cfg_.hit_latency, ready);
      touchLru(way);
      continue;
    }
    // Write (a write-back from above, or a surface write): write-allocate;
    // sectors written only in part keep their other bytes, fetched from below
    // (not waited for: the write is posted).
    const uint32_t missing = l ? any & ~l->valid : any;
    classify(line, any, missing != 0);
    if (missing == 0) ++stats_.hits[si];
    else ++stats_.misses[si];
    done = std::max(done, moved);  // accepted once its bytes crossed the port
    if (!l && cfg_.victim_only) {
      // Not held: straight to the level below (a victim level allocates only
      // victims), accepted when the level below accepted it.
      done = std::max(done, lower_.access(start, b, uint32_t(e - b), true, s));
      stats_.writeback_bytes[si] += e - b;
      continue;
    }
    if (!l) {
      // Accepted once the way is free too (its old line accepted below), and
      // its data is there then, for a reader whose lookup comes after this
      // write (its writer's next read, as before). The write may be another
      // partition's, at its time a quantum ahead of a reader behind (an l2's
      // eviction of that reader's line written into a non-victim l3, the
      // A-buffer's node bursts): that reader waits only as long as the way
      // took, from its own lookup (Line::readyFor), not until the other's
      // future.
      Cycle freed;
      way = allocate(start, set, line, freed);
      l = &record(way);
      recordFill(*l, start, freed);
      done = std::max(done, freed);
    }
    const uint32_t partial = any & ~whole & ~l->valid;
    if (partial) recordFill(*l, after_lookup, fetch(after_lookup, line, partial, s));
    l->valid |= any;
    l->dirty |= any;
    surface(way) = s;
    touchLru(way);
  }
  return done;
}

Cycle CacheLevel::insertVictim(Cycle now, uint64_t addr, uint32_t line_bytes, uint32_t sector_bytes, uint32_t valid,
                               uint32_t dirty, Surface s) {
  const unsigned si = unsigned(s);
  Cycle accepted = now;
  ++stats_.victims_in;
  // The classifier learns each line's sectors once (consecutive installs of
  // one line are one install: nothing else touches it between them).
  uint64_t pending_line = 0;
  uint32_t pending = 0;
  bool has_pending = false;
  const auto flush = [&] {
    if (has_pending) classes_->install(pending_line, pending);
    pending = 0;
    has_pending = false;
  };
  // Each valid sector of the evicted line: a run of bytes, dirty or clean.
  for (uint32_t k = 0; k < 32 && k * sector_bytes < line_bytes; ++k) {
    if (!(valid >> k & 1)) continue;
    const uint64_t a = addr + uint64_t(k) * sector_bytes;
    const bool is_dirty = (dirty >> k & 1) != 0;
    const uint64_t line = a >> line_shift_, line_addr = line << line_shift_;
    checkLine(line);
    uint32_t any, whole;
    sectorsOf(line_addr, a, sector_bytes, any, whole);
    unsigned slice;
    const size_t set = setOfLine(line, slice);
    Cycle moved;
    const Cycle start = bookPort(slice, now, sector_bytes, moved);
    accepted = std::max(accepted, moved);
    stats_.write_bytes[si] += sector_bytes;
    size_t way = find(set, line);
    if (way == kNoWay) {
      if (whole == 0) {
        // Covers no whole sector of ours: dirty bytes go on below, clean ones are dropped.
        if (is_dirty) {
          accepted = std::max(accepted, lower_.access(start, a, sector_bytes, true, s));
          stats_.writeback_bytes[si] += sector_bytes;
        }
        continue;
      }
      Cycle freed;
      way = allocate(start, set, line, freed);
      accepted = std::max(accepted, freed);
      // Not `ready = freed`: with partitions a quantum apart, a victim the
      // partition ahead evicts "later" may be read by the one behind at its
      // own, earlier time; the line's data would then wait for the future.
      // The inserting level already waits for `freed` (accepted).
      surface(way) = s;
    }
    Line* const l = &record(way);
    if (classes_) {
      if (has_pending && line != pending_line) flush();
      pending_line = line;
      pending |= whole;
      has_pending = true;
    }
    l->valid |= whole;
    if (is_dirty) {
      l->dirty |= whole;
      surface(way) = s;
      if (any & ~whole) {  // the rest of a partly covered sector: written through
        accepted = std::max(accepted, lower_.access(start, a, sector_bytes, true, s));
        stats_.writeback_bytes[si] += sector_bytes;
      }
    }
    touchLru(way);
  }
  if (classes_) flush();
  return accepted;
}

void CacheLevel::dirtyRanges(std::vector<DirtyRange>& out) const {
  for (size_t word = 0; word < set_used_.size(); ++word)
    for (uint64_t bits = set_used_[word]; bits != 0; bits &= bits - 1) {
      const size_t set = word * 64 + size_t(std::countr_zero(bits));
      for (unsigned w = 0; w < cfg_.ways; ++w) dirtyRuns((set << way_shift_) + w, out);
    }
}

void CacheLevel::dirtyRuns(size_t way, std::vector<DirtyRange>& out) const {
  if (tag(way) == 0) return;
  const Line& l = record(way);
  const uint64_t addr = lineOf(way) * cfg_.line_bytes;
  const Surface surf = surface(way);
  forEachRun(l.dirty, [&](uint32_t s, uint32_t e) {
    out.push_back({addr + uint64_t(s) * sector_bytes_, (e - s) * sector_bytes_, surf});
  });
}

}  // namespace oit::rop
