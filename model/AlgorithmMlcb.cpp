// Multi-layered coverage blending (Wyman 2016, Sec. 5), one pass.
// MLAB's sorted k-layer list, but each layer holds a straight colour c, a
// depth z and a b-bit *pre-occluded* coverage mask m' (eq. 11) instead of
// premultiplied colour and transmittance:
//   insert: m = hashed alpha-to-coverage mask; m' = m & ~(OR of the masks in
//           front); the layers behind lose the bits of m' (they stay
//           pre-occluded, so all stored masks are pairwise disjoint);
//   merge (k + 1 layers): the last two become c = (|m'_k| c_k + |m'_k+1| c_k+1)
//           / |m'_k | m'_k+1|, m = m'_k | m'_k+1, z = z_k (eq. 12-14);
//   resolve (eq. 15): C = (|~OR m'| C_bg + sum |m'_i| c_i) / b.
// The fragments carry no geometric coverage (m_geom = all ones), so
// m = m_a2c: floor(a b) or ceil(a b) bits (stochastic rounding, E = a b),
// at hashed positions. Layout, traffic and deviations: ALGORITHMS.md.
#include <bit>
#include <cmath>
#include <string>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {

uint64_t mlcbCoverageMask(const Fragment& f, unsigned bits, uint64_t seed) {
  // Stochastic rounding keeps every fragment's expected coverage exactly
  // a b, which makes the no-merge result an unbiased estimate of the
  // reference; an integral a b (e.g. dyadic alpha) always gets exactly a b bits.
  const double ab = std::clamp(double(f.a), 0.0, 1.0) * bits;
  unsigned n = unsigned(ab);
  const double frac = ab - n;
  if (frac > 0.0 && double(fragmentHash(f, seed, 0) >> 11) * 0x1p-53 < frac) ++n;
  n = std::min(n, bits);
  const uint64_t full = bits == 64 ? ~uint64_t(0) : (uint64_t(1) << bits) - 1;
  // Draw the smaller of the set / unset positions (at most b/2 steps): a
  // uniform n-subset's complement is a uniform (b - n)-subset.
  const bool invert = 2 * n > bits;
  const unsigned draw = invert ? bits - n : n;
  unsigned idx[64];
  for (unsigned i = 0; i < bits; ++i) idx[i] = i;
  uint64_t h = fragmentHash(f, seed, 1);
  uint64_t m = 0;
  for (unsigned i = 0; i < draw; ++i) {  // partial Fisher-Yates: distinct uniform positions
    h = h * 6364136223846793005ull + 1442695040888963407ull;
    // Multiply-shift range reduction (no division); bias < 64 / 2^32.
    const unsigned j = i + unsigned(((h >> 32) * uint64_t(bits - i)) >> 32);
    std::swap(idx[i], idx[j]);
    m |= uint64_t(1) << idx[i];
  }
  return invert ? ~m & full : m;
}

namespace {

struct Layer {
  float r, g, b;  // straight colour (the paper stores c_i unpremultiplied)
  float z;        // +inf when empty
  uint64_t m;     // pre-occluded coverage; 0 exactly when empty
};

class Mlcb final : public OitAlgorithm {
 public:
  explicit Mlcb(const AlgorithmParams& p) : k_(p.layers), b_(p.bits), fmt_(p.format), seed_(p.seed) {
    // Colour words per format, and the spare bits they leave for a small mask:
    // rgba8 uses the T byte of the MLAB row, fp16 the upper half of word 1.
    unsigned spare = 0;
    switch (fmt_) {
      case StorageFormat::Fp32: cw_ = 3; spare = 0; break;
      case StorageFormat::Fp16: cw_ = 2; spare = 16; break;
      case StorageFormat::Rgba8T8Z32: cw_ = 1; spare = 8; break;
    }
    inline_ = b_ <= spare;
    mw_ = inline_ ? 0 : (b_ <= 32 ? 1 : 2);
    lw_ = cw_ + 1 + mw_;
    full_ = b_ == 64 ? ~uint64_t(0) : (uint64_t(1) << b_) - 1;
    setLayout({0, fmt_, k_ * lw_,
               std::string("k layers: colour (") + toString(fmt_) + " rgb" +
                   (inline_ ? ", mask in the spare bits" : "") + "), z fp32" +
                   (inline_ ? "" : mw_ == 1 ? ", mask u32" : ", mask u64")});
  }
  std::string_view name() const override { return "mlcb"; }

  void clear(uint32_t* w) override {
    for (unsigned i = 0; i < k_; ++i) store(w, i, Layer{0, 0, 0, kInf, 0});
  }

