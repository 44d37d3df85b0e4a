// Blending-array algorithms: alpha (one accumulator), mlab, hybrid, kbuffer.
// All of them insert with MLAB's `f.z <= B[i].z` bubble, so a later-submitted
// fragment lands in front of stored rows of equal depth (the product's tie rule).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {
namespace {

// A fragment with a = 0 changes no pixel in the reference; letting it take a
// layer would only push real fragments out (notes, pitfall 3). Every
// algorithm therefore discards it without touching the state.
inline bool noContribution(const Fragment& f) { return !(f.a > 0.0f); }

// Rows sorted front to back, empty rows (z = +inf) at the end.
class SortedRows : public OitAlgorithm {
 protected:
  SortedRows(const AlgorithmParams& p, unsigned rows) : fmt_(p.format), rw_(rowWords(p.format)), n_(rows) {}

  void loadRows(const uint32_t* w, LayerRow* rows) const {
    for (unsigned i = 0; i < n_; ++i) rows[i] = loadRow(fmt_, w + i * rw_);
  }
  void storeRows(uint32_t* w, const LayerRow* rows, unsigned from) const {
    for (unsigned i = from; i < n_; ++i) storeRow(fmt_, rows[i], w + i * rw_);
  }
  void clearRows(uint32_t* w) const {
    for (unsigned i = 0; i < n_; ++i) storeRow(fmt_, kEmptyRow, w + i * rw_);
  }
  // MLAB's one-pass bubble: returns the row that falls off the end (the
  // fragment itself, an older row, or an empty row) and sets `first` to the
  // first changed row (n_ when none changed).
  LayerRow bubble(LayerRow* rows, LayerRow cur, unsigned& first) const {
    first = n_;
    for (unsigned i = 0; i < n_; ++i) {
      if (cur.z <= rows[i].z) {
        std::swap(cur, rows[i]);
        if (first == n_) first = i;
      }
    }
    return cur;
  }
  // Front-to-back composite of the rows (eq. 5/6 of the MLAB paper); returns
  // the remaining transmittance in T.
  void composite(const uint32_t* w, float& r, float& g, float& b, float& T) const {
    r = g = b = 0.0f;
    T = 1.0f;
    for (unsigned i = 0; i < n_; ++i) {
      const LayerRow row = loadRow(fmt_, w + i * rw_);
      if (row.z == kInf) break;  // sorted: only empty rows follow
      r += row.r * T;
      g += row.g * T;
      b += row.b * T;
      T *= row.t;
    }
  }

  StorageFormat fmt_;
  unsigned rw_;
  unsigned n_;  // sorted rows
};

// ---------------------------------------------------------------- mlab
class Mlab final : public SortedRows {
 public:
  explicit Mlab(const AlgorithmParams& p) : SortedRows(p, p.layers) {
    setLayout({p.layers, p.format, 0, ""});
  }
  std::string_view name() const override { return "mlab"; }
  void clear(uint32_t* w) override { clearRows(w); }
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext&) override {
    if (noContribution(f)) return InsertOutcome::Discarded;
    if (fmt_ == StorageFormat::Fp32) return insertFp32(w, f);
    LayerRow rows[kMaxLayers];
    loadRows(w, rows);
    unsigned first;
    const LayerRow out = bubble(rows, fragmentRow(f), first);
    InsertOutcome o = InsertOutcome::Stored;
    if (out.z != kInf) {  // k + 1 rows: merge the last two (eq. 7, 8; Z of the nearer)
      LayerRow& l = rows[n_ - 1];
      l.r += out.r * l.t;
      l.g += out.g * l.t;
      l.b += out.b * l.t;
      l.t *= out.t;
      first = std::min(first, n_ - 1);
      o = InsertOutcome::Merged;
    }
    storeRows(w, rows, first);
    return o;
  }
  Rgb resolve(const uint32_t* w, Rgb bg) override {
    float r, g, b, T;
    composite(w, r, g, b, T);
    return finiteRgb(r + bg.r * T, g + bg.g * T, b + bg.b * T);
  }

