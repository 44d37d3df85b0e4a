// Order-independent accumulators: weighted sum (Meshkin 2007), weighted
// average (Bavoil & Myers 2008), weighted blended OIT (McGuire & Bavoil 2013).
// Each keeps an RGBA accumulator in the storage format's precision (like a
// render target: fp32, fp16 RGBA16F, or unorm8 RGBA8 which saturates at 1).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "model/AlgorithmDetail.hpp"

namespace oit::model::detail {
namespace {

// The weighted sums every algorithm here keeps: (sum w c, sum w).
inline void accumulate(Rgba& acc, const Fragment& f, float w) {
  acc.r += w * f.r;
  acc.g += w * f.g;
  acc.b += w * f.b;
  acc.a += w;
}

// ---------------------------------------------------------------- wsum
// Accumulates (sum a c, sum a); C = C_bg + sum a c - C_bg sum a, clamped to
// [0,1] because it leaves that range once sum a > 1.
class Wsum final : public OitAlgorithm {
 public:
  explicit Wsum(const AlgorithmParams& p) : fmt_(p.format) {
    setLayout({0, p.format, accWords(p.format), "RGBA accumulator: sum a*c, sum a"});
  }
  std::string_view name() const override { return "wsum"; }
  void clear(uint32_t* w) override { storeAcc(fmt_, {0, 0, 0, 0}, w); }
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext& ctx) override {
    ctx.work = {0, 0};
    if (noContribution(f)) return InsertOutcome::Discarded;
    ctx.work = {0, 1};  // one accumulator
    Rgba acc = loadAcc(fmt_, w);
    accumulate(acc, f, f.a);
    storeAcc(fmt_, acc, w);
    return InsertOutcome::Stored;
  }
  Rgb resolve(const uint32_t* w, Rgb bg) override {
    const Rgba s = loadAcc(fmt_, w);
    auto ch = [&](float sum, float c) { return std::clamp(c + sum - c * s.a, 0.0f, 1.0f); };
    return finiteRgb(ch(s.r, bg.r), ch(s.g, bg.g), ch(s.b, bg.b));
  }

 private:
  StorageFormat fmt_;
};

// ---------------------------------------------------------------- wavg
// Accumulates (sum a c, sum a) and the count n of contributing fragments;
// C = (sum a c / sum a)(1 - T) + C_bg T, T = (1 - sum a / n)^n. Empty or
// zero-alpha pixels give the background (no 0/0).
class Wavg final : public OitAlgorithm {
 public:
  explicit Wavg(const AlgorithmParams& p) : fmt_(p.format), n_at_(accWords(p.format)) {
    setLayout({0, p.format, n_at_ + 1, "RGBA accumulator: sum a*c, sum a; fragment count n (u32)"});
  }
  std::string_view name() const override { return "wavg"; }
  void clear(uint32_t* w) override {
    storeAcc(fmt_, {0, 0, 0, 0}, w);
    w[n_at_] = 0;
  }
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext& ctx) override {
    ctx.work = {0, 0};
    if (noContribution(f)) return InsertOutcome::Discarded;
    ctx.work = {0, 1};  // one accumulator
    Rgba acc = loadAcc(fmt_, w);
    accumulate(acc, f, f.a);
    storeAcc(fmt_, acc, w);
    if (w[n_at_] < UINT32_MAX) ++w[n_at_];
    return InsertOutcome::Stored;
  }
  Rgb resolve(const uint32_t* w, Rgb bg) override {
    const Rgba s = loadAcc(fmt_, w);
    const uint32_t n = w[n_at_];
    if (n == 0 || !(s.a > 0.0f)) return finiteRgb(bg.r, bg.g, bg.b);
    // Quantised sums can exceed n slightly: keep the base in [0,1].
    const double base = std::clamp(1.0 - double(s.a) / n, 0.0, 1.0);
    const float T = float(std::pow(base, double(n)));
    const float cov = 1.0f - T;
    return finiteRgb(s.r / s.a * cov + bg.r * T, s.g / s.a * cov + bg.g * T, s.b / s.a * cov + bg.b * T);
  }

 private:
  StorageFormat fmt_;
  unsigned n_at_;
};

// ---------------------------------------------------------------- wboit
// Accumulates A = sum w (a c, a) and revealage R = prod (1 - a);
// C = A.rgb / clamp(A.a, 1e-4, 5e4) (1 - R) + C_bg R.
class Wboit final : public OitAlgorithm {
 public:
  Wboit(const AlgorithmParams& p) : fmt_(p.format), eq_(p.weight), camera_(p.camera), r_at_(accWords(p.format)) {
    setLayout({0, p.format, r_at_ + 1,
               std::string("RGBA accumulator: sum w*a*c, sum w*a; revealage R (") +
                   (fmt_ == StorageFormat::Fp16 ? "fp16" : "fp32") + ")"});
  }
  std::string_view name() const override { return "wboit"; }