  // Work: the position search compares layers 0..p (their masks ORed); the
  // new layer and every layer behind it (masks cleared, shifted) are
  // rewritten, which includes the merged last layer.
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext& ctx) override {
    ctx.work = {0, 0};
    if (noContribution(f)) return InsertOutcome::Discarded;  // a = 0: common rule
    const uint64_t m = mlcbCoverageMask(f, b_, seed_);
    if (m == 0) return InsertOutcome::Discarded;  // rounded to no coverage: contributes nothing
    Layer L[kMaxLayers + 1];
    unsigned n = 0;
    while (n < k_ && (L[n] = load(w, n)).m != 0) ++n;
    // MLAB's `f.z <= z_i`: the new fragment goes in front of equal depths (tie rule).
    unsigned p = 0;
    uint64_t occl = 0;
    while (p < n && !(f.z <= L[p].z)) occl |= L[p++].m;
    const uint64_t mv = m & ~occl;
    ctx.work.compares = uint8_t(std::min(p + 1, std::max(n, 1u)));
    // Fully hidden by nearer layers: it can never show (the coverage in front
    // of a depth only grows), so it takes no layer and nothing is written.
    if (mv == 0) return InsertOutcome::Discarded;
    // Shift the layers behind, take away the new bits (eq. 11 kept true for
    // them) and drop any that lose all coverage: an empty mask adds nothing.
    unsigned out = p;
    Layer behind[kMaxLayers];
    unsigned nb = 0;
    for (unsigned i = p; i < n; ++i) {
      Layer l = L[i];
      l.m &= ~mv;
      if (l.m != 0) behind[nb++] = l;
    }
    L[out++] = Layer{f.r, f.g, f.b, f.z, mv};
    for (unsigned i = 0; i < nb; ++i) L[out++] = behind[i];
    InsertOutcome o = InsertOutcome::Stored;
    if (out > k_) {  // k + 1 layers: merge the last two (eq. 12-14)
      Layer& a = L[k_ - 1];
      const Layer& c = L[k_];
      const float na = float(std::popcount(a.m)), nc = float(std::popcount(c.m));
      const float s = na + nc;  // masks are disjoint: |a | c| = |a| + |c|
      a.r = (na * a.r + nc * c.r) / s;
      a.g = (na * a.g + nc * c.g) / s;
      a.b = (na * a.b + nc * c.b) / s;
      a.m |= c.m;  // z stays the nearer one's
      out = k_;
      p = std::min(p, k_ - 1);  // the merged layer may sit in front of the new one
      o = InsertOutcome::Merged;
    }
    for (unsigned i = p; i < k_; ++i) store(w, i, i < out ? L[i] : Layer{0, 0, 0, kInf, 0});
    ctx.work.moves = uint8_t(std::max(n, out) - p);
    return o;
  }

  Rgb resolve(const uint32_t* w, Rgb bg) override {
    // Eq. 15 in double: exact for the bit counts, one rounding at the end.
    double r = 0, g = 0, b = 0;
    unsigned covered = 0;
    for (unsigned i = 0; i < k_; ++i) {
      const Layer l = load(w, i);
      if (l.m == 0) break;  // sorted and compact: only empty layers follow
      const unsigned n = unsigned(std::popcount(l.m));
      covered += n;
      r += double(n) * l.r;
      g += double(n) * l.g;
      b += double(n) * l.b;
    }
    const double rest = double(b_ - std::min(covered, b_));  // disjoint masks: covered <= b
    return finiteRgb(float((r + rest * bg.r) / b_), float((g + rest * bg.g) / b_),
                     float((b + rest * bg.b) / b_));
  }

 private:
  Layer load(const uint32_t* w, unsigned i) const {
    const uint32_t* q = w + i * lw_;
    Layer l;
    uint32_t spareBits = 0;
    switch (fmt_) {
      case StorageFormat::Fp32:
        l.r = asFloat(q[0]);
        l.g = asFloat(q[1]);
        l.b = asFloat(q[2]);
        break;
      case StorageFormat::Fp16:
        l.r = decodeHalf(uint16_t(q[0]));
        l.g = decodeHalf(uint16_t(q[0] >> 16));
        l.b = decodeHalf(uint16_t(q[1]));
        spareBits = q[1] >> 16;
        break;
      case StorageFormat::Rgba8T8Z32:
        l.r = decodeUnorm8(uint8_t(q[0]));
        l.g = decodeUnorm8(uint8_t(q[0] >> 8));
        l.b = decodeUnorm8(uint8_t(q[0] >> 16));
        spareBits = q[0] >> 24;
        break;
    }
    l.z = asFloat(q[cw_]);
    if (inline_) l.m = spareBits;
    else l.m = mw_ == 1 ? q[cw_ + 1] : (uint64_t(q[cw_ + 1]) | uint64_t(q[cw_ + 2]) << 32);
    l.m &= full_;  // foreign bits beyond b never count
    return l;
  }
  void store(uint32_t* w, unsigned i, const Layer& l) const {
    uint32_t* q = w + i * lw_;
    const uint32_t spareBits = inline_ ? uint32_t(l.m) : 0;
    switch (fmt_) {
      case StorageFormat::Fp32:
        q[0] = asWord(l.r);
        q[1] = asWord(l.g);
        q[2] = asWord(l.b);
        break;
      case StorageFormat::Fp16:
        q[0] = uint32_t(encodeHalf(l.r)) | uint32_t(encodeHalf(l.g)) << 16;
        q[1] = uint32_t(encodeHalf(l.b)) | spareBits << 16;
        break;
      case StorageFormat::Rgba8T8Z32:
        q[0] = (encodeUnorm8x4(l.r, l.g, l.b, 0.0f) & 0xFFFFFFu) | spareBits << 24;
        break;
    }
    q[cw_] = asWord(l.z);
    if (mw_ >= 1) q[cw_ + 1] = uint32_t(l.m);
    if (mw_ == 2) q[cw_ + 2] = uint32_t(l.m >> 32);
  }

  unsigned k_, b_;
  StorageFormat fmt_;
  uint64_t seed_;
  unsigned cw_ = 3, mw_ = 1, lw_ = 5;  // colour / mask / layer words
  bool inline_ = false;
  uint64_t full_ = 0;
};

}  // namespace

std::unique_ptr<OitAlgorithm> makeMlcb(const AlgorithmParams& p) {
  requireLayers("mlcb", p);
  if (p.bits < 1 || p.bits > 64)
    badParam("mlcb", "bits must be in 1..64 (one u64 mask per layer), got " + std::to_string(p.bits));
  return std::make_unique<Mlcb>(p);
}

}  // namespace oit::model::detail
