#include "oit_rop/stages/FrontEnd.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace oit::rop {

namespace {
constexpr size_t kHighWatermark = size_t(1) << 20;  // records per partition backlog
constexpr size_t kLowWatermark = kHighWatermark / 2;
constexpr size_t kRouteChunk = 8192;  // records routed per refill() (a source batch may hold more)
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr size_t kPrefetchAhead = 16;  // records ahead: 16 ran about 1 % faster than 8 or 32 (bench trace, session 13)
}  // namespace

FrameGeometry::FrameGeometry(uint32_t w, uint32_t h, const PartitionConfig& p, LockGranularity lock)
    : width(w), height(h), tile_w(p.tile_width), tile_h(p.tile_height), partitions(p.count) {
  if (tile_w == 0 || tile_h == 0) throw std::invalid_argument("partitions.tile_width/tile_height must be > 0");
  if (partitions == 0 || partitions > 255) throw std::invalid_argument("partitions.count must be in [1, 255]");
  const uint32_t tile_px = tile_w * tile_h;
  if ((tile_px & (tile_px - 1)) != 0)
    throw std::invalid_argument("partitions.tile_width/tile_height must be powers of two");
  tile_shift = 0;
  while ((1u << tile_shift) != tile_px) ++tile_shift;
  tiles_x = (w + tile_w - 1) / tile_w;
  tiles_y = (h + tile_h - 1) / tile_h;
  tile_col.resize(w);
  tile_row.resize(h);
  pix_col.resize(w);
  pix_row.resize(h);
  for (uint32_t x = 0; x < w; ++x) {
    tile_col[x] = x / tile_w;
    pix_col[x] = tile_col[x] * tile_px + x % tile_w;
  }
  for (uint32_t y = 0; y < h; ++y) {
    tile_row[y] = (y / tile_h) * tiles_x;
    pix_row[y] = tile_row[y] * tile_px + (y % tile_h) * tile_w;
  }
  owner.resize(size_t(tiles_x) * tiles_y);
  local.resize(owner.size());
  const uint32_t per_row = (tiles_x + partitions - 1) / partitions;  // a partition's tiles in one row, at most
  for (uint32_t ty = 0; ty < tiles_y; ++ty)
    for (uint32_t tx = 0; tx < tiles_x; ++tx) {
      owner[size_t(ty) * tiles_x + tx] = uint8_t((tx + ty) % partitions);
      local[size_t(ty) * tiles_x + tx] = ty * per_row + tx / partitions;  // tx = r + N j: j is unique in the row
    }
  // A quad is 2x2 screen-aligned pixels; with even tile sizes (config: powers
  // of two, at least 2 for quad locks) it never straddles two tiles.
  const uint32_t qw = (tile_w + 1) / 2, qh = (tile_h + 1) / 2;
  lock_row.resize(h);
  lock_col.resize(w);
  switch (lock) {
    case LockGranularity::Pixel:
      lock_per_tile = tile_w * tile_h;
      for (uint32_t y = 0; y < h; ++y) lock_row[y] = (y % tile_h) * tile_w;
      for (uint32_t x = 0; x < w; ++x) lock_col[x] = x % tile_w;
      break;
    case LockGranularity::Quad:
      lock_per_tile = qw * qh;
      for (uint32_t y = 0; y < h; ++y) lock_row[y] = (y % tile_h) / 2 * qw;
      for (uint32_t x = 0; x < w; ++x) lock_col[x] = (x % tile_w) / 2;
      break;
    case LockGranularity::Tile:
      lock_per_tile = 1;  // lock_row and lock_col stay 0
      break;
  }
}

FrontEnd::FrontEnd(FragmentSource& src, model::OitAlgorithm& algo, const model::DrawClassifier& classes,
                   const model::OpaqueLayer& opaque, std::vector<uint64_t> opaque_per_partition,
                   const FrameGeometry& geo, const RopConfig& cfg)
    : src_(src),
      algo_(algo),
      classes_(classes),
      opaque_(opaque),
      geo_(geo),
      hierarchical_(cfg.early_depth.hierarchical),
      prim_runs_(cfg.lock.per_primitive && cfg.lock.granularity != LockGranularity::Pixel),
      defer_(cfg.lock.mode != LockMode::Ordered),
      words_(algo.stateWords()),
      passes_(algo.passes()),
      state_(size_t(geo.width) * geo.height * algo.stateWords()),
      queues_(geo.partitions, Fifo<InRec>(1u << 12)),
      deferred_(geo.partitions, Fifo<Fragment>(defer_ ? 1u << 12 : 2)),
      opaque_per_part_(std::move(opaque_per_partition)) {
  const size_t pixels = size_t(geo.width) * geo.height;
  algo_.clearFrame(state_.data(), pixels);

  // Hierarchical Z per tile from the final opaque depth (+inf where none landed).
  const uint32_t tiles = geo.tiles();
  hiz_min_.assign(tiles, kInf);
  hiz_max_.assign(tiles, -kInf);
  landed_.assign(tiles, 0);
  tile_nodes_.assign(algo.bounded() ? 0 : tiles, 0);
  if (cfg.lock.mode == LockMode::None) updates_.assign(pixels, 0);
  for (uint32_t y = 0; y < geo.height; ++y)
    for (uint32_t x = 0; x < geo.width; ++x) {
      const size_t p = size_t(y) * geo.width + x;
      const uint32_t t = geo.tileOf(x, y);
      const float z = opaque.depth[p];
      hiz_min_[t] = std::min(hiz_min_[t], z);
      hiz_max_[t] = std::max(hiz_max_[t], z);
      if (opaque.landed(p)) ++landed_[t];
    }
  if (opaque_per_part_.size() != geo.partitions)
    throw std::invalid_argument("FrontEnd: opaque_per_partition needs one count per partition");
  counts_.pass_outcomes.assign(passes_, {});
  src_.rewind();
  ++source_reads_;
}

