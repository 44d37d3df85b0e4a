// Blending-array algorithms: alpha (one accumulator), mlab, hybrid, kbuffer.
// All of them insert with MLAB's `f.z <= B[i].z` bubble, so a later-submitted
// fragment lands in front of stored rows of equal depth (the product's tie rule).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <type_traits>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {
namespace {

// Rows sorted front to back, empty rows (z = +inf) at the end.
//
// Every insert is MLAB's one-pass bubble (`f.z <= B[i].z`: swap and carry
// on), done in place. clear and insert keep the rows sorted by z (`<=`;
// empty rows last; a NaN depth never compares true, so it is never stored),
// so the bubble is "put the fragment at the first row p with f.z <= z_p,
// shift rows p.. down one, the last row falls off": the slot is found on the
// raw z words, only the new row (and a merged last row) goes through the
// codec. Shifted rows move as raw words because every stored code decodes and
// re-encodes to itself (all unorm8 codes and every finite half code; checked
// exhaustively in test_storage_format), so the bits equal those of decoding
// every row, bubbling and re-encoding (test_layered_inplace checks that
// reference). The one exception, fp16's Inf / NaN half codes, never comes from
// encodeHalf; shiftRows still rewrites them as the round trip would.
class SortedRows : public OitAlgorithm {
 public:
  // Every sorted-rows insert: a fragment without contribution is discarded,
  // the rest go to the derived class's insertAt<fmt_>, picked once
  // (pickInsert) and handed to the frame loops as their insertFn().
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned pass, const InsertContext& ctx) final {
    return insert_(*this, w, f, pass, ctx);
  }
  InsertFn insertFn() const final { return insert_; }

 protected:
  SortedRows(const AlgorithmParams& p, unsigned rows) : fmt_(p.format), rw_(rowWords(p.format)), n_(rows) {}
  // For the constructor of A (which befriends SortedRows for its insertAt).
  template <class A>
  void pickInsert() {
    insert_ = withFormat([](auto fmt) -> InsertFn { return &insertVia<A, decltype(fmt)::value>; });
  }

  void clearRows(uint32_t* w) const {
    for (unsigned i = 0; i < n_; ++i) storeRow(fmt_, kEmptyRow, w + i * rw_);
  }
  // fn(std::integral_constant<StorageFormat, fmt_>{}). The inserts pick their
  // instantiation for fmt_ once, in the constructor: row size and codec are
  // compile-time constants, and each format's insert is compiled on its own.
  template <class Fn>
  decltype(auto) withFormat(Fn&& fn) const {
    using enum StorageFormat;
    if (fmt_ == Fp32) return fn(std::integral_constant<StorageFormat, Fp32>{});
    if (fmt_ == Rgba8T8Z32) return fn(std::integral_constant<StorageFormat, Rgba8T8Z32>{});
    return fn(std::integral_constant<StorageFormat, Fp16>{});
  }
  // Where the bubble puts a fragment at depth z: the first row with z <= its
  // depth, n_ when the fragment itself falls off.
  template <StorageFormat F>
  unsigned slot(const uint32_t* w, float z) const {
    constexpr unsigned kRw = rowWords(F);
    unsigned p = 0;
    while (p < n_ && !(z <= asFloat(w[p * kRw + kRw - 1]))) ++p;
    return p;
  }
  // The first empty row at or after `from` (n_ when none): rows are sorted
  // with the empty ones last, so the occupied rows a shift from `from` moves
  // are [from, firstEmpty(from)).
  template <StorageFormat F>
  unsigned firstEmpty(const uint32_t* w, unsigned from) const {
    while (from < n_ && depth<F>(w, from) != kInf) ++from;
    return from;
  }
  template <StorageFormat F>
  static float depth(const uint32_t* w, unsigned row) {
    return asFloat(w[row * rowWords(F) + rowWords(F) - 1]);
  }
  // Rows [from, to) move down one, to [from + 1, to + 1). (memmove pays off
  // for fp32's 5-word rows, a word loop for the 2- and 3-word ones.)
  template <StorageFormat F>
  static void shiftRows(uint32_t* w, unsigned from, unsigned to) {
    constexpr unsigned kRw = rowWords(F);
    if constexpr (F == StorageFormat::Fp32) {
      if (from < to) std::memmove(w + (from + 1) * kRw, w + from * kRw, size_t(to - from) * kRw * sizeof(uint32_t));
    } else {
      for (unsigned i = to; i-- > from;) {
        const uint32_t* s = w + i * kRw;
        uint32_t* d = w + (i + 1) * kRw;
        for (unsigned j = 0; j < kRw; ++j) d[j] = (F == StorageFormat::Fp16 && j < 2) ? requantizedHalves(s[j]) : s[j];
      }
    }
  }
  // eq. 7, 8 of the MLAB paper: the nearer row l absorbs the row behind it
  // and keeps its own Z.
  static void mergeBehind(LayerRow& l, const LayerRow& out) {
    l.r += out.r * l.t;
    l.g += out.g * l.t;
    l.b += out.b * l.t;
    l.t *= out.t;
  }
  // Front-to-back composite of the rows (eq. 5/6 of the MLAB paper); returns
  // the remaining transmittance in T. Per format, as the inserts: the resolve
  // runs once per pixel of the frame, and a runtime format decoded every row
  // through a switch.
  template <StorageFormat F>
  void compositeAt(const uint32_t* w, float& r, float& g, float& b, float& T) const {
    constexpr unsigned kRw = rowWords(F);
    r = g = b = 0.0f;
    T = 1.0f;
    for (unsigned i = 0; i < n_; ++i) {
      const LayerRow row = loadRow(F, w + i * kRw);
      if (row.z == kInf) break;  // sorted: only empty rows follow
      r += row.r * T;
      g += row.g * T;
      b += row.b * T;
      T *= row.t;
    }
  }
  void composite(const uint32_t* w, float& r, float& g, float& b, float& T) const {
    withFormat([&](auto fmt) { compositeAt<decltype(fmt)::value>(w, r, g, b, T); });
  }