 private:
  // The same insert in place on fp32 rows (raw LayerRow words): the rows are
  // always sorted by z (`<=`; empty rows, +inf, last), so the bubble is
  // "insert at the first row with f.z <= z, shift the rest down one, the
  // last row falls off". Same float operations as the generic path, so the
  // same bits (bench_functional's checksum and every mlab test unchanged);
  // it only skips copying all k rows out and back.
  InsertOutcome insertFp32(uint32_t* w, const Fragment& f) const {
    constexpr unsigned kRw = 5;
    unsigned p = 0;
    while (p < n_ && !(f.z <= asFloat(w[p * kRw + 4]))) ++p;
    const LayerRow fr = fragmentRow(f);
    LayerRow out = fr;  // p == n_: the fragment itself falls off
    if (p < n_) {
      std::memcpy(&out, w + (n_ - 1) * kRw, sizeof out);
      std::memmove(w + (p + 1) * kRw, w + p * kRw, size_t(n_ - 1 - p) * kRw * sizeof(uint32_t));
      std::memcpy(w + p * kRw, &fr, sizeof fr);
    }
    if (out.z == kInf) return InsertOutcome::Stored;
    LayerRow l;  // merge into the last row (eq. 7, 8; Z of the nearer)
    std::memcpy(&l, w + (n_ - 1) * kRw, sizeof l);
    l.r += out.r * l.t;
    l.g += out.g * l.t;
    l.b += out.b * l.t;
    l.t *= out.t;
    std::memcpy(w + (n_ - 1) * kRw, &l, sizeof l);
    return InsertOutcome::Merged;
  }
};

// ---------------------------------------------------------------- kbuffer
class KBuffer final : public SortedRows {
 public:
  explicit KBuffer(const AlgorithmParams& p) : SortedRows(p, p.layers) {
    setLayout({p.layers, p.format, 0, ""});
  }
  std::string_view name() const override { return "kbuffer"; }
  void clear(uint32_t* w) override { clearRows(w); }
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext&) override {
    if (noContribution(f)) return InsertOutcome::Discarded;
    LayerRow rows[kMaxLayers];
    loadRows(w, rows);
    unsigned first;
    const LayerRow out = bubble(rows, fragmentRow(f), first);  // the furthest row falls off
    // The fragment itself was the furthest: nothing changes, nothing written.
    if (first == n_) return InsertOutcome::Discarded;
    storeRows(w, rows, first);
    // Merged: kept, but an older row was evicted to make room.
    return out.z != kInf ? InsertOutcome::Merged : InsertOutcome::Stored;
  }
  Rgb resolve(const uint32_t* w, Rgb bg) override {
    float r, g, b, T;
    composite(w, r, g, b, T);
    return finiteRgb(r + bg.r * T, g + bg.g * T, b + bg.b * T);
  }
};

// ---------------------------------------------------------------- hybrid
// k-1 core rows + the tail. fp32 keeps the tail unpacked (5 words: r, g, b,
// alpha_sum as binary32, count) so the reference configuration adds no
// quantisation; rgba8t8z32 and fp16 use the paper's packed 8-byte tail.
class Hybrid final : public SortedRows {
 public:
  explicit Hybrid(const AlgorithmParams& p)
      : SortedRows(p, p.layers - 1), packed_(p.format != StorageFormat::Fp32) {
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
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext&) override {
    if (noContribution(f)) return InsertOutcome::Discarded;
    LayerRow rows[kMaxLayers];
    loadRows(w, rows);
    unsigned first;
    const LayerRow out = bubble(rows, fragmentRow(f), first);
    storeRows(w, rows, first);
    if (out.z == kInf) return InsertOutcome::Stored;
    // The overflowing row joins the tail (Listing 2; a row whose stored T
    // rounded to 1 adds nothing, as in the paper).
    if (out.t != 1.0f) {
      HybridTail t = loadTail(w + tail_at_);
      t.r += out.r;
      t.g += out.g;
      t.b += out.b;
      t.alpha_sum += 1.0f - out.t;
      if (t.count < UINT32_MAX) ++t.count;
      storeTail(w + tail_at_, t);
    }
    return InsertOutcome::Merged;
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
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext&) override {
    if (noContribution(f)) return InsertOutcome::Discarded;
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