bool FrontEnd::canRefill() const {
  if (exhausted_) return false;
  for (const auto& q : queues_)
    if (q.size() >= kHighWatermark) return false;
  return true;
}

void FrontEnd::wakeWaiters(unsigned partition) {
  if (queues_[partition].size() == kLowWatermark) {
    waiters_ = 0;
    drained_.notify(sc_core::SC_ZERO_TIME);
  }
}

FrontEnd::PixelState FrontEnd::pixelState() {
  return {&algo_, state_.data(), words_, geo_.width, opaque_.depth.data(),
          tile_nodes_.empty() ? nullptr : tile_nodes_.data(), updates_.empty() ? nullptr : updates_.data()};
}

void FrontEnd::addOutcomes(unsigned pass, const std::array<uint64_t, model::kOutcomeCount>& outcomes) {
  auto& out = counts_.pass_outcomes.at(pass);
  for (unsigned o = 0; o < model::kOutcomeCount; ++o) {
    out[o] += outcomes[o];
    counts_.bytes_read += outcomes[o] * algo_.readBytes(pass, model::InsertOutcome(o));
    counts_.bytes_written += outcomes[o] * algo_.writeBytes(pass, model::InsertOutcome(o));
  }
  if (pass == 0) {
    counts_.stored += outcomes[size_t(model::InsertOutcome::Stored)];
    counts_.merged += outcomes[size_t(model::InsertOutcome::Merged)];
    counts_.discarded += outcomes[size_t(model::InsertOutcome::Discarded)];
  }
}

