#include "model/StressSuite.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <stdexcept>
#include <utility>

#include "model/MemorySource.hpp"

namespace oit::model::stress {

namespace {

constexpr float kDenormMin = std::numeric_limits<float>::denorm_min();
constexpr float kFltMin = std::numeric_limits<float>::min();
// The six alphas of the issue. 1 - 1e-7 is the float nearest to it (1 - 2^-23).
const std::array<float, 6> kAlphaSet{0.0f, 1e-7f, 1.0f / 255.0f, 0.5f, 1.0f - 1e-7f, 1.0f};

// Every case: a 2x2 frame with one opaque and one transparent draw and the
// camera planes; pixel (1,0) never receives a fragment, so every run also
// checks that an empty pixel resolves to the clear colour without 0/0.
class Builder {
 public:
  Builder(std::string name, std::string what, Rgb clear = {0.2f, 0.4f, 0.6f}) {
    c_.name = std::move(name);
    c_.what = std::move(what);
    c_.clear = clear;
    c_.header.width = 2;
    c_.header.height = 2;
    c_.header.camera = CameraPlanes{kNear, kFar};
    c_.header.draws = {{kOpaqueDraw, DrawClass::Opaque, "wall"}, {kGlassDraw, DrawClass::Transparent, "glass"}};
  }
  // Each fragment gets its own primitive id, so the random hashes of slab /
  // stochastic differ per fragment.
  void glass(uint16_t x, uint16_t y, float z, Rgb c, float a) {
    c_.fragments.push_back(Fragment{x, y, z, c.r, c.g, c.b, a, prim_++, kGlassDraw});
  }
  void opaque(uint16_t x, uint16_t y, float z, Rgb c) {
    c_.fragments.push_back(Fragment{x, y, z, c.r, c.g, c.b, 1.0f, prim_++, kOpaqueDraw});
  }
  void shuffle(SplitMix64& rng) {
    auto& f = c_.fragments;
    for (size_t i = f.size(); i > 1; --i) std::swap(f[i - 1], f[rng.below(uint32_t(i))]);
  }
  StressCase take() { return std::move(c_); }