  // The rows composited over the background (mlab, kbuffer): resolveRowsAt<fmt_>.
  template <StorageFormat F>
  Rgb resolveRowsAt(const uint32_t* w, Rgb bg) const {
    float r, g, b, T;
    compositeAt<F>(w, r, g, b, T);
    return finiteRgb(r + bg.r * T, g + bg.g * T, b + bg.b * T);
  }
  // Bytes the resolve of the rows reads: rows front to back up to the first
  // empty row or the row that makes the transmittance exactly 0 (both
  // included); the rows behind add exactly nothing, so stopping there gives
  // the image compositeAt gives.
  template <StorageFormat F>
  unsigned resolvedRowBytes(const uint32_t* w) const {
    constexpr unsigned kRw = rowWords(F);
    float T = 1.0f;
    for (unsigned i = 0; i < n_; ++i) {
      const LayerRow row = loadRow(F, w + i * kRw);
      T *= row.t;
      if (row.z == kInf || T == 0.0f) return (i + 1) * 4 * kRw;
    }
    return n_ * 4 * kRw;
  }
  unsigned resolvedRowBytes(const uint32_t* w) const {
    return withFormat([&](auto fmt) { return resolvedRowBytes<decltype(fmt)::value>(w); });
  }
  using ResolveFn = Rgb (SortedRows::*)(const uint32_t*, Rgb) const;
  ResolveFn resolveRowsFn() const {
    return withFormat([](auto fmt) -> ResolveFn { return &SortedRows::resolveRowsAt<decltype(fmt)::value>; });
  }

  StorageFormat fmt_;
  unsigned rw_;
  unsigned n_;  // sorted rows

 private:
  template <class A, StorageFormat F>
  static InsertOutcome insertVia(OitAlgorithm& a, uint32_t* w, const Fragment& f, unsigned, const InsertContext& ctx) {
    if (noContribution(f)) {
      ctx.work = {0, 0};
      return InsertOutcome::Discarded;
    }
    return static_cast<const A&>(a).template insertAt<F>(w, f, ctx.work);
  }
  // Work of a sorted insert (ALGORITHMS.md, "Work per insert"): the slot
  // search compares rows 0..p (p + 1 rows, all n when it falls off the end).
 protected:
  uint8_t comparesTo(unsigned p) const { return uint8_t(std::min(255u, std::min(p + 1, n_))); }
  static uint8_t count(unsigned n) { return uint8_t(std::min(255u, n)); }
 private:
  InsertFn insert_ = nullptr;  // insertVia<the derived class, fmt_>
};

