// Numerical stress suite (model/StressSuite.hpp): every algorithm x format x k
// must stay finite, in [0,1] and balanced on every stress case; plus the
// closed-form values the theory gives for some of the cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <numeric>
#include <set>
#include <sstream>
#include <unistd.h>

#include "model/StressSuite.hpp"

namespace oit::model::stress {
namespace {

constexpr StorageFormat kAllFormats[] = {StorageFormat::Fp32, StorageFormat::Rgba8T8Z32, StorageFormat::Fp16};

std::string who(const StressRow& r) {
  return r.case_name + ": " + r.algorithm + (r.variant.empty() ? "" : " " + r.variant) + ", format " + r.format +
         ", k " + (r.k ? std::to_string(r.k) : std::string("-"));
}

std::unique_ptr<OitAlgorithm> make(const std::string& algo, StorageFormat f, unsigned k, AlgorithmParams p = {}) {
  p.format = f;
  p.layers = k;
  return makeAlgorithm(algo, p);
}

Image render(const StressCase& c, const std::string& algo, StorageFormat f = StorageFormat::Fp32, unsigned k = 4,
             AlgorithmParams p = {}) {
  auto a = make(algo, f, k, p);
  return renderCase(c, *a).image;
}

// Independent reference: the transparent fragments of one pixel in front of
// its first-landed nearest opaque fragment, ordered by depth with a later
// submission in front on ties, composited in long double.
Rgb independentReference(const StressCase& c, uint16_t x, uint16_t y) {
  float oz = std::numeric_limits<float>::infinity();
  Rgb bg = c.clear;
  std::vector<std::pair<size_t, Fragment>> glass;
  for (size_t i = 0; i < c.fragments.size(); ++i) {
    const Fragment& f = c.fragments[i];
    if (f.x != x || f.y != y) continue;
    if (f.draw == kOpaqueDraw) {
      if (f.z < oz) oz = f.z, bg = {f.r, f.g, f.b};
    } else {
      glass.push_back({i, f});
    }
  }
  std::erase_if(glass, [&](const auto& g) { return !(g.second.z < oz); });
  std::sort(glass.begin(), glass.end(), [](const auto& a, const auto& b) {
    if (a.second.z != b.second.z) return a.second.z < b.second.z;
    return a.first > b.first;  // tie: later submitted in front
  });
  long double r = 0, g = 0, b = 0, T = 1;
  for (const auto& [i, f] : glass) {
    r += T * f.a * f.r;
    g += T * f.a * f.g;
    b += T * f.a * f.b;
    T *= 1.0L - f.a;
  }
  return {float(r + T * bg.r), float(g + T * bg.g), float(b + T * bg.b)};
}

void expectNear(const Rgb& got, const Rgb& want, double tol, const std::string& what) {
  EXPECT_NEAR(got.r, want.r, tol) << what << " (red)";
  EXPECT_NEAR(got.g, want.g, tol) << what << " (green)";
  EXPECT_NEAR(got.b, want.b, tol) << what << " (blue)";
}

// ---------------------------------------------------------------- per case
class StressCaseTest : public ::testing::TestWithParam<std::string> {};

// One test per stress case: every algorithm (variants included) x format x k.
TEST_P(StressCaseTest, EveryAlgorithmFiniteInRangeAndBalanced) {
  StressOptions o;
  o.cases = {GetParam()};
  const std::vector<StressRow> rows = runStress(o);
  std::set<std::string> ranFp32;
  for (const StressRow& r : rows) {
    if (r.status == RowStatus::NotApplicable) {
      // Only a format / k the algorithm rejects; fp32 is accepted by all.
      EXPECT_NE(r.format, "fp32") << who(r) << ": " << r.note;
      continue;
    }
    if (r.format == "fp32") ranFp32.insert(r.algorithm);
    EXPECT_NE(r.status, RowStatus::Error) << who(r) << ": " << r.note;
    EXPECT_EQ(r.non_finite, 0u) << who(r) << " produced NaN/Inf: " << r.note;
    EXPECT_EQ(r.out_of_range, 0u) << who(r) << " left [0,1] (min " << r.min_value << ", max " << r.max_value
                                  << "): " << r.note;
    EXPECT_TRUE(r.balanced) << who(r) << ": " << r.note;
    // The reference against itself in fp32. In rgba8t8z32 / fp16 the nodes
    // keep 8-bit / half colour and alpha (the 12- / 16-byte node), and deep
    // stacks of small alphas lose to the rounding as a real 12-byte A-buffer
    // does (merge_chain_fp16_4096 in rgba8t8z32: 0.295): range and finiteness
    // are asserted above, not the error.
    if (r.algorithm == "abuffer" && r.format == "fp32") {
      EXPECT_EQ(r.max_abs_error, 0.0) << who(r);
    }
  }
  for (const AlgorithmInfo& a : algorithmNames())
    EXPECT_TRUE(ranFp32.count(std::string(a.name))) << a.name << " never ran in fp32 on " << GetParam();
}

INSTANTIATE_TEST_SUITE_P(Cases, StressCaseTest, ::testing::ValuesIn(caseNames()),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           std::string s = i.param;
                           for (char& ch : s)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return s;
                         });

// ---------------------------------------------------------------- the suite itself
TEST(StressSuite, CasesAreDeterministicAndNamed) {
  const auto& names = caseNames();
  EXPECT_EQ(std::set<std::string>(names.begin(), names.end()).size(), names.size()) << "duplicate case names";
  EXPECT_GE(names.size(), 15u);
  for (const std::string& n : names) {
    const StressCase a = makeCase(n), b = makeCase(n);
    EXPECT_EQ(a.name, n);
    ASSERT_EQ(a.fragments.size(), b.fragments.size()) << n;
    EXPECT_EQ(0, std::memcmp(a.fragments.data(), b.fragments.data(), a.fragments.size() * sizeof(Fragment))) << n;
    ASSERT_TRUE(a.header.camera.has_value()) << n << ": wboit eq. 7-9 need camera planes";
    for (const Fragment& f : a.fragments) {
      ASSERT_LT(f.x, a.header.width) << n;
      ASSERT_LT(f.y, a.header.height) << n;
      ASSERT_NE(a.header.findDraw(f.draw), nullptr) << n;
      // Every value a valid trace may hold ([0,1]; -0 and denormals included).
      for (float v : {f.z, f.r, f.g, f.b, f.a}) ASSERT_TRUE(v >= 0.0f && v <= 1.0f) << n;
    }
  }
  // 4096 fragments on one pixel, as the issue asks.
  const StressCase d = makeCase("depth4096_alpha0.5_random");
  EXPECT_EQ(std::count_if(d.fragments.begin(), d.fragments.end(), [](const Fragment& f) { return f.x == 0 && f.y == 0; }),
            4096);
  try {
    makeCase("no_such_case");
    ADD_FAILURE() << "unknown case accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("equal_depths_512"), std::string::npos) << e.what();
  }
}

TEST(StressSuite, UnsupportedFormatsAreNotApplicableNotFailures) {
  StressOptions o;
  o.cases = {"alpha_1_x4096"};
  o.algorithms = {"wboit", "adaptive"};
  o.layers = {4};
  const auto rows = runStress(o);
  size_t na = 0;
  for (const StressRow& r : rows) {
    const bool expectNa = (r.algorithm == "wboit" && r.format == "rgba8t8z32") ||
                          (r.algorithm == "adaptive" && r.format != "fp32");
    EXPECT_EQ(r.status == RowStatus::NotApplicable, expectNa) << who(r) << ": " << r.note;
    EXPECT_FALSE(r.status == RowStatus::NotApplicable && r.violation()) << who(r);
    na += r.status == RowStatus::NotApplicable;
  }
  EXPECT_EQ(na, 4u + 2u);  // wboit: 4 weight equations x rgba8; adaptive: rgba8, fp16
  StressOptions bad;
  bad.algorithms = {"nope"};
  EXPECT_THROW(runStress(bad), std::invalid_argument);
}

TEST(StressSuite, TablesAreWrittenWholeWithEveryRow) {
  StressOptions o;
  o.cases = {"wboit_weight_max", "alpha_0_x4096"};
  o.algorithms = {"abuffer", "wboit", "mlab"};
  o.layers = {1, 4};
  const auto rows = runStress(o);
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("oitsim-stress-test-" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  writeStressTables(rows, dir.string(), "oitsim stress --test");
  std::ifstream csv(dir / "stress-table.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line.rfind("case,algorithm,variant,format,k,status,", 0), 0u) << line;
  size_t n = 0;
  while (std::getline(csv, line)) ++n;
  EXPECT_EQ(n, rows.size());
  std::stringstream md;
  md << std::ifstream(dir / "stress-table.md").rdbuf();
  EXPECT_NE(md.str().find("`oitsim stress --test`"), std::string::npos);
  const bool anyViolation = std::any_of(rows.begin(), rows.end(), [](const StressRow& r) { return r.violation(); });
  EXPECT_EQ(md.str().find("## Violations\n\nNone."), anyViolation ? std::string::npos : md.str().find("## Violations"));
  for (const auto& e : std::filesystem::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp"), std::string::npos) << "leftover " << e.path();
  std::filesystem::remove_all(dir);
}

// ---------------------------------------------------------------- the reference
// The table's errors are against abuffer: check it against an independent
// long-double composite on every pixel of every case (denormal / -0 depths,
// ties, opaque culling included).
TEST(StressReference, AbufferMatchesIndependentCompositeOnEveryCase) {
  for (const std::string& n : caseNames()) {
    const StressCase c = makeCase(n);
    const Image img = render(c, "abuffer");
    for (uint16_t y = 0; y < c.header.height; ++y)
      for (uint16_t x = 0; x < c.header.width; ++x)
        expectNear(img.at(x, y), independentReference(c, x, y), 2e-7, n + " pixel " + std::to_string(x) + "," + std::to_string(y));
  }
}

// 4096 x alpha 1e-7 of one colour c: C = c + (bg - c) T, T = (1 - 1e-7)^4096.
TEST(StressReference, Alpha1e7ClosedForm) {
  const StressCase c = makeCase("alpha_1e-7_x4096");
  const Fragment& f = c.fragments.front();
  const double T = std::pow(1.0 - double(1e-7f), 4096.0);
  ASSERT_NEAR(T, 0.99959, 1e-5);
  Image img = render(c, "abuffer");
  const Rgb p = img.at(0, 0);
  EXPECT_NEAR(p.r, f.r + (c.clear.r - f.r) * T, 1e-7);
  EXPECT_NEAR(p.g, f.g + (c.clear.g - f.g) * T, 1e-7);
  EXPECT_NEAR(p.b, f.b + (c.clear.b - f.b) * T, 1e-7);
  // In unorm8 rows 1 - 1e-7 stores as T = 1 and a c as 0: the fragments
  // vanish and the layered algorithms return the background bit-exactly.
  // (hybrid is not in this list: a fragment that overflows before it was ever
  // stored keeps its exact alpha in the fp16 tail sum, so it does count.)
  for (const char* a : {"mlab", "kbuffer"})
    for (unsigned k : {1u, 4u, 16u}) {
      img = render(c, a, StorageFormat::Rgba8T8Z32, k);
      EXPECT_EQ(img.at(0, 0), c.clear) << a << " k " << k;
    }
}

// ---------------------------------------------------------------- exact values
// alpha = 0 changes nothing: every algorithm, format and k returns the
// background bit-exactly (a = 0 must neither take a layer nor divide by 0).
TEST(StressExact, Alpha0IsBackgroundEverywhere) {
  const StressCase c = makeCase("alpha_0_x4096");
  for (const StressConfig& cfg : stressConfigs())
    for (StorageFormat f : kAllFormats)
      for (unsigned k : {1u, 4u, 16u}) {
        std::unique_ptr<OitAlgorithm> a;
        try {
          a = make(cfg.algorithm, f, k, cfg.params);
        } catch (const std::invalid_argument&) {
          continue;  // format not supported
        }
        const RenderResult r = renderCase(c, *a);
        for (const Rgb& p : r.image.pixels)
          EXPECT_EQ(p, c.clear) << cfg.algorithm << " " << cfg.variant << " " << toString(f) << " k " << k;
      }
}

// An alpha-1 fragment in front of everything: the algorithms that keep the
// nearest surface exactly return its colour, whether it is submitted first
// (pixel 0,0) or last (pixel 1,1).
TEST(StressExact, Alpha1FrontFragmentIsItsColour) {
  const StressCase c = makeCase("alpha_1_then_more");
  const Rgb front{0.8f, 0.3f, 0.1f};
  struct Exact {
    const char* algo;
    AlgorithmParams p;
    unsigned minK;
  };
  AlgorithmParams mask;
  mask.coverage_mask = true;
  mask.bits = 32;
  AlgorithmParams s64;
  s64.samples = 64;
  const Exact exact[] = {{"abuffer", {}, 1}, {"mlab", {}, 1},     {"kbuffer", {}, 1},   {"hybrid", {}, 2},
                         {"adaptive", {}, 1}, {"slab", {}, 1},    {"slab", mask, 1},    {"stochastic", {}, 1},
                         {"stochastic", s64, 1}};
  for (const Exact& e : exact)
    for (unsigned k : {1u, 4u, 16u}) {
      if (k < e.minK) continue;  // hybrid k = 1 has no core row: all in the averaged tail
      const Image img = render(c, e.algo, StorageFormat::Fp32, k, e.p);
      EXPECT_EQ(img.at(0, 0), front) << e.algo << " k " << k << " (submitted first)";
      EXPECT_EQ(img.at(1, 1), front) << e.algo << " k " << k << " (submitted last)";
    }
  // Submission-order blending is right only when the front one comes last.
  EXPECT_EQ(render(c, "alpha").at(1, 1), front);
  EXPECT_GT(std::abs(render(c, "alpha").at(0, 0).r - front.r), 0.01f);
  // Quantised rows: the colour's own rounding only (unorm8 half step, fp16 2^-12 relative).
  for (const char* a : {"mlab", "kbuffer", "hybrid"})
    for (unsigned k : {2u, 4u, 16u}) {
      expectNear(render(c, a, StorageFormat::Rgba8T8Z32, k).at(0, 0), front, 0.5 / 255 + 1e-7,
                 std::string(a) + " rgba8 k " + std::to_string(k));
      expectNear(render(c, a, StorageFormat::Fp16, k).at(1, 1), front, 0.8 / 4096 + 1e-7,
                 std::string(a) + " fp16 k " + std::to_string(k));
    }
}

// Three fragments of alpha 0.5 at one depth, red then green then blue: the
// later one is in front, C = 0.5 blue + 0.25 green + 0.125 red + 0.125 bg.
TEST(StressExact, EqualDepthsLaterSubmittedInFront) {
  const StressCase c = makeCase("equal_depths_512");
  const Rgb bg = c.clear;
  const Rgb want{float(0.125 + 0.125 * bg.r), float(0.25 + 0.125 * bg.g), float(0.5 + 0.125 * bg.b)};
  struct Exact {
    const char* algo;
    unsigned minK;
  };
  // slab with continuous alpha and < k layers inserts every fragment
  // (nothing strictly in front: P = 1); mlab / alpha: equal depths with the
  // later in front is back-to-front input, exact at any k.
  const Exact exact[] = {{"abuffer", 1}, {"alpha", 1}, {"mlab", 1}, {"kbuffer", 3},
                         {"hybrid", 4},  {"adaptive", 3}, {"slab", 3}};
  for (const Exact& e : exact)
    for (unsigned k : {1u, 4u, 16u}) {
      if (k < e.minK) continue;
      const Image img = render(c, e.algo, StorageFormat::Fp32, k);
      expectNear(img.at(1, 1), want, 1e-6, std::string(e.algo) + " k " + std::to_string(k));
    }
  // The 512-deep pixel is back-to-front input too: mlab and alpha stay exact.
  const Rgb ref = render(c, "abuffer").at(0, 0);
  for (unsigned k : {1u, 4u, 16u}) expectNear(render(c, "mlab", StorageFormat::Fp32, k).at(0, 0), ref, 1e-6, "mlab 512");
  expectNear(render(c, "alpha").at(0, 0), ref, 1e-6, "alpha 512");
}

// Opaque at depth 0 culls every transparent fragment: every algorithm shows
// the opaque colour bit-exactly; culled counts match an independent count.
TEST(StressExact, OpaqueCullsEverythingBehind) {
  const StressCase c = makeCase("opaque_in_front");
  uint64_t expectCulled = 0;
  {
    std::map<std::pair<int, int>, float> oz;
    for (const Fragment& f : c.fragments)
      if (f.draw == kOpaqueDraw) {
        auto [it, fresh] = oz.try_emplace({f.x, f.y}, f.z);
        if (!fresh) it->second = std::min(it->second, f.z);
      }
    for (const Fragment& f : c.fragments)
      if (f.draw != kOpaqueDraw && oz.count({f.x, f.y}) && f.z >= oz[{f.x, f.y}]) ++expectCulled;
  }
  ASSERT_GT(expectCulled, 256u);
  for (const StressConfig& cfg : stressConfigs())
    for (StorageFormat f : kAllFormats) {
      std::unique_ptr<OitAlgorithm> a;
      try {
        a = make(cfg.algorithm, f, 4, cfg.params);
      } catch (const std::invalid_argument&) {
        continue;
      }
      const RenderResult r = renderCase(c, *a);
      const std::string w = cfg.algorithm + " " + cfg.variant + " " + toString(f);
      EXPECT_EQ(r.image.at(1, 1), (Rgb{0.9f, 0.8f, 0.7f})) << w;
      EXPECT_EQ(r.counts.culled, expectCulled) << w;
      EXPECT_EQ(r.counts.opaque, 4u) << w;
    }
  // Two opaque fragments of equal depth: the first one wins (depth test LESS).
  expectNear(independentReference(c, 0, 1), render(c, "abuffer").at(0, 1), 2e-7, "equal opaque depth");
}

// MLAB is exact for input sorted front to back or back to front at any k:
// in fp32 the error is rounding only, even after 4095 merges.
TEST(StressExact, MlabSortedMergeChainsExactInFp32) {
  for (const char* n : {"merge_chain_8bit_1024", "merge_chain_fp16_4096"}) {
    const StressCase c = makeCase(n);
    const Image ref = render(c, "abuffer");
    for (unsigned k : {1u, 4u, 16u}) {
      const Image img = render(c, "mlab", StorageFormat::Fp32, k);
      for (uint16_t xy : {0, 1}) expectNear(img.at(xy, xy), ref.at(xy, xy), 2e-5, std::string(n) + " k " + std::to_string(k));
    }
  }
}

// wboit with one colour is exact while sum w a stays under the 5e4 clamp:
// 16 alpha-1 fragments at the 3e3 weight cap (sum 48000).
TEST(StressExact, WboitUniformColourBelowClampIsExact) {
  const StressCase c = makeCase("wboit_weight_max");
  for (int eq : {7, 8, 9, 10}) {
    AlgorithmParams p;
    p.weight = eq;
    expectNear(render(c, "wboit", StorageFormat::Fp32, 4, p).at(1, 1), {1.0f, 0.5f, 0.25f}, 1e-6,
               "wboit eq " + std::to_string(eq));
  }
}

// ---------------------------------------------------------------- saturation
// The final colour write saturates to [0,1] (model/AlgorithmDetail.hpp). These
// two cases once left the range; they pin the saturated values.

// wboit as published divides by clamp(sum w a, 1e-4, 5e4): 64 alpha-1
// fragments of colour (1, .5, .25) at z = 0 with eq. 10 weigh 3e3 each, so
// A = 192000 (1, .5, .25, 1), A.a clamps to 5e4 and the colour is
// 3.84 (1, .5, .25) before the write saturates it; R = 0 hides the background.
TEST(StressSaturation, WboitPublishedClampOvershootSaturates) {
  const StressCase c = makeCase("wboit_weight_max");
  AlgorithmParams p;
  p.weight = 10;
  const Rgb got = render(c, "wboit", StorageFormat::Fp32, 4, p).at(0, 0);
  EXPECT_EQ(got.r, 1.0f);
  EXPECT_EQ(got.g, 1.0f);
  EXPECT_FLOAT_EQ(got.b, 0.96f);
}

// unorm8 and fp16 rows quantise a c and T = 1 - a independently: c = 1,
// a = 0.5 over white stores colour code 128 and T code 128, 256/255 before
// saturation; fp16 with a = 1e-7 keeps colour 1.19e-7 beside T = 1.
TEST(StressSaturation, QuantisedRowsOverWhiteSaturateToOne) {
  StressCase one = makeCase("white_on_white");
  one.fragments = {Fragment{0, 0, 0.5f, 1, 1, 1, 0.5f, 0, kGlassDraw}};
  EXPECT_EQ(render(one, "mlab", StorageFormat::Rgba8T8Z32, 4).at(0, 0).r, 1.0f);
  // Below the overshoot nothing is clamped: c = 0 gives T code 128 alone.
  one.fragments = {Fragment{0, 0, 0.5f, 0, 0, 0, 0.5f, 0, kGlassDraw}};
  EXPECT_FLOAT_EQ(render(one, "mlab", StorageFormat::Rgba8T8Z32, 4).at(0, 0).r, 128.0f / 255.0f);
  one.fragments = {Fragment{0, 0, 0.5f, 1, 1, 1, 1e-7f, 0, kGlassDraw}};
  EXPECT_EQ(render(one, "mlab", StorageFormat::Fp16, 4).at(0, 0).r, 1.0f);
}

}  // namespace
}  // namespace oit::model::stress