  void beginFrame(const TraceHeader& h) override {
    if (eq_ == 10) return;
    std::optional<CameraPlanes> cam = camera_ ? camera_ : h.camera;
    if (!cam)
      throw std::invalid_argument("wboit: weight eq. " + std::to_string(eq_) +
                                  " needs view-space depth, but the trace header has no camera "
                                  "near/far planes (give them, or use weight 10)");
    if (!(cam->near_plane > 0.0f) || !(cam->far_plane > cam->near_plane) || !std::isfinite(cam->far_plane))
      throw std::invalid_argument("wboit: camera planes need 0 < near < far < inf, got near " +
                                  std::to_string(cam->near_plane) + ", far " +
                                  std::to_string(cam->far_plane));
    near_ = cam->near_plane;
    far_ = cam->far_plane;
    have_camera_ = true;
  }

  void clear(uint32_t* w) override {
    storeAcc(fmt_, {0, 0, 0, 0}, w);
    storeR(w, 1.0f);
  }
  InsertOutcome insert(uint32_t* w, const Fragment& f, unsigned, const InsertContext& ctx) override {
    ctx.work = {0, 0};
    if (noContribution(f)) return InsertOutcome::Discarded;
    ctx.work = {0, 1};  // one accumulator
    // A += w (a c, a): the paper accumulates premultiplied colour times w(z, a),
    // which already holds a factor a (eq. 7-10), so a enters twice.
    const float wa = weight(f);
    Rgba acc = loadAcc(fmt_, w);
    accumulate(acc, f, wa * f.a);
    storeAcc(fmt_, acc, w);
    storeR(w, loadR(w) * (1.0f - f.a));
    return InsertOutcome::Stored;
  }
  Rgb resolve(const uint32_t* w, Rgb bg) override {
    const Rgba s = loadAcc(fmt_, w);
    const float R = loadR(w);
    const float den = std::clamp(s.a, 1e-4f, 5e4f), cov = 1.0f - R;
    return finiteRgb(s.r / den * cov + bg.r * R, s.g / den * cov + bg.g * R, s.b / den * cov + bg.b * R);
  }

  // w(z, a) as the paper writes it, alpha times the clamped depth term
  // (eq. 7-9 on view-space |z|, eq. 10 on window depth).
  float weight(const Fragment& f) const {
    if (eq_ == 10) {
      const float d = 1.0f - f.z;
      return f.a * std::max(1e-2f, 3e3f * d * d * d);
    }
    if (!have_camera_) throw std::logic_error("wboit: beginFrame() was not called");
    // Perspective window depth d in [0,1] back to view distance:
    // z = n f / (f - d (f - n)); d = 0 -> n, d = 1 -> f.
    const float z = near_ * far_ / (far_ - f.z * (far_ - near_));
    float v;
    if (eq_ == 7) {
      const float a = z / 5.0f, b = z / 200.0f;
      v = 10.0f / (1e-5f + a * a + b * b * b * b * b * b);
    } else if (eq_ == 8) {
      const float a = z / 10.0f, b = z / 200.0f;
      v = 10.0f / (1e-5f + a * a * a + b * b * b * b * b * b);
    } else {
      const float b = z / 200.0f;
      v = 0.03f / (1e-5f + b * b * b * b);
    }
    return f.a * std::clamp(v, 1e-2f, 3e3f);
  }

 private:
  float loadR(const uint32_t* w) const {
    return fmt_ == StorageFormat::Fp16 ? decodeHalf(uint16_t(w[r_at_])) : asFloat(w[r_at_]);
  }
  void storeR(uint32_t* w, float R) const {
    w[r_at_] = fmt_ == StorageFormat::Fp16 ? uint32_t(encodeHalf(R)) : asWord(R);
  }

  StorageFormat fmt_;
  int eq_;
  std::optional<CameraPlanes> camera_;
  unsigned r_at_;
  float near_ = 0, far_ = 0;
  bool have_camera_ = false;
};

}  // namespace

std::unique_ptr<OitAlgorithm> makeWsum(const AlgorithmParams& p) { return std::make_unique<Wsum>(p); }
std::unique_ptr<OitAlgorithm> makeWavg(const AlgorithmParams& p) { return std::make_unique<Wavg>(p); }
std::unique_ptr<OitAlgorithm> makeWboit(const AlgorithmParams& p) {
  // Weights reach 3e3: an unorm8 accumulator saturates on the first fragment.
  requireFormat("wboit", p, {StorageFormat::Fp32, StorageFormat::Fp16});
  if (p.weight != 7 && p.weight != 8 && p.weight != 9 && p.weight != 10)
    badParam("wboit", "weight must be 7, 8, 9 or 10, got " + std::to_string(p.weight));
  return std::make_unique<Wboit>(p);
}

}  // namespace oit::model::detail
