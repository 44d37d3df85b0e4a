// Stochastic layered alpha blending (Wyman 2016, SIGGRAPH talk), two passes.
// Pass 0 ("select layers"): a fragment F lands between the stored layers in
// front of it and those behind; with C_acc the coverage of the layers in front
// it is inserted with probability P_b(s, t) (eq. 1, stratified):
//   P_b(s, t) = 1 - (s)_t / (b)_t for t <= s, 1 for t > s,
// s = occluded bits, t = F's bits. Beyond k layers the furthest is dropped.
// Pass 1 ("colour"): Enderton et al.'s alpha correction with the stored
// layers as the visibility function: vis_i = coverage left by the layers in
// front; U = sum vis a c, U1 = sum vis a, T = prod (1 - a) (exact, pass 0);
// C = U (1 - T) / U1 + T C_bg.
// Variants: continuous alpha (layers keep alpha; s = C_acc b and t = a b are
// real, P is bilinearly interpolated in the (b+1)^2 table) and coverage masks
// (layers keep a b-bit mask with round(a b) random bits, b <= 32; inserted
// iff (m_occl | m) != m_occl, the event P_b is the probability of).
// Ties: each layer keeps its per-pixel submission index (seq) so an
// equal-depth layer submitted later counts as in front, in both passes.
#include <bit>
#include <cmath>
#include <string>
#include <vector>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {
namespace {

class Slab final : public OitAlgorithm {
 public:
  explicit Slab(const AlgorithmParams& p)
      : k_(p.layers), b_(p.bits), mask_(p.coverage_mask), seed_(p.seed), table_((b_ + 1) * (b_ + 1)) {
    for (unsigned s = 0; s <= b_; ++s)
      for (unsigned t = 0; t <= b_; ++t) {
        double ratio = 1.0;  // (s)_t / (b)_t
        for (unsigned i = 0; i < t && ratio > 0.0; ++i) ratio *= (double(s) - i) / (double(b_) - i);
        table_[s * (b_ + 1) + t] = t > s ? 1.0 : 1.0 - std::max(0.0, ratio);
      }
    acc_ = 3 * k_;
    setLayout({0, StorageFormat::Fp32, 3 * k_ + 7,
               std::string("k layers (z fp32, ") + (mask_ ? "coverage mask u32" : "alpha fp32") +
                   ", seq u32); U r,g,b, U1, T (fp32); per-pass fragment counters (u32 x 2)"});
  }
  std::string_view name() const override { return "slab"; }
  unsigned passes() const override { return 2; }
  std::string_view passName(unsigned pass) const override {
    return pass == 0 ? "select layers" : pass == 1 ? "colour" : "?";
  }

  void clear(uint32_t* w) override {
    for (unsigned i = 0; i < k_; ++i) {
      w[3 * i] = asWord(kInf);
      w[3 * i + 1] = 0;
      w[3 * i + 2] = 0;
    }
    for (unsigned i = 0; i < 7; ++i) w[acc_ + i] = 0;
    w[acc_ + 4] = asWord(1.0f);  // T
  }

  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned pass, const InsertContext& ctx) override {
    if (noContribution(f)) {  // skipped before counting, both passes
      ctx.work = {0, 0};
      return InsertOutcome::Discarded;
    }
    return pass == 0 ? select(w, f, ctx.work) : colour(w, f, ctx.work);
  }

  Rgb resolve(const uint32_t* w, Rgb bg) override {
    const uint32_t* a = w + acc_;  // U rgb, U1, T
    float r = 0, g = 0, b = 0;
    const float T = asFloat(a[4]), u1 = asFloat(a[3]);
    if (u1 > 0.0f) {  // U1 = 0: nothing visible, no 0/0
      r = asFloat(a[0]) / u1 * (1.0f - T);
      g = asFloat(a[1]) / u1 * (1.0f - T);
      b = asFloat(a[2]) / u1 * (1.0f - T);
    }
    return finiteRgb(r + T * bg.r, g + T * bg.g, b + T * bg.b);
  }

  // Words: layers [0, 3k), then from acc_: U r, g, b, U1, T, counter pass 0, counter pass 1.
  // Pass 0 reads and writes the layers, T and its counter (a Discarded
  // fragment still writes T and the counter); pass 1 reads the layers, U, U1
  // and its counter and writes U, U1 and the counter.
  StateRanges readRanges(unsigned pass, InsertOutcome) const override {
    const uint32_t a = 4 * acc_;
    return pass == 0 ? StateRanges::two(0, a, a + 16, a + 24) : StateRanges::two(0, a + 16, a + 24, a + 28);
  }
  StateRanges writeRanges(unsigned pass, InsertOutcome o) const override {
    const uint32_t a = 4 * acc_;
    if (pass == 1) return o == InsertOutcome::Discarded ? StateRanges::none() : StateRanges::two(a, a + 16, a + 24, a + 28);
    return o == InsertOutcome::Discarded ? StateRanges::one(a + 16, a + 24) : StateRanges::two(0, a, a + 16, a + 24);
  }

  // P_b at real-valued (s, t), bilinear in the table (exact at integers).
  double probability(double s, double t) const {
    s = std::clamp(s, 0.0, double(b_));
    t = std::clamp(t, 0.0, double(b_));
    const unsigned s0 = std::min(unsigned(s), b_ - (b_ > 0)), t0 = std::min(unsigned(t), b_ - (b_ > 0));
    const unsigned s1 = std::min(s0 + 1, b_), t1 = std::min(t0 + 1, b_);
    const double fs = s - s0, ft = t - t0;
    auto P = [&](unsigned si, unsigned ti) { return table_[si * (b_ + 1) + ti]; };
    return (1 - fs) * ((1 - ft) * P(s0, t0) + ft * P(s0, t1)) + fs * ((1 - ft) * P(s1, t0) + ft * P(s1, t1));
  }