// ---------------------------------------------------------------- mlab
class Mlab final : public SortedRows {
 public:
  explicit Mlab(const AlgorithmParams& p)
      : SortedRows(p, p.layers), resolve_(resolveRowsFn()) {
    pickInsert<Mlab>();
    setLayout({p.layers, p.format, 0, ""});
  }
  std::string_view name() const override { return "mlab"; }
  void clear(uint32_t* w) override { clearRows(w); }
  Rgb resolve(const uint32_t* w, Rgb bg) override { return (this->*resolve_)(w, bg); }
  unsigned resolveBytes(const uint32_t* w) const override { return resolvedRowBytes(w); }

 private:
  friend class SortedRows;  // pickInsert
  // The bubble in place (see SortedRows). With k + 1 rows the one falling
  // off merges into the row that ends up last (eq. 7, 8; Z of the nearer).
  // As in the bubble over decoded rows, the fragment's row takes part
  // unquantised: it is the row falling off when it lands behind every row,
  // and the merge target when it lands in the last row.
  // Work: the slot search's compares; moves = the new row and the occupied
  // rows shifted behind it (a full array: rows p..n-1, the merged last row
  // among them), 1 for a merge into the last row.
  template <StorageFormat F>
  InsertOutcome insertAt(uint32_t* w, const Fragment& f, InsertWork& work) const {
    constexpr unsigned kRw = rowWords(F);
    const unsigned p = slot<F>(w, f.z);
    const LayerRow fr = fragmentRow(f);
    uint32_t* last = w + (n_ - 1) * kRw;
    work.compares = comparesTo(p);
    if (p == n_) {  // behind every row
      if (fr.z == kInf) {  // +inf falls off like an empty row
        work.moves = 0;
        return InsertOutcome::Stored;
      }
      LayerRow l = loadRow(F, last);
      mergeBehind(l, fr);
      storeRow(F, l, last);
      work.moves = 1;
      return InsertOutcome::Merged;
    }
    if (depth<F>(w, n_ - 1) == kInf) {  // an empty row falls off
      work.moves = count(firstEmpty<F>(w, p) - p + 1);
      shiftRows<F>(w, p, n_ - 1);
      storeRow(F, fr, w + p * kRw);
      return InsertOutcome::Stored;
    }
    work.moves = count(n_ - p);
    const LayerRow out = loadRow(F, last);
    LayerRow l = p == n_ - 1 ? fr : loadRow(F, last - kRw);  // row n-2 before the shift
    mergeBehind(l, out);
    if (p < n_ - 1) {
      shiftRows<F>(w, p, n_ - 2);
      storeRow(F, fr, w + p * kRw);
    }
    storeRow(F, l, last);
    return InsertOutcome::Merged;
  }
  ResolveFn resolve_;  // resolveRowsAt<fmt_>
};

// ---------------------------------------------------------------- kbuffer
class KBuffer final : public SortedRows {
 public:
  explicit KBuffer(const AlgorithmParams& p)
      : SortedRows(p, p.layers), resolve_(resolveRowsFn()) {
    pickInsert<KBuffer>();
    setLayout({p.layers, p.format, 0, ""});
  }
  std::string_view name() const override { return "kbuffer"; }
  void clear(uint32_t* w) override { clearRows(w); }
  Rgb resolve(const uint32_t* w, Rgb bg) override { return (this->*resolve_)(w, bg); }
  unsigned resolveBytes(const uint32_t* w) const override { return resolvedRowBytes(w); }
  // The rows are sorted, so the last row alone decides a rejection: a
  // fragment not in front of it (!(z <= its depth)) lands behind every row.
  // The insert reads that row first, so a Discarded insert (rejected, or
  // a = 0) reads one row and writes none; the others read every row.
  StateRanges readRanges(unsigned, InsertOutcome o) const override {
    const uint32_t all = n_ * 4 * rw_;
    return o == InsertOutcome::Discarded ? StateRanges::one(all - 4 * rw_, all) : StateRanges::one(0, all);
  }

