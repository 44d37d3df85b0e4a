// Stochastic transparency (Enderton et al. 2010) with alpha correction, two
// passes over the transparent fragments.
// Pass 0 ("depth samples"): a fragment covers round(a S) of the pixel's S
// samples (stratified: exactly that many, chosen by the fragment hash) and
// depth-tests each (a later fragment of equal depth wins, as in the product's
// tie rule); the exact total transmittance T = prod (1 - a) is accumulated
// in the same pass (Enderton uses a separate one).
// Pass 1 ("colour"): vis_i = #{s : z_i <= z_s} / S; U = sum vis a c,
// U1 = sum vis a; C = (U1 > 0 ? U (1 - T) / U1 : 0) + T C_bg.
// Deviation: samples keep no submission index, so in pass 1 two fragments of
// equal depth both count a sample holding that depth as visible.
#include <algorithm>
#include <bit>
#include <string>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {
namespace {

class Stochastic final : public OitAlgorithm {
 public:
  explicit Stochastic(const AlgorithmParams& p) : s_(p.samples), seed_(p.seed) {
    setLayout({0, StorageFormat::Fp32, s_ + 5, "S sample depths (fp32); T (fp32); U r,g,b, U1 (fp32)"});
  }
  std::string_view name() const override { return "stochastic"; }
  unsigned passes() const override { return 2; }
  std::string_view passName(unsigned pass) const override {
    return pass == 0 ? "depth samples" : pass == 1 ? "colour" : "?";
  }
  void clear(uint32_t* w) override {
    for (unsigned i = 0; i < s_; ++i) w[i] = asWord(kInf);
    w[s_] = asWord(1.0f);
    for (unsigned i = 1; i < 5; ++i) w[s_ + i] = 0;
  }
  // Work: pass 0 depth-tests the round(a S) covered samples and writes the
  // ones it wins plus T; pass 1 compares all S samples and writes one
  // accumulator.
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned pass, const InsertContext& ctx) override {
    if (noContribution(f)) {
      ctx.work = {0, 0};
      return InsertOutcome::Discarded;
    }
    if (pass == 0) {
      w[s_] = asWord(asFloat(w[s_]) * (1.0f - f.a));
      const uint64_t m = coverage(f);
      unsigned wrote = 0;
      for (unsigned i = 0; i < s_; ++i)
        if ((m >> i & 1) && f.z <= asFloat(w[i])) {
          w[i] = asWord(f.z);
          ++wrote;
        }
      ctx.work = {uint8_t(std::popcount(m)), uint8_t(wrote + 1)};
      return wrote ? InsertOutcome::Stored : InsertOutcome::Discarded;
    }
    ctx.work = {uint8_t(s_), 1};
    unsigned visible = 0;
    for (unsigned i = 0; i < s_; ++i) visible += f.z <= asFloat(w[i]);
    const float va = float(visible) / float(s_) * f.a;
    uint32_t* u = w + s_ + 1;
    u[0] = asWord(asFloat(u[0]) + va * f.r);
    u[1] = asWord(asFloat(u[1]) + va * f.g);
    u[2] = asWord(asFloat(u[2]) + va * f.b);
    u[3] = asWord(asFloat(u[3]) + va);
    return InsertOutcome::Stored;
  }
  Rgb resolve(const uint32_t* w, Rgb bg) override {
    const float T = asFloat(w[s_]);
    const uint32_t* u = w + s_ + 1;
    const float u1 = asFloat(u[3]);
    float r = 0, g = 0, b = 0;
    if (u1 > 0.0f) {
      r = asFloat(u[0]) / u1 * (1.0f - T);
      g = asFloat(u[1]) / u1 * (1.0f - T);
      b = asFloat(u[2]) / u1 * (1.0f - T);
    }
    return finiteRgb(r + T * bg.r, g + T * bg.g, b + T * bg.b);
  }
  // Words: sample depths [0, S), T at S, U r, g, b, U1 at S + 1 .. S + 4.
  // Pass 0 reads and writes the depths and T (a Discarded fragment still
  // writes T: a > 0); pass 1 reads the depths, U and U1 and writes U and U1.
  StateRanges readRanges(unsigned pass, InsertOutcome) const override {
    const uint32_t d = 4 * s_;
    return pass == 0 ? StateRanges::one(0, d + 4) : StateRanges::two(0, d, d + 4, d + 20);
  }
  StateRanges writeRanges(unsigned pass, InsertOutcome o) const override {
    const uint32_t d = 4 * s_;
    if (pass == 1) return o == InsertOutcome::Discarded ? StateRanges::none() : StateRanges::one(d + 4, d + 20);
    return o == InsertOutcome::Discarded ? StateRanges::one(d, d + 4) : StateRanges::one(0, d + 4);
  }

 private:
  // round(a S) distinct samples, uniformly chosen (partial Fisher-Yates on
  // the fragment hash): stratified coverage.
  uint64_t coverage(const Fragment& f) const {
    const unsigned t = unsigned(std::lround(double(f.a) * s_));
    unsigned idx[64];
    for (unsigned i = 0; i < s_; ++i) idx[i] = i;
    uint64_t h = fragmentHash(f, seed_, 2);
    uint64_t m = 0;
    for (unsigned i = 0; i < t; ++i) {
      h = h * 6364136223846793005ull + 1442695040888963407ull;
      const unsigned j = i + unsigned((h >> 33) % (s_ - i));
      std::swap(idx[i], idx[j]);
      m |= uint64_t(1) << idx[i];
    }
    return m;
  }
  unsigned s_;
  uint64_t seed_;
};

}  // namespace

std::unique_ptr<OitAlgorithm> makeStochastic(const AlgorithmParams& p) {
  requireFormat("stochastic", p, {StorageFormat::Fp32});
  if (p.samples < 1 || p.samples > 64)
    badParam("stochastic", "samples must be in 1..64, got " + std::to_string(p.samples));
  return std::make_unique<Stochastic>(p);
}

}  // namespace oit::model::detail