 private:
  // A b-bit mask with round(a b) bits chosen uniformly (stratified: exact count).
  uint32_t coverageMask(const Fragment& f) const {
    const unsigned t = unsigned(std::lround(double(f.a) * b_));
    unsigned idx[32];
    for (unsigned i = 0; i < b_; ++i) idx[i] = i;
    uint64_t h = fragmentHash(f, seed_, 1);
    uint32_t m = 0;
    for (unsigned i = 0; i < t; ++i) {  // partial Fisher-Yates
      h = h * 6364136223846793005ull + 1442695040888963407ull;
      const unsigned j = i + unsigned((h >> 33) % (b_ - i));
      std::swap(idx[i], idx[j]);
      m |= 1u << idx[i];
    }
    return m;
  }
  static bool inFront(float zl, uint32_t seql, float z, uint32_t seq) {
    return zl < z || (zl == z && seql > seq);
  }

  // Work: every stored layer is compared (its coverage in front is summed);
  // T and the counter are written always, a kept fragment also rewrites the
  // layers from its position (shifted ones and its own).
  InsertOutcome select(uint32_t* w, const Fragment& f, InsertWork& work) {
    w[acc_ + 4] = asWord(asFloat(w[acc_ + 4]) * (1.0f - f.a));  // exact total T for the correction
    const uint32_t seq = w[acc_ + 5]++;
    // Layers are sorted by (z, later first); the new one is the latest.
    unsigned n = 0, p = 0;
    uint32_t occl = 0;
    double keep = 1.0;  // continuous: prod (1 - alpha) of layers in front
    for (; n < k_ && asFloat(w[3 * n]) != kInf; ++n) {
      if (asFloat(w[3 * n]) < f.z) {
        p = n + 1;
        if (mask_) occl |= w[3 * n + 1];
        else keep *= 1.0 - asFloat(w[3 * n + 1]);
      }
    }
    work = {uint8_t(n), 1};
    if (p == k_) return InsertOutcome::Discarded;  // behind a full list
    uint32_t cov;
    if (mask_) {
      // Explicit masks: the paper's own test (Sec. 4.2), insert iff the mask
      // has a bit the layers in front do not cover. P_b is only the
      // probability of this event for a mask nobody has drawn; drawing it
      // from the counts with an independent xi would drop fragments whose
      // actual mask is visible (biased against stochastic transparency).
      cov = coverageMask(f);
      if ((occl | cov) == occl) return InsertOutcome::Discarded;
    } else {
      cov = asWord(f.a);
      const double P = probability((1.0 - keep) * b_, double(f.a) * b_);
      const double xi = double(fragmentHash(f, seed_, 0) >> 11) * 0x1p-53;  // uniform [0,1)
      if (!(xi < P)) return InsertOutcome::Discarded;
    }
    const unsigned last = std::min(n, k_ - 1);  // a full list drops its furthest layer
    work.moves = uint8_t(std::min(255u, 2 + last - p));
    for (unsigned i = last; i > p; --i) {
      w[3 * i] = w[3 * (i - 1)];
      w[3 * i + 1] = w[3 * (i - 1) + 1];
      w[3 * i + 2] = w[3 * (i - 1) + 2];
    }
    w[3 * p] = asWord(f.z);
    w[3 * p + 1] = cov;
    w[3 * p + 2] = seq;
    return n == k_ ? InsertOutcome::Merged : InsertOutcome::Stored;  // Merged: furthest layer evicted
  }

  // Work: the layers compared until the first one not in front, one accumulator written.
  InsertOutcome colour(uint32_t* w, const Fragment& f, InsertWork& work) {
    const uint32_t seq = w[acc_ + 6]++;
    float vis;
    unsigned i = 0;
    if (mask_) {
      uint32_t occl = 0;
      for (; i < k_ && inFront(asFloat(w[3 * i]), w[3 * i + 2], f.z, seq); ++i) occl |= w[3 * i + 1];
      vis = 1.0f - float(std::popcount(occl)) / float(b_);
    } else {
      vis = 1.0f;
      for (; i < k_ && inFront(asFloat(w[3 * i]), w[3 * i + 2], f.z, seq); ++i) vis *= 1.0f - asFloat(w[3 * i + 1]);
    }
    work = {uint8_t(std::min(i + 1, k_)), 1};
    uint32_t* a = w + acc_;
    const float va = vis * f.a;
    a[0] = asWord(asFloat(a[0]) + va * f.r);
    a[1] = asWord(asFloat(a[1]) + va * f.g);
    a[2] = asWord(asFloat(a[2]) + va * f.b);
    a[3] = asWord(asFloat(a[3]) + va);
    return InsertOutcome::Stored;
  }

  unsigned k_, b_;
  bool mask_;
  uint64_t seed_;
  std::vector<double> table_;
  unsigned acc_ = 0;
};

}  // namespace

std::unique_ptr<OitAlgorithm> makeSlab(const AlgorithmParams& p) {
  requireLayers("slab", p);
  requireFormat("slab", p, {StorageFormat::Fp32});
  const unsigned maxBits = p.coverage_mask ? 32 : 1024;
  if (p.bits < 1 || p.bits > maxBits)
    badParam("slab", "bits must be in 1.." + std::to_string(maxBits) +
                         (p.coverage_mask ? " with coverage masks" : "") + ", got " + std::to_string(p.bits));
  return std::make_unique<Slab>(p);
}

}  // namespace oit::model::detail