 private:
  friend class SortedRows;  // pickInsert
  // The bubble in place (see SortedRows); the furthest of k + 1 rows is dropped.
  // Work: a rejection compares the last row only (the sorted rows' last row
  // decides, as readRanges reads only it) and writes nothing; a kept fragment
  // compares rows 0..p and writes its row and the occupied rows shifted behind it.
  template <StorageFormat F>
  InsertOutcome insertAt(uint32_t* w, const Fragment& f, InsertWork& work) const {
    const unsigned p = slot<F>(w, f.z);
    // The fragment itself was the furthest: nothing changes, nothing written.
    if (p == n_) {
      work = {1, 0};
      return InsertOutcome::Discarded;
    }
    const bool evicts = depth<F>(w, n_ - 1) != kInf;
    work = {comparesTo(p), count(evicts ? n_ - p : firstEmpty<F>(w, p) - p + 1)};
    shiftRows<F>(w, p, n_ - 1);
    storeRow(F, fragmentRow(f), w + p * rowWords(F));
    // Merged: kept, but an older row was evicted to make room.
    return evicts ? InsertOutcome::Merged : InsertOutcome::Stored;
  }
  ResolveFn resolve_;  // resolveRowsAt<fmt_>
};

// ---------------------------------------------------------------- hybrid
// k-1 core rows + the tail. fp32 keeps the tail unpacked (5 words: r, g, b,
// alpha_sum as binary32, count) so the reference configuration adds no
// quantisation; rgba8t8z32 and fp16 use the paper's packed 8-byte tail.
class Hybrid final : public SortedRows {
 public:
  explicit Hybrid(const AlgorithmParams& p)
      : SortedRows(p, p.layers - 1),
        packed_(p.format != StorageFormat::Fp32) {
    pickInsert<Hybrid>();
    tail_at_ = n_ * rw_;
    setLayout({n_, p.format, packed_ ? 2u : 5u,
               packed_ ? "packed tail (colour 3x10 bit, alpha_sum fp16, count 16 bit)"
                       : "tail r, g, b, alpha_sum (fp32), count (u32)"});
  }
  std::string_view name() const override { return "hybrid"; }
  void clear(uint32_t* w) override {
    clearRows(w);
    storeTail(w + tail_at_, HybridTail{0, 0, 0, 0, 0});
  }
  Rgb resolve(const uint32_t* w, Rgb bg) override {
    float r, g, b, T;
    composite(w, r, g, b, T);
    const HybridTail t = loadTail(w + tail_at_);
    if (t.count > 0 && t.alpha_sum > 0.0f) {
      // Weighted average behind the core: colour = acc / accAlpha,
      // alpha = 1 - (1 - accAlpha / count)^count (guarded: no 0/0).
      const double n = t.count;
      const double mean = std::min(1.0, double(t.alpha_sum) / n);
      const float alpha = float(1.0 - std::pow(1.0 - mean, n));
      const float s = alpha / t.alpha_sum;
      r += T * t.r * s;
      g += T * t.g * s;
      b += T * t.b * s;
      T *= 1.0f - alpha;
    }
    return finiteRgb(r + bg.r * T, g + bg.g * T, b + bg.b * T);
  }