 private:
  StressCase c_;
  uint32_t prim_ = 0;
};

Rgb randomColour(SplitMix64& rng) { return {rng.open01(), rng.open01(), rng.open01()}; }

// n fragments at pixel (x, y), random depth in (0,1), alpha from `alpha`.
template <class AlphaFn, class ColourFn>
void randomFragments(Builder& b, SplitMix64& rng, uint16_t x, uint16_t y, unsigned n, AlphaFn alpha, ColourFn colour) {
  for (unsigned i = 0; i < n; ++i) {
    const float z = rng.open01();
    const Rgb c = colour();
    b.glass(x, y, z, c, alpha());
  }
}

// Depth 4096 on pixel (0,0) and 16 on (1,1), random depths, shuffled.
template <class AlphaFn>
StressCase depthCase(const char* name, const char* what, uint64_t seed, AlphaFn alpha, Rgb clear = {0.2f, 0.4f, 0.6f}) {
  Builder b(name, what, clear);
  SplitMix64 rng(seed);
  auto colour = [&] { return randomColour(rng); };
  randomFragments(b, rng, 0, 0, 4096, [&] { return alpha(rng); }, colour);
  randomFragments(b, rng, 1, 1, 16, [&] { return alpha(rng); }, colour);
  b.shuffle(rng);
  return b.take();
}

// Constant-colour stacks: the reference is c + (bg - c) T exactly, which the
// tests use for closed-form checks.
StressCase constantColourCase(const char* name, const char* what, float a, Rgb c, Rgb bg, uint64_t seed) {
  Builder b(name, what, bg);
  SplitMix64 rng(seed);
  for (unsigned i = 0; i < 4096; ++i) b.glass(0, 0, rng.open01(), c, a);
  for (unsigned i = 0; i < 16; ++i) b.glass(1, 1, rng.open01(), randomColour(rng), a);
  b.shuffle(rng);
  return b.take();
}

StressCase mergeChain(const char* name, const char* what, unsigned n, float a, uint64_t seed) {
  // (0,0) front to back (every insert past k merges the two furthest rows),
  // (1,1) back to front (every insert lands in front, the back rows merge).
  // Both orders are exact for MLAB at any k in exact arithmetic, so the
  // error is the storage format's alone.
  Builder b(name, what);
  SplitMix64 rng(seed);
  for (unsigned i = 0; i < n; ++i) b.glass(0, 0, float(i + 1) / float(n + 1), randomColour(rng), a);
  for (unsigned i = 0; i < n; ++i) b.glass(1, 1, float(n - i) / float(n + 1), randomColour(rng), a);
  return b.take();
}

struct CaseDef {
  const char* name;
  StressCase (*make)();
};

const std::vector<CaseDef>& caseDefs() {
  static const std::vector<CaseDef> defs = {
      {"depth4096_alpha0.5_random",
       [] {
         return depthCase("depth4096_alpha0.5_random", "4096 fragments on one pixel, alpha 0.5, random depths and order",
                          11, [](SplitMix64&) { return 0.5f; });
       }},
      {"depth4096_alpha_uniform",
       [] {
         return depthCase("depth4096_alpha_uniform", "4096 fragments on one pixel, alpha uniform in (0,1)", 12,
                          [](SplitMix64& r) { return r.open01(); });
       }},
      {"depth4096_alpha_mixed",
       [] {
         return depthCase("depth4096_alpha_mixed",
                          "4096 fragments, alpha drawn from {0, 1e-7, 1/255, 0.5, 1-1e-7, 1}", 13,
                          [](SplitMix64& r) { return kAlphaSet[r.below(6)]; });
       }},
      {"alpha_0_x4096",
       [] {
         return depthCase("alpha_0_x4096", "4096 fragments of alpha 0: the image must be the background", 14,
                          [](SplitMix64&) { return 0.0f; }, {0.25f, 0.5f, 0.75f});
       }},
      {"alpha_1e-7_x4096",
       [] {
         return constantColourCase("alpha_1e-7_x4096", "4096 fragments of alpha 1e-7, one colour: T = (1-1e-7)^4096",
                                   1e-7f, {0.9f, 0.6f, 0.1f}, {0.1f, 0.4f, 0.9f}, 15);
       }},
      {"alpha_1div255_x4096",
       [] {
         return constantColourCase("alpha_1div255_x4096",
                                   "4096 fragments of alpha 1/255 (one unorm8 step), one colour: T = (254/255)^4096",
                                   1.0f / 255.0f, {0.9f, 0.6f, 0.1f}, {0.1f, 0.4f, 0.9f}, 16);
       }},
      {"alpha_1-1e-7_x4096",
       [] {
         return depthCase("alpha_1-1e-7_x4096", "4096 fragments of alpha 1-1e-7: transmittance underflows", 17,
                          [](SplitMix64&) { return 1.0f - 1e-7f; });
       }},
      {"alpha_1_x4096",
       [] {
         return depthCase("alpha_1_x4096", "4096 fragments of alpha 1: the image is the nearest fragment's colour",
                          18, [](SplitMix64&) { return 1.0f; });
       }},
      {"alpha_1_then_more",
       [] {
         // (0,0): the alpha-1 front fragment is submitted first, (1,1): last.
         // 4095 random fragments behind it (z > 0.3) either way.
         Builder b("alpha_1_then_more",
                   "alpha-1 front fragment (z 0.25) submitted first (0,0) / last (1,1), 4095 behind it");
         SplitMix64 rng(19);
         const Rgb front{0.8f, 0.3f, 0.1f};
         b.glass(0, 0, 0.25f, front, 1.0f);
         for (unsigned i = 0; i < 4095; ++i) b.glass(0, 0, 0.3f + 0.65f * rng.open01(), randomColour(rng), rng.open01());
         for (unsigned i = 0; i < 4095; ++i) b.glass(1, 1, 0.3f + 0.65f * rng.open01(), randomColour(rng), rng.open01());
         b.glass(1, 1, 0.25f, front, 1.0f);
         return b.take();
       }},
      {"equal_depths_512",
       [] {
         // Tie rule: a later-submitted fragment is in front (painter's order).
         Builder b("equal_depths_512", "512 fragments at one depth (0,0); 3 at one depth (1,1); 64 on two depths (0,1)");
         SplitMix64 rng(20);
         for (unsigned i = 0; i < 512; ++i) b.glass(0, 0, 0.5f, randomColour(rng), rng.open01());
         b.glass(1, 1, 0.5f, {1, 0, 0}, 0.5f);
         b.glass(1, 1, 0.5f, {0, 1, 0}, 0.5f);
         b.glass(1, 1, 0.5f, {0, 0, 1}, 0.5f);
         for (unsigned i = 0; i < 64; ++i) b.glass(0, 1, (i % 2) ? 0.25f : 0.75f, randomColour(rng), rng.open01());
         return b.take();
       }},
      {"depth_0_1_denormal",
       [] {
         // Depth 0, -0 (ties with 0), denormals, FLT_MIN, 1 - 2^-24 and 1
         // (no opaque fragment, so z = 1 is not culled).
         Builder b("depth_0_1_denormal",
                   "depths 0, -0, denormals, FLT_MIN, 0.5, 1-2^-24, 1: 9 fragments scrambled (0,0), 1024 (1,1)");
         const std::array<float, 9> depths{0.0f, -0.0f, kDenormMin, 2 * kDenormMin,
                                           std::nextafter(kFltMin, 0.0f), kFltMin, 0.5f,
                                           std::nextafter(1.0f, 0.0f), 1.0f};
         const std::array<unsigned, 9> order{6, 2, 8, 0, 5, 3, 1, 7, 4};
         SplitMix64 rng(21);
         for (unsigned i : order) b.glass(0, 0, depths[i], randomColour(rng), 0.5f);
         for (unsigned i = 0; i < 1024; ++i) b.glass(1, 1, depths[rng.below(9)], randomColour(rng), rng.open01());
         return b.take();
       }},
      {"merge_chain_8bit_1024",
       [] {
         return mergeChain("merge_chain_8bit_1024",
                           "1024 fragments of alpha 0.02, sorted front to back (0,0) / back to front (1,1)", 1024, 0.02f,
                           22);
       }},
      {"merge_chain_fp16_4096",
       [] {
         return mergeChain("merge_chain_fp16_4096",
                           "4096 fragments of alpha 1e-3, sorted front to back (0,0) / back to front (1,1)", 4096, 1e-3f,
                           23);
       }},
      {"wboit_weight_max",
       [] {
         // z = 0 gives the 3e3 weight cap of every wboit equation. (0,0): 64
         // alpha-1 fragments of one colour (sum w a = 192000 > 5e4 clamp and
         // > fp16 65504); (1,1): 16 of them (48000, below both); (0,1): 64 of
         // alpha 0.5 and random colours (96000).
         Builder b("wboit_weight_max", "depth 0 (weight cap 3e3): 64 / 16 alpha-1 and 64 alpha-0.5 fragments",
                   {0.0f, 0.0f, 0.0f});
         SplitMix64 rng(24);
         const Rgb c{1.0f, 0.5f, 0.25f};
         for (unsigned i = 0; i < 64; ++i) b.glass(0, 0, 0.0f, c, 1.0f);
         for (unsigned i = 0; i < 16; ++i) b.glass(1, 1, 0.0f, c, 1.0f);
         for (unsigned i = 0; i < 64; ++i) b.glass(0, 1, 0.0f, randomColour(rng), 0.5f);
         return b.take();
       }},
      {"wboit_weight_min",
       [] {
         // z = 1 gives the smallest weights (eq. 10: 1e-2 a); with alpha 1e-7
         // the sum of w a (~4e-6) sits under the 1e-4 denominator clamp and
         // below fp16's smallest subnormal.
         Builder b("wboit_weight_min", "depth 1 (weight floor): 4096 alpha-1e-7 (0,0), 4096 alpha-1/255 (1,1)");
         SplitMix64 rng(25);
         for (unsigned i = 0; i < 4096; ++i) b.glass(0, 0, 1.0f, randomColour(rng), 1e-7f);
         for (unsigned i = 0; i < 4096; ++i) b.glass(1, 1, 1.0f, randomColour(rng), 1.0f / 255.0f);
         return b.take();
       }},
      {"opaque_in_front",
       [] {
         // (0,0): opaque at 0.3 submitted mid-stream, 2048 transparent around
         // it plus 8 exactly at 0.3 (culled: at the opaque depth). (1,1):
         // opaque at depth 0 submitted last culls all 256 transparent. (0,1):
         // two opaque at equal depth (the first wins), 64 transparent.
         Builder b("opaque_in_front", "opaque surfaces at 0.3 / 0 / equal depths with transparent fragments around them");
         SplitMix64 rng(26);
         for (unsigned i = 0; i < 2048; ++i) {
           if (i == 1000) b.opaque(0, 0, 0.3f, {0.1f, 0.7f, 0.2f});
           if (i % 256 == 0) b.glass(0, 0, 0.3f, randomColour(rng), rng.open01());
           b.glass(0, 0, rng.open01(), randomColour(rng), rng.open01());
         }
         for (unsigned i = 0; i < 256; ++i) b.glass(1, 1, rng.open01(), randomColour(rng), rng.open01());
         b.opaque(1, 1, 0.0f, {0.9f, 0.8f, 0.7f});
         b.opaque(0, 1, 0.6f, {0.5f, 0.5f, 0.0f});
         for (unsigned i = 0; i < 64; ++i) b.glass(0, 1, rng.open01(), randomColour(rng), rng.open01());
         b.opaque(0, 1, 0.6f, {0.0f, 0.5f, 0.5f});
         return b.take();
       }},
      {"tail_count_70000",
       [] {
         // 70000 > 65535: the packed hybrid tail's 16-bit count saturates and
         // its fp16 alpha sum stops growing; wavg's count grows past 2^16.
         Builder b("tail_count_70000", "70000 fragments of alpha in (0,0.01) on one pixel: 16-bit counters saturate");
         SplitMix64 rng(27);
         for (unsigned i = 0; i < 70000; ++i) b.glass(0, 0, rng.open01(), randomColour(rng), 0.01f * rng.open01());
         return b.take();
       }},
      {"white_on_white",
       [] {
         // (0,0): colour 1 over a white background, exact answer 1; (1,1):
         // colour 0 over it, exact answer T. Rounding must not leave [0,1].
         Builder b("white_on_white", "colour 1 over background 1 (exact 1), colour 0 (1,1), alphas from the issue's set",
                   {1.0f, 1.0f, 1.0f});
         SplitMix64 rng(28);
         for (unsigned i = 0; i < 1024; ++i) b.glass(0, 0, rng.open01(), {1, 1, 1}, kAlphaSet[rng.below(6)]);
         for (unsigned i = 0; i < 1024; ++i) b.glass(1, 1, rng.open01(), {0, 0, 0}, kAlphaSet[rng.below(6)]);
         return b.take();
       }},
      {"alpha_denormal_x4096",
       [] {
         return depthCase("alpha_denormal_x4096", "4096 fragments of denormal / FLT_MIN alpha (a > 0 yet a c underflows)",
                          29, [](SplitMix64& r) {
                            const std::array<float, 3> a{kDenormMin, kFltMin / 2, kFltMin};
                            return a[r.below(3)];
                          });
       }},
  };
  return defs;
}

const char* kFormatNames[] = {"fp32", "rgba8t8z32", "fp16"};
constexpr std::array<StorageFormat, 3> kFormats{StorageFormat::Fp32, StorageFormat::Rgba8T8Z32, StorageFormat::Fp16};

// Everything but the makeAlgorithm rejection is recorded as an Error row.
std::unique_ptr<OitAlgorithm> tryMake(const std::string& algo, const AlgorithmParams& p, std::string& why) {
  try {
    return makeAlgorithm(algo, p);
  } catch (const std::invalid_argument& e) {
    why = e.what();
    return nullptr;
  }
}

void evaluate(const StressCase& c, const Image& ref, const std::vector<char>& covered, OitAlgorithm& a, StressRow& row) {
  row.bytes_per_pixel = a.bytesPerPixel();
  RenderResult r;
  try {
    r = renderCase(c, a);
  } catch (const std::exception& e) {
    row.status = RowStatus::Error;
    row.note = std::string("render threw: ") + e.what();
    return;
  }
  const RenderCounts& n = r.counts;
  row.stored = n.stored;
  row.merged = n.merged;
  row.discarded = n.discarded;
  row.culled = n.culled;
  row.balanced = n.balanced();
  for (const auto& pass : n.pass_outcomes)
    if (pass[0] + pass[1] + pass[2] + n.opaque + n.culled != n.fragments_in) row.balanced = false;

  double maxErr = 0, sq = 0;
  uint64_t samples = 0;
  bool haveFinite = false;
  std::string worst;
  double worstDist = 0;
  for (uint32_t y = 0; y < r.image.height; ++y)
    for (uint32_t x = 0; x < r.image.width; ++x) {
      const size_t i = r.image.index(x, y);
      const Rgb& p = r.image.pixels[i];
      const Rgb& q = ref.pixels[i];
      const float v[3] = {p.r, p.g, p.b}, w[3] = {q.r, q.g, q.b};
      for (int ch = 0; ch < 3; ++ch) {
        if (!std::isfinite(v[ch])) {
          if (row.non_finite++ == 0) worst = fmt::format("{} at ({},{}) ch {}", v[ch], x, y, ch);
          worstDist = std::numeric_limits<double>::infinity();
          continue;
        }
        row.min_value = haveFinite ? std::min(row.min_value, double(v[ch])) : double(v[ch]);
        row.max_value = haveFinite ? std::max(row.max_value, double(v[ch])) : double(v[ch]);
        haveFinite = true;
        if (!(v[ch] >= 0.0f && v[ch] <= 1.0f)) {
          ++row.out_of_range;
          const double dist = v[ch] < 0.0f ? -double(v[ch]) : double(v[ch]) - 1.0;
          if (dist > worstDist) {
            worstDist = dist;
            worst = fmt::format("{:.9g} at ({},{}) ch {}", v[ch], x, y, ch);
          }
        }
        const double e = std::abs(double(v[ch]) - double(w[ch]));
        maxErr = std::max(maxErr, e);
        if (covered[i]) {
          sq += e * e;
          ++samples;
        }
      }
    }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  row.max_abs_error = row.non_finite ? nan : maxErr;
  row.rmse = row.non_finite ? nan : (samples ? std::sqrt(sq / double(samples)) : 0.0);

  std::string why;
  if (row.non_finite) why += fmt::format("{} non-finite channel(s), first {}; ", row.non_finite, worst);
  else if (row.out_of_range) why += fmt::format("{} channel(s) outside [0,1], worst {}; ", row.out_of_range, worst);
  if (!row.balanced)
    why += fmt::format("outcomes unbalanced (in {}, opaque {}, culled {}, stored {}, merged {}, discarded {}); ",
                       n.fragments_in, n.opaque, n.culled, n.stored, n.merged, n.discarded);
  if (!why.empty()) {
    why.resize(why.size() - 2);
    row.status = RowStatus::Violation;
    row.note = why;
  }
}

std::string num(double v) {
  if (std::isnan(v)) return "nan";
  if (v == 0) return "0";
  return fmt::format("{:.3g}", v);
}
std::string kText(unsigned k) { return k ? std::to_string(k) : "-"; }
std::string mdCell(std::string s) {
  std::replace(s.begin(), s.end(), '|', '/');
  std::replace(s.begin(), s.end(), '\n', ' ');
  return s;
}
std::string csvCell(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string q = "\"";
  for (char ch : s) q += ch == '"' ? std::string("\"\"") : std::string(1, ch);
  return q + "\"";
}
std::string algoLabel(const StressRow& r) { return r.variant.empty() ? r.algorithm : r.algorithm + " " + r.variant; }

void writeAtomically(const std::filesystem::path& path, const std::string& content) {
  const std::filesystem::path tmp = path.string() + fmt::format(".tmp.{}", ::getpid());
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(fmt::format("{}: cannot create temporary file {}", path.string(), tmp.string()));
    out.write(content.data(), std::streamsize(content.size()));
    out.flush();
    if (!out) {
      out.close();
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw std::runtime_error(fmt::format("{}: write failed", path.string()));
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignore;
    std::filesystem::remove(tmp, ignore);
    throw std::runtime_error(fmt::format("{}: cannot rename {} over it: {}", path.string(), tmp.string(), ec.message()));
  }
}

}  // namespace

const char* toString(RowStatus s) {
  switch (s) {
    case RowStatus::Ok: return "ok";
    case RowStatus::NotApplicable: return "n/a";
    case RowStatus::Violation: return "VIOLATION";
    case RowStatus::Error: return "ERROR";
  }
  return "?";
}

const std::vector<std::string>& caseNames() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> v;
    for (const CaseDef& d : caseDefs()) v.emplace_back(d.name);
    return v;
  }();
  return names;
}