// The per-record loop of refill(). Everything it reads or counts is held in
// locals: algo_.insert() is an opaque virtual call, after which member fields
// would be reloaded and member counters stored back on every record. First:
// pass 0, which also counts per draw, the opaque and culled totals and (A-buffer)
// the nodes stored per tile;
// Hierarchical: early_depth.hierarchical (a test per record less);
// Defer: lock.mode unordered / none, the fragment goes to its partition's
// deferred() queue uninserted (the partition inserts it at lock entry).
template <bool First, bool Hierarchical, bool Defer>
void FrontEnd::route(std::span<const Fragment> batch) {
  model::OitAlgorithm& algo = algo_;
  const model::OitAlgorithm::InsertFn insert = algo.insertFn();
  const unsigned pass = pass_, words = words_;
  const uint32_t width = geo_.width;
  const uint32_t* const tile_row = geo_.tile_row.data();
  const uint32_t* const tile_col = geo_.tile_col.data();
  const uint32_t* const pix_row = geo_.pix_row.data();
  const uint32_t* const pix_col = geo_.pix_col.data();
  const uint8_t* const owner = geo_.owner.data();
  const uint32_t* const local = geo_.local.data();
  const uint32_t* const lock_row = geo_.lock_row.data();
  const uint32_t* const lock_col = geo_.lock_col.data();
  const uint32_t lock_per_tile = geo_.lock_per_tile;
  const float* const hiz_min = hiz_min_.data();
  const float* const hiz_max = hiz_max_.data();
  uint32_t* const tile_nodes = tile_nodes_.empty() ? nullptr : tile_nodes_.data();
  Fifo<InRec>* const queues = queues_.data();
  Fifo<Fragment>* const deferred = deferred_.data();
  uint32_t* const state = state_.data();
  const float* const opaque_z = opaque_.depth.data();
  std::array<uint64_t, model::kOutcomeCount> outcomes{};
  uint64_t opaque = 0, culled = 0;
  // Per-draw counts of the current run of one draw, added to per_draw_ when it ends.
  uint32_t last_draw = ~0u;
  bool last_opaque = false;
  DrawCounts* dc = nullptr;
  DrawCounts run{};
  const auto flushRun = [&] {
    if (dc) {
      dc->fragments += run.fragments;
      dc->culled += run.culled;
      dc->inserted += run.inserted;
    }
    run = DrawCounts{};
  };
  model::InsertContext ctx;
  uint32_t seq = uint32_t(index_);
  uint32_t run_draw = run_draw_, run_prim = run_prim_, run_start = run_start_;
  const bool prim_runs = prim_runs_;
  const size_t n = batch.size();
  const size_t pixel_bytes = size_t(words) * sizeof(uint32_t);
  for (size_t i = 0; i < n; ++i, ++seq) {
    // The state (tens of MB) and the opaque depth are touched in quad order:
    // fetch the lines of a record a few iterations ahead (a hint only; the
    // prefetched record may be opaque or culled).
    if (i + kPrefetchAhead < n) {
      const Fragment& a = batch[i + kPrefetchAhead];
      const size_t ap = size_t(a.y) * width + a.x;
      if constexpr (!Defer) {  // (deferred: the partition touches the state, later)
        const char* line = reinterpret_cast<const char*>(state + ap * words);
        __builtin_prefetch(line, 1);
        if (pixel_bytes > 64) __builtin_prefetch(line + pixel_bytes - 1, 1);
      }
      __builtin_prefetch(opaque_z + ap);
    }
    const Fragment& f = batch[i];
    if (f.draw != last_draw) {
      last_draw = f.draw;
      last_opaque = classes_.isOpaque(f.draw);
      if constexpr (First) {
        flushRun();
        dc = last_opaque ? nullptr : &per_draw_[f.draw];
      }
    }
    if (last_opaque) {
      if constexpr (First) ++opaque;
      continue;
    }
    const uint32_t pixel = uint32_t(f.y) * width + f.x;
    const uint32_t tile = tile_row[f.y] + tile_col[f.x];
    const float oz = opaque_z[pixel];
    if (!prim_runs) {
      run_start = seq;  // offset 0: the lock does not group (and does not read it)
    } else if ((f.prim != run_prim) | (f.draw != run_draw) | (seq - run_start > 0xFFFF)) {
      run_draw = f.draw;
      run_prim = f.prim;
      run_start = seq;
    }
    InRec r{local[tile] * lock_per_tile + lock_row[f.y] + lock_col[f.x], pix_row[f.y] + pix_col[f.x], seq, 0, 0,
            uint16_t(seq - run_start), {0, 0}};
    if (Hierarchical ? !(f.z < hiz_min[tile] || f.z >= hiz_max[tile]) : true) r.flags |= InRec::kNeedsDepthRead;
    if (f.z >= oz) {  // at or behind the opaque surface: culled
      r.flags |= InRec::kCulled;
      r.outcome = InRec::kCulledKind;
      if constexpr (First) {
        ++culled;
        ++run.fragments;
        ++run.culled;
      }
    } else if constexpr (Defer) {
      r.flags |= InRec::kDeferredInsert;
      deferred[owner[tile]].push(f);
      if constexpr (First) {
        ++run.fragments;
        ++run.inserted;
      }
    } else {
      ctx.opaque_z = oz;
      const model::InsertOutcome o = insert(algo, state + size_t(pixel) * words, f, pass, ctx);
      r.outcome = uint8_t(o);
      r.work = ctx.work;
      ++outcomes[size_t(o)];
      if constexpr (First) {
        ++run.fragments;
        ++run.inserted;
        if (tile_nodes && o == model::InsertOutcome::Stored) ++tile_nodes[tile];
      }
    }
    queues[owner[tile]].push(r);
  }
  if constexpr (First) flushRun();
  run_draw_ = run_draw;
  run_prim_ = run_prim;
  run_start_ = run_start;
  index_ += n;
  if constexpr (!Defer) addOutcomes(pass, outcomes);
  counts_.opaque += opaque;
  counts_.culled += culled;
}

template <bool First>
void FrontEnd::routeBatch(std::span<const Fragment> batch) {
  if (defer_)
    hierarchical_ ? route<First, true, true>(batch) : route<First, false, true>(batch);
  else
    hierarchical_ ? route<First, true, false>(batch) : route<First, false, false>(batch);
}

void FrontEnd::refill() {
  if (exhausted_) return;
  // A source batch is routed kRouteChunk records at a time: the queue records
  // a chunk writes are still in the L2 when the partitions read them.
  if (pending_.empty()) pending_ = src_.next();  // valid until the next next()
  const std::span<const Fragment> batch = pending_.first(std::min(pending_.size(), kRouteChunk));
  pending_ = pending_.subspan(batch.size());
  if (batch.empty()) {
    // End of pass: every partition drains before its next pass (or resolve).
    for (auto& q : queues_) q.push(InRec{0, 0, 0, InRec::kPassEnd, 0, 0, {0, 0}});
    if (pass_ == 0) counts_.fragments_in = index_;
    if (progress_) progress_(double(pass_ + 1) / passes_, std::string(algo_.passName(pass_)));
    if (++pass_ < passes_) {
      src_.rewind();
      ++source_reads_;
      index_ = 0;
      run_draw_ = run_prim_ = ~0u;  // seq starts again: no run carries over
      next_progress_ = kProgressRecords;
    } else {
      exhausted_ = true;
    }
    return;
  }
  if (pass_ == 0)
    routeBatch<true>(batch);
  else
    routeBatch<false>(batch);
  if (progress_ && index_ >= next_progress_) {
    next_progress_ = index_ + kProgressRecords;
    const uint64_t total = std::max<uint64_t>(1, src_.header().fragment_count);
    progress_((pass_ + std::min(1.0, double(index_) / double(total))) / passes_, std::string(algo_.passName(pass_)));
  }
}

}  // namespace oit::rop
