// LDR-FLIP, written from the HPG 2020 paper (model/METRICS.md has every step
// and constant). The filtered planes are single precision (as the reference
// implementation filters; half the memory and twice the vector width of
// double: 0.5 s instead of 0.9 s for a 1280x720 pair), the colour conversions
// double; borders clamp to the edge pixel; the 2D filters are applied as
// separable passes (x, then y), which is exact for the Gaussians the paper uses.
#include "model/Flip.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include <fmt/format.h>

namespace oit::model {

namespace {

using Vec3 = std::array<double, 3>;
using Mat3 = std::array<Vec3, 3>;

constexpr double kPi = std::numbers::pi;

// The paper's constants.
constexpr double kQc = 0.7;   // colour error exponent
constexpr double kPc = 0.4;   // share of cmax mapped below kPt
constexpr double kPt = 0.95;  // error the kPc point maps to
constexpr double kW = 0.082;  // degrees: peak-to-trough width of the edge detector
constexpr double kQf = 0.5;   // feature error exponent

Vec3 mul(const Mat3& m, const Vec3& v) {
  return {m[0][0] * v[0] + m[0][1] * v[1] + m[0][2] * v[2], m[1][0] * v[0] + m[1][1] * v[1] + m[1][2] * v[2],
          m[2][0] * v[0] + m[2][1] * v[1] + m[2][2] * v[2]};
}

Mat3 inverse(const Mat3& m) {
  const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  Mat3 r{};
  r[0][0] = (m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det;
  r[0][1] = (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det;
  r[0][2] = (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det;
  r[1][0] = (m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det;
  r[1][1] = (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det;
  r[1][2] = (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det;
  r[2][0] = (m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det;
  r[2][1] = (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det;
  r[2][2] = (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det;
  return r;
}

// Linear sRGB <-> CIE XYZ, derived from the sRGB primaries and the D65 white
// (IEC 61966-2-1 chromaticities): the columns are the primaries' XYZ scaled so
// that RGB (1,1,1) is the white.
struct ColourSpace {
  Mat3 rgb_to_xyz{}, xyz_to_rgb{};
  Vec3 white{};  // XYZ of RGB (1,1,1), Y = 1

  ColourSpace() {
    const double px[3] = {0.64, 0.30, 0.15}, py[3] = {0.33, 0.60, 0.06};
    const double wx = 0.3127, wy = 0.3290;
    Mat3 p{};
    for (int c = 0; c < 3; ++c) {
      p[0][c] = px[c] / py[c];
      p[1][c] = 1.0;
      p[2][c] = (1.0 - px[c] - py[c]) / py[c];
    }
    white = {wx / wy, 1.0, (1.0 - wx - wy) / wy};
    const Vec3 s = mul(inverse(p), white);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) rgb_to_xyz[r][c] = p[r][c] * s[c];
    xyz_to_rgb = inverse(rgb_to_xyz);
  }

  // YCxCz: the linearised CIELAB of the paper (Lab without the cube root).
  Vec3 ycxcz(const Vec3& rgb) const {
    const Vec3 xyz = mul(rgb_to_xyz, rgb);
    const double x = xyz[0] / white[0], y = xyz[1] / white[1], z = xyz[2] / white[2];
    return {116.0 * y - 16.0, 500.0 * (x - y), 200.0 * (y - z)};
  }
  Vec3 linearFromYcxcz(const Vec3& v) const {
    const double y = (v[0] + 16.0) / 116.0;
    const double x = v[1] / 500.0 + y, z = y - v[2] / 200.0;
    return mul(xyz_to_rgb, Vec3{x * white[0], y * white[1], z * white[2]});
  }
  // CIELAB with the a* and b* of the Hunt effect (scaled by 0.01 L*).
  Vec3 huntLab(const Vec3& rgb) const {
    const Vec3 xyz = mul(rgb_to_xyz, rgb);
    constexpr double d = 6.0 / 29.0;
    auto f = [&](double t) { return t > d * d * d ? std::cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0; };
    const double fx = f(xyz[0] / white[0]), fy = f(xyz[1] / white[1]), fz = f(xyz[2] / white[2]);
    const double l = 116.0 * fy - 16.0;
    return {l, 0.01 * l * 500.0 * (fx - fy), 0.01 * l * 200.0 * (fy - fz)};
  }
};

const ColourSpace& space() {
  static const ColourSpace s;
  return s;
}

// HyAB: city-block lightness difference plus Euclidean chroma difference.
double hyab(const Vec3& a, const Vec3& b) {
  const double da = a[1] - b[1], db = a[2] - b[2];
  return std::abs(a[0] - b[0]) + std::sqrt(da * da + db * db);
}

double srgbDecode(double s) { return s <= 0.04045 ? s / 12.92 : std::pow((s + 0.055) / 1.055, 2.4); }

// One channel of the image, row-major, top row first.
using Plane = std::vector<float>;

// out(x) = sum_i k[i] in(x + i - r), the row's edge pixel repeated beyond it.
// Each output sums its taps in the order i = 0..2r; the loops run over whole
// rows so that the compiler vectorises them. `out` is overwritten (no zeroing:
// a 1280x720 frame's planes were a fifth of the run in memset and page faults).
void convolveX(const Plane& in, Plane& out, uint32_t w, uint32_t h, const std::vector<double>& k) {
  const size_t r = k.size() / 2;
  out.resize(in.size());
  std::vector<float> pad(w + 2 * r);
  for (uint32_t y = 0; y < h; ++y) {
    const float* row = in.data() + size_t(y) * w;
    std::fill(pad.begin(), pad.begin() + long(r), row[0]);
    std::copy(row, row + w, pad.begin() + long(r));
    std::fill(pad.begin() + long(r + w), pad.end(), row[w - 1]);
    float* dst = out.data() + size_t(y) * w;
    const float k0 = float(k[0]);
    for (uint32_t x = 0; x < w; ++x) dst[x] = k0 * pad[x];
    for (size_t i = 1; i < k.size(); ++i) {
      const float ki = float(k[i]);
      const float* src = pad.data() + i;
      for (uint32_t x = 0; x < w; ++x) dst[x] += ki * src[x];
    }
  }
}

// The same along columns, the top and bottom rows repeated beyond the frame.
void convolveY(const Plane& in, Plane& out, uint32_t w, uint32_t h, const std::vector<double>& k) {
  const int r = int(k.size() / 2);
  out.resize(in.size());
  for (int y = 0; y < int(h); ++y) {
    float* dst = out.data() + size_t(y) * w;
    for (int i = -r; i <= r; ++i) {
      const float ki = float(k[size_t(i + r)]);
      const float* src = in.data() + size_t(std::clamp(y + i, 0, int(h) - 1)) * w;
      if (i == -r) {
        for (uint32_t x = 0; x < w; ++x) dst[x] = ki * src[x];
      } else {
        for (uint32_t x = 0; x < w; ++x) dst[x] += ki * src[x];
      }
    }
  }
}

// The contrast sensitivity filters (paper, Section 4.1): per opponent channel a
// sum of Gaussians a sqrt(pi / b) exp(-pi^2 d^2 / b) of the distance d in
// degrees, normalised to sum to 1. Achromatic (a, b) = (1, 0.0047), red-green
// (1, 0.0053), blue-yellow (34.1, 0.04) + (13.5, 0.025). The radius covers three
// standard deviations of the widest Gaussian (b = 0.04) for every channel.
struct SpatialFilters {
  std::vector<double> y, cx;
  std::vector<double> cz1, cz2;  // the blue-yellow sum as two separable terms
};

SpatialFilters spatialFilters(double ppd) {
  const double b_max = 0.04;
  const int r = int(std::ceil(3.0 * std::sqrt(b_max / (2.0 * kPi * kPi)) * ppd));
  SpatialFilters f;
  auto gauss = [&](double d2, double a, double b) { return a * std::sqrt(kPi / b) * std::exp(-kPi * kPi * d2 / b); };
  double sy = 0, scx = 0, s1 = 0, s2 = 0;
  for (int i = -r; i <= r; ++i) {
    const double d = i / ppd, d2 = d * d;
    f.y.push_back(gauss(d2, 1.0, 0.0047));
    f.cx.push_back(gauss(d2, 1.0, 0.0053));
    // a sqrt(pi/b) e^{-pi^2 (x^2 + y^2) / b} = [sqrt(a sqrt(pi/b)) e^{-pi^2 x^2 / b}] [same in y]
    f.cz1.push_back(std::sqrt(34.1 * std::sqrt(kPi / 0.04)) * std::exp(-kPi * kPi * d2 / 0.04));
    f.cz2.push_back(std::sqrt(13.5 * std::sqrt(kPi / 0.025)) * std::exp(-kPi * kPi * d2 / 0.025));
    sy += f.y.back();
    scx += f.cx.back();
    s1 += f.cz1.back();
    s2 += f.cz2.back();
  }
  for (double& v : f.y) v /= sy;
  for (double& v : f.cx) v /= scx;
  // The 2D blue-yellow kernel sums to s1^2 + s2^2 (each term is an outer product).
  const double n = std::sqrt(s1 * s1 + s2 * s2);
  for (double& v : f.cz1) v /= n;
  for (double& v : f.cz2) v /= n;
  return f;
}

// Edge and point detectors (paper, Section 4.2): the first and second
// derivatives of a Gaussian with sigma = w / 2 degrees (w = 0.082), radius
// 3 sigma; the Gaussian sums to 1, the positive and negative weights of each
// derivative to +1 and -1.
struct FeatureFilters {
  std::vector<double> g, dg, ddg;
};

FeatureFilters featureFilters(double ppd) {
  const double sigma = 0.5 * kW * ppd;
  const int r = int(std::ceil(3.0 * sigma));
  FeatureFilters f;
  double sg = 0, dpos = 0, dneg = 0, ddpos = 0, ddneg = 0;
  for (int i = -r; i <= r; ++i) {
    const double x = i, g = std::exp(-(x * x) / (2.0 * sigma * sigma));
    const double dg = -x * g, ddg = (x * x / (sigma * sigma) - 1.0) * g;
    f.g.push_back(g);
    f.dg.push_back(dg);
    f.ddg.push_back(ddg);
    sg += g;
    (dg > 0 ? dpos : dneg) += std::abs(dg);
    (ddg > 0 ? ddpos : ddneg) += std::abs(ddg);
  }
  for (size_t i = 0; i < f.g.size(); ++i) {
    f.g[i] /= sg;
    f.dg[i] /= f.dg[i] > 0 ? dpos : dneg;
    f.ddg[i] /= f.ddg[i] > 0 ? ddpos : ddneg;
  }
  return f;
}

// What the error needs of one image: its CSF-filtered colour as Hunt-adjusted
// Lab and its edge and point strengths. Computed one image at a time through
// one set of scratch planes.
struct Perceived {
  Plane l, a, b, edge, point;
};

struct Scratch {
  Plane y, cx, cz, t, u, v, w;
};

Perceived perceive(const Srgb8Image& img, const SpatialFilters& sf, const FeatureFilters& ff, Scratch& s) {
  const uint32_t w = img.width, h = img.height;
  const size_t n = size_t(w) * h;
  std::array<double, 256> lut{};
  for (int c = 0; c < 256; ++c) lut[size_t(c)] = srgbDecode(c / 255.0);
  s.y.resize(n);
  s.cx.resize(n);
  s.cz.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Vec3 v = space().ycxcz({lut[img.rgb[3 * i]], lut[img.rgb[3 * i + 1]], lut[img.rgb[3 * i + 2]]});
    s.y[i] = v[0];
    s.cx[i] = v[1];
    s.cz[i] = v[2];
  }
  Perceived p;
  // Colour: each channel through its CSF (Cz: the sum of two separable terms).
  convolveX(s.y, s.t, w, h, sf.y);
  convolveY(s.t, p.l, w, h, sf.y);
  convolveX(s.cx, s.t, w, h, sf.cx);
  convolveY(s.t, p.a, w, h, sf.cx);
  convolveX(s.cz, s.t, w, h, sf.cz1);
  convolveY(s.t, p.b, w, h, sf.cz1);
  convolveX(s.cz, s.t, w, h, sf.cz2);
  convolveY(s.t, s.u, w, h, sf.cz2);
  for (size_t i = 0; i < n; ++i) {
    // Back to linear RGB, clamped to [0,1], then Hunt-adjusted Lab (in place).
    Vec3 rgb = space().linearFromYcxcz({p.l[i], p.a[i], p.b[i] + s.u[i]});
    for (double& c : rgb) c = std::clamp(c, 0.0, 1.0);
    const Vec3 lab = space().huntLab(rgb);
    p.l[i] = lab[0];
    p.a[i] = lab[1];
    p.b[i] = lab[2];
  }
  // Features of the unfiltered achromatic channel, normalised to Y / Wy in [0,1].
  for (size_t i = 0; i < n; ++i) s.y[i] = (s.y[i] + 16.0) / 116.0;
  convolveX(s.y, s.t, w, h, ff.dg);
  convolveY(s.t, s.u, w, h, ff.g);     // dx
  convolveX(s.y, s.t, w, h, ff.g);
  convolveY(s.t, s.v, w, h, ff.dg);    // dy
  convolveY(s.t, s.w, w, h, ff.ddg);   // ddy
  p.edge.resize(n);
  for (size_t i = 0; i < n; ++i) p.edge[i] = std::sqrt(s.u[i] * s.u[i] + s.v[i] * s.v[i]);  // small: no overflow
  convolveX(s.y, s.t, w, h, ff.ddg);
  convolveY(s.t, s.u, w, h, ff.g);     // ddx
  p.point.resize(n);
  for (size_t i = 0; i < n; ++i) p.point[i] = std::sqrt(s.u[i] * s.u[i] + s.w[i] * s.w[i]);
  return p;
}

}  // namespace

Srgb8Image toSrgb8Image(const Image& img) {
  Srgb8Image out;
  out.width = img.width;
  out.height = img.height;
  out.rgb.resize(size_t(img.width) * img.height * 3);
  for (uint32_t y = 0; y < img.height; ++y) {
    uint8_t* row = out.rgb.data() + size_t(img.height - 1 - y) * img.width * 3;  // Image rows are bottom first
    for (uint32_t x = 0; x < img.width; ++x) {
      const Rgb& p = img.pixels[img.index(x, y)];
      row[3 * x] = toSrgb8(p.r);
      row[3 * x + 1] = toSrgb8(p.g);
      row[3 * x + 2] = toSrgb8(p.b);
    }
  }
  return out;
}

FlipMap ldrFlip(const Srgb8Image& reference, const Srgb8Image& test, double ppd) {
  if (!(ppd > 0.0) || !std::isfinite(ppd))
    throw std::invalid_argument(fmt::format("FLIP: pixels per degree must be a positive number, got {}", ppd));
  if (reference.width != test.width || reference.height != test.height)
    throw std::invalid_argument(fmt::format("FLIP: size mismatch {}x{} vs reference {}x{}", test.width, test.height,
                                            reference.width, reference.height));
  const uint32_t w = reference.width, h = reference.height;
  if (w == 0 || h == 0) throw std::invalid_argument("FLIP: empty image");
  const size_t n = size_t(w) * h;
  if (reference.rgb.size() != 3 * n || test.rgb.size() != 3 * n)
    throw std::invalid_argument("FLIP: an image holds fewer or more bytes than its size needs");

  const SpatialFilters sf = spatialFilters(ppd);
  const FeatureFilters ff = featureFilters(ppd);
  Scratch scratch;
  const Perceived rp = perceive(reference, sf, ff, scratch);
  const Perceived tp = perceive(test, sf, ff, scratch);

  // The largest colour difference: green against blue (paper, Section 4.1.2).
  const double cmax = std::pow(hyab(space().huntLab({0, 1, 0}), space().huntLab({0, 0, 1})), kQc);
  const double pccmax = kPc * cmax;

  FlipMap map;
  map.width = w;
  map.height = h;
  map.error.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const double d = std::pow(hyab({rp.l[i], rp.a[i], rp.b[i]}, {tp.l[i], tp.a[i], tp.b[i]}), kQc);
    // Errors up to pc cmax map linearly to [0, pt], the rest to (pt, 1].
    double colour = d < pccmax ? d * kPt / pccmax : kPt + (d - pccmax) / (cmax - pccmax) * (1.0 - kPt);
    colour = std::clamp(colour, 0.0, 1.0);
    const double edge = std::abs(rp.edge[i] - tp.edge[i]), point = std::abs(rp.point[i] - tp.point[i]);
    static_assert(kQf == 0.5);  // the square root below
    const double feature = std::clamp(std::sqrt(std::max(edge, point) / std::sqrt(2.0)), 0.0, 1.0);
    // Features raise the colour error towards 1; 0^0 (no colour error, full
    // feature error) is 1 by the formula, and the paper keeps it.
    map.error[i] = float(std::clamp(std::pow(colour, 1.0 - feature), 0.0, 1.0));
  }
  map.stats = flipStats(map.error);
  return map;
}

FlipStats flipStats(const std::vector<float>& error) {
  FlipStats s;
  if (error.empty()) return s;
  std::vector<float> sorted(error);
  std::sort(sorted.begin(), sorted.end());
  double sum = 0;
  for (float e : sorted) sum += e;
  s.mean = sum / double(sorted.size());
  s.max = sorted.back();
  if (sum <= 0.0) return s;
  auto weighted = [&](double q) {
    double run = 0;
    for (float e : sorted) {
      run += e;
      if (run > q * sum) return double(e);
    }
    return double(sorted.back());
  };
  s.weighted_q1 = weighted(0.25);
  s.weighted_median = weighted(0.5);
  s.weighted_q3 = weighted(0.75);
  return s;
}

}  // namespace oit::model