StressCase makeCase(std::string_view name) {
  for (const CaseDef& d : caseDefs())
    if (name == d.name) return d.make();
  std::string valid;
  for (const CaseDef& d : caseDefs()) valid += (valid.empty() ? "" : ", ") + std::string(d.name);
  throw std::invalid_argument("unknown stress case '" + std::string(name) + "' (valid: " + valid + ")");
}

RenderResult renderCase(const StressCase& c, OitAlgorithm& algo) {
  MemorySource src(c.header, c.fragments, 1000);
  RenderOptions o;
  o.clear_colour = c.clear;
  return FunctionalRenderer(o).render(src, algo);
}

std::vector<StressConfig> stressConfigs() {
  std::vector<StressConfig> out;
  for (const AlgorithmInfo& info : algorithmNames()) {
    const std::string name(info.name);
    AlgorithmParams p;
    if (name == "wboit") {
      for (int eq : {7, 8, 9, 10}) {
        p.weight = eq;
        // eq. 7-9 read the planes from the trace header; give them here too.
        p.camera = CameraPlanes{kNear, kFar};
        out.push_back({name, fmt::format("eq{}", eq), p});
      }
    } else if (name == "slab") {
      p.bits = 8;
      out.push_back({name, "b8", p});
      p.coverage_mask = true;
      p.bits = 32;
      out.push_back({name, "mask-b32", p});
    } else if (name == "stochastic") {
      for (unsigned samples : {8u, 64u}) {
        p.samples = samples;
        out.push_back({name, fmt::format("S{}", samples), p});
      }
    } else {
      out.push_back({name, "", p});
    }
  }
  return out;
}