 private:
  friend class SortedRows;  // pickInsert
  // The bubble in place over the k - 1 core rows (see SortedRows). The row
  // falling off is the fragment's unquantised row when it lands behind every
  // row, else the old last row (z = +inf: empty, nothing to add).
  // Work: the core's slot search; moves = its row and the occupied core rows
  // shifted behind it, plus the tail when a row joins it.
  template <StorageFormat F>
  InsertOutcome insertAt(uint32_t* w, const Fragment& f, InsertWork& work) const {
    const unsigned p = slot<F>(w, f.z);
    const LayerRow fr = fragmentRow(f);
    LayerRow out = fr;
    work = {comparesTo(p), 0};
    if (p < n_) {
      work.moves = count(std::min(firstEmpty<F>(w, p) + 1, n_) - p);  // a full core: rows p..n-1
      out = kEmptyRow;
      if (depth<F>(w, n_ - 1) != kInf) out = loadRow(F, w + (n_ - 1) * rowWords(F));
      shiftRows<F>(w, p, n_ - 1);
      storeRow(F, fr, w + p * rowWords(F));
    }
    if (out.z == kInf) return InsertOutcome::Stored;
    // The overflowing row joins the tail (Listing 2). A row whose stored T
    // rounded to 1 may still hold colour (fp16 keeps a premultiplied colour of
    // 2e-4 but rounds T = 1 - 2e-4 to 1): its alpha enters as max(r, g, b), a
    // lower bound (premultiplied colour <= alpha), so its colour is kept to
    // first order instead of dropped. Only an empty row adds nothing.
    const float alpha = out.t != 1.0f ? 1.0f - out.t : std::max({out.r, out.g, out.b});
    if (alpha > 0.0f) {
      work.moves = count(work.moves + 1u);
      HybridTail t = loadTail(w + tail_at_);
      t.r += out.r;
      t.g += out.g;
      t.b += out.b;
      t.alpha_sum += alpha;
      if (t.count < UINT32_MAX) ++t.count;
      storeTail(w + tail_at_, t);
    }
    return InsertOutcome::Merged;
  }
  HybridTail loadTail(const uint32_t* w) const {
    if (packed_) return decodeTail(w);
    return {asFloat(w[0]), asFloat(w[1]), asFloat(w[2]), asFloat(w[3]), w[4]};
  }
  void storeTail(uint32_t* w, const HybridTail& t) const {
    if (packed_) return encodeTail(t, w);
    w[0] = asWord(t.r);
    w[1] = asWord(t.g);
    w[2] = asWord(t.b);
    w[3] = asWord(t.alpha_sum);
    w[4] = t.count;
  }
  bool packed_;
  unsigned tail_at_ = 0;
};

// ---------------------------------------------------------------- alpha
// Over-blending in submission order into one RGBA accumulator (premultiplied
// colour, transmittance): A = p + t A, T = t T; resolve A + T bg, which is
// exactly blending each fragment over the background in submission order.
class Alpha final : public OitAlgorithm {
 public:
  explicit Alpha(const AlgorithmParams& p) : fmt_(p.format) {
    setLayout({0, p.format, accWords(p.format), "RGBA accumulator: premultiplied colour, transmittance"});
  }
  std::string_view name() const override { return "alpha"; }
  void clear(uint32_t* w) override { storeAcc(fmt_, {0, 0, 0, 1}, w); }
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext& ctx) override {
    if (noContribution(f)) {
      ctx.work = {0, 0};
      return InsertOutcome::Discarded;
    }
    ctx.work = {0, 1};  // one accumulator
    Rgba acc = loadAcc(fmt_, w);
    const float t = 1.0f - f.a;
    acc.r = f.a * f.r + t * acc.r;
    acc.g = f.a * f.g + t * acc.g;
    acc.b = f.a * f.b + t * acc.b;
    acc.a = t * acc.a;
    storeAcc(fmt_, acc, w);
    return InsertOutcome::Stored;
  }
  Rgb resolve(const uint32_t* w, Rgb bg) override {
    const Rgba acc = loadAcc(fmt_, w);
    return finiteRgb(acc.r + bg.r * acc.a, acc.g + bg.g * acc.a, acc.b + bg.b * acc.a);
  }

 private:
  StorageFormat fmt_;
};

}  // namespace

std::unique_ptr<OitAlgorithm> makeMlab(const AlgorithmParams& p) {
  requireLayers("mlab", p);
  return std::make_unique<Mlab>(p);
}
std::unique_ptr<OitAlgorithm> makeKBuffer(const AlgorithmParams& p) {
  requireLayers("kbuffer", p);
  return std::make_unique<KBuffer>(p);
}
std::unique_ptr<OitAlgorithm> makeHybrid(const AlgorithmParams& p) {
  requireLayers("hybrid", p);
  return std::make_unique<Hybrid>(p);
}
std::unique_ptr<OitAlgorithm> makeAlpha(const AlgorithmParams& p) { return std::make_unique<Alpha>(p); }

}  // namespace oit::model::detail