std::vector<StressRow> runStress(const StressOptions& opt) {
  std::vector<StressConfig> configs;
  const std::vector<StressConfig> all = stressConfigs();
  if (opt.algorithms.empty()) {
    configs = all;
  } else {
    for (const std::string& a : opt.algorithms) {
      bool found = false;
      for (const StressConfig& c : all)
        if (c.algorithm == a) {
          configs.push_back(c);
          found = true;
        }
      if (!found) makeAlgorithm(a, AlgorithmParams{});  // throws naming the valid algorithms
      if (!found) throw std::invalid_argument("unknown OIT algorithm '" + a + "'");
    }
  }
  const std::vector<std::string>& cases = opt.cases.empty() ? caseNames() : opt.cases;
  for (const std::string& name : cases) (void)makeCase(name);  // validate every name first

  std::vector<StressRow> rows;
  for (const std::string& name : cases) {
    if (opt.on_case) opt.on_case(name);
    const StressCase c = makeCase(name);
    auto refAlgo = makeAlgorithm("abuffer", AlgorithmParams{});
    const Image ref = renderCase(c, *refAlgo).image;
    std::vector<char> covered(size_t(c.header.width) * c.header.height, 0);
    for (const Fragment& f : c.fragments) covered[size_t(f.y) * c.header.width + f.x] = 1;

    for (const StressConfig& cfg : configs)
      for (size_t fi = 0; fi < kFormats.size(); ++fi) {
        StressRow base;
        base.case_name = c.name;
        base.algorithm = cfg.algorithm;
        base.variant = cfg.variant;
        base.format = kFormatNames[fi];
        base.fragments = c.fragments.size();
        AlgorithmParams p = cfg.params;
        p.format = kFormats[fi];

        // Does the state depend on k? Probe two sizes: if the layout is the
        // same, the algorithm has no k and runs once (k shown as "-").
        std::string why2, why3;
        AlgorithmParams p2 = p, p3 = p;
        p2.layers = 2;
        p3.layers = 3;
        auto a2 = tryMake(cfg.algorithm, p2, why2);
        auto a3 = tryMake(cfg.algorithm, p3, why3);
        if (!a2 && !a3) {
          StressRow r = base;
          r.status = RowStatus::NotApplicable;
          r.note = why2;
          rows.push_back(r);
          continue;
        }
        const bool usesK = !(a2 && a3 && a2->stateWords() == a3->stateWords());
        std::vector<unsigned> ks = usesK ? opt.layers : std::vector<unsigned>{0};
        for (unsigned k : ks) {
          StressRow r = base;
          r.k = k;
          AlgorithmParams pk = p;
          if (k) pk.layers = k;
          std::string why;
          auto a = tryMake(cfg.algorithm, pk, why);
          if (!a) {
            r.status = RowStatus::NotApplicable;
            r.note = why;
          } else {
            evaluate(c, ref, covered, *a, r);
          }
          rows.push_back(std::move(r));
        }
      }
  }
  return rows;
}

std::string toCsv(const std::vector<StressRow>& rows) {
  std::string s =
      "case,algorithm,variant,format,k,status,fragments,max_abs_error,rmse,min,max,non_finite,out_of_range,"
      "balanced,stored,merged,discarded,culled,bytes_per_pixel,note\n";
  auto g = [](double v) { return std::isnan(v) ? std::string("nan") : fmt::format("{:.9g}", v); };
  for (const StressRow& r : rows) {
    const bool ran = r.status == RowStatus::Ok || r.status == RowStatus::Violation;
    s += fmt::format("{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", csvCell(r.case_name),
                     csvCell(r.algorithm), csvCell(r.variant), r.format, kText(r.k), toString(r.status), r.fragments,
                     ran ? g(r.max_abs_error) : "", ran ? g(r.rmse) : "", ran ? g(r.min_value) : "",
                     ran ? g(r.max_value) : "", r.non_finite, r.out_of_range, r.balanced ? 1 : 0, r.stored, r.merged,
                     r.discarded, r.culled, r.bytes_per_pixel, csvCell(r.note));
  }
  return s;
}

std::string toMarkdown(const std::vector<StressRow>& rows, const std::string& command) {
  size_t ran = 0, na = 0, bad = 0;
  std::vector<std::string> caseOrder, algoOrder;
  auto addUnique = [](std::vector<std::string>& v, const std::string& s) {
    if (std::find(v.begin(), v.end(), s) == v.end()) v.push_back(s);
  };
  for (const StressRow& r : rows) {
    addUnique(caseOrder, r.case_name);
    addUnique(algoOrder, r.algorithm);
    if (r.status == RowStatus::NotApplicable) ++na;
    else ++ran;
    if (r.violation()) ++bad;
  }
  std::string s = "# oitsim numerical stress table\n\n";
  s += fmt::format("Produced by `{}`. Column meanings: reports/stress/README.md.\n\n", command);
  s += fmt::format("{} cases x {} algorithms: {} configurations run, {} n/a (format or k rejected by the algorithm), "
                   "**{} violations** (NaN/Inf, output outside [0,1], unbalanced outcome counts, or a render error).\n\n",
                   caseOrder.size(), algoOrder.size(), ran, na, bad);

  s += "## Cases\n\n| case | fragments | what it stresses |\n|---|---:|---|\n";
  for (const std::string& cn : caseOrder) {
    const StressCase c = makeCase(cn);
    s += fmt::format("| {} | {} | {} |\n", cn, c.fragments.size(), mdCell(c.what));
  }

  s += "\n## Violations\n\n";
  if (!bad) {
    s += "None.\n";
  } else {
    s += "| case | algorithm | format | k | status | min | max | finding |\n|---|---|---|---|---|---:|---:|---|\n";
    for (const StressRow& r : rows)
      if (r.violation())
        s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} |\n", r.case_name, algoLabel(r), r.format, kText(r.k),
                         toString(r.status), num(r.min_value), num(r.max_value), mdCell(r.note));
  }

  // Worst max-abs error per case and algorithm over formats, k and variants.
  s += "\n## Worst max abs error vs abuffer (over formats, k and variants; ! = violation in that cell)\n\n| case |";
  for (const std::string& a : algoOrder) s += " " + a + " |";
  s += "\n|---|";
  for (size_t i = 0; i < algoOrder.size(); ++i) s += "---:|";
  s += "\n";
  for (const std::string& cn : caseOrder) {
    s += "| " + cn + " |";
    for (const std::string& a : algoOrder) {
      double worst = -1;
      bool v = false, nan = false;
      for (const StressRow& r : rows)
        if (r.case_name == cn && r.algorithm == a && r.status != RowStatus::NotApplicable) {
          v |= r.violation();
          if (std::isnan(r.max_abs_error)) nan = true;
          else if (r.status != RowStatus::Error) worst = std::max(worst, r.max_abs_error);
        }
      s += " " + (nan ? std::string("nan") : worst < 0 ? std::string("n/a") : num(worst)) + (v ? " !" : "") + " |";
    }
    s += "\n";
  }

  s += "\n## All configurations\n\n"
       "| case | algorithm | format | k | status | max abs err | RMSE | min | max | stored | merged | discarded | "
       "culled | B/px | note |\n|---|---|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n";
  for (const StressRow& r : rows) {
    if (r.status == RowStatus::NotApplicable) {
      s += fmt::format("| {} | {} | {} | {} | n/a | | | | | | | | | | {} |\n", r.case_name, algoLabel(r), r.format,
                       kText(r.k), mdCell(r.note));
      continue;
    }
    s += fmt::format("| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n", r.case_name,
                     algoLabel(r), r.format, kText(r.k), toString(r.status), num(r.max_abs_error), num(r.rmse),
                     num(r.min_value), num(r.max_value), r.stored, r.merged, r.discarded, r.culled, r.bytes_per_pixel,
                     mdCell(r.note));
  }
  return s;
}

void writeStressTables(const std::vector<StressRow>& rows, const std::string& dir, const std::string& command) {
  const std::filesystem::path d(dir);
  std::error_code ec;
  std::filesystem::create_directories(d, ec);
  if (ec) throw std::runtime_error(fmt::format("{}: cannot create directory: {}", dir, ec.message()));
  writeAtomically(d / "stress-table.md", toMarkdown(rows, command));
  writeAtomically(d / "stress-table.csv", toCsv(rows));
}

}  // namespace oit::model::stress
