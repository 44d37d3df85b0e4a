// Per-pixel OIT algorithms against hand-computed values and the A-buffer.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "AlgoTestUtil.hpp"
#include "model/AlgorithmDetail.hpp"

using namespace oit;
using namespace oit::model;
using namespace oit::model::testutil;

namespace {

const std::vector<std::string> kAll = {"abuffer", "alpha", "mlab", "hybrid", "adaptive",
                                       "kbuffer", "wsum", "wavg", "wboit", "slab", "stochastic",
                                       "mlcb"};
// Algorithms whose pixel depends on fragment order / depth (tie rule matters).
const std::vector<std::string> kOrdered = {"abuffer", "mlab", "hybrid", "adaptive", "kbuffer"};

}  // namespace

TEST(Registry, ListsEveryAlgorithmWithDescription) {
  const auto& names = algorithmNames();
  ASSERT_EQ(names.size(), kAll.size());
  for (size_t i = 0; i < kAll.size(); ++i) {
    EXPECT_EQ(names[i].name, kAll[i]);
    EXPECT_FALSE(names[i].description.empty());
    EXPECT_EQ(makeAlgorithm(kAll[i], {})->name(), kAll[i]);
  }
}

TEST(Registry, RejectsUnknownNamesAndBadParameters) {
  try {
    makeAlgorithm("mlba", {});
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("mlab"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("wboit"), std::string::npos) << e.what();
  }
  EXPECT_THROW(makeAlgorithm("mlab", layers(0)), std::invalid_argument);
  EXPECT_THROW(makeAlgorithm("kbuffer", layers(65)), std::invalid_argument);
  EXPECT_THROW(makeAlgorithm("adaptive", layers(4, StorageFormat::Fp16)), std::invalid_argument);
  EXPECT_THROW(makeAlgorithm("wboit", layers(4, StorageFormat::Rgba8T8Z32)), std::invalid_argument);
  AlgorithmParams p;
  p.weight = 11;
  try {
    makeAlgorithm("wboit", p);
    FAIL() << "no throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("7, 8, 9 or 10"), std::string::npos) << e.what();
  }
}

TEST(Layout, BytesPerPixelFollowTheStorageFormat) {
  // MLAB paper, Sec. 4.2: 8 B per row in rgba8t8z32; HT iso-memory with MLAB.
  EXPECT_EQ(makeAlgorithm("mlab", layers(4, StorageFormat::Rgba8T8Z32))->bytesPerPixel(), 32u);
  EXPECT_EQ(makeAlgorithm("hybrid", layers(4, StorageFormat::Rgba8T8Z32))->bytesPerPixel(), 32u);
  EXPECT_EQ(makeAlgorithm("mlab", layers(4))->bytesPerPixel(), 80u);
  EXPECT_EQ(makeAlgorithm("mlab", layers(4, StorageFormat::Fp16))->bytesPerPixel(), 48u);
  EXPECT_EQ(makeAlgorithm("kbuffer", layers(2))->stateWords(), 10u);
  EXPECT_EQ(makeAlgorithm("alpha", layers(1, StorageFormat::Rgba8T8Z32))->bytesPerPixel(), 4u);
  EXPECT_EQ(makeAlgorithm("wboit", layers(1, StorageFormat::Fp16))->bytesPerPixel(), 12u);
  EXPECT_EQ(makeAlgorithm("adaptive", layers(4))->bytesPerPixel(), 4u * (12 + 5));
  EXPECT_EQ(makeAlgorithm("abuffer", {})->bytesPerPixel(), 4u);
  EXPECT_FALSE(makeAlgorithm("abuffer", {})->bounded());
  EXPECT_EQ(makeAlgorithm("adaptive", {})->passes(), 2u);
}

TEST(Layout, Fp32FastPathMatchesTheCodec) {
  const LayerRow row{0.1f, 0.2f, 0.3f, 0.4f, 0.5f};
  uint32_t a[5], b[5];
  detail::storeRow(StorageFormat::Fp32, row, a);
  encodeRow(StorageFormat::Fp32, row, b);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(a[i], b[i]);
  const LayerRow back = detail::loadRow(StorageFormat::Fp32, b);
  const LayerRow ref = decodeRow(StorageFormat::Fp32, b);
  EXPECT_EQ(back.r, ref.r);
  EXPECT_EQ(back.t, ref.t);
  EXPECT_EQ(back.z, ref.z);
}

// One fragment per pixel: every algorithm is exact. Dyadic inputs make every
// product exact in binary32, so equality is bitwise.
TEST(Exactness, OneFragmentPerPixelEveryAlgorithmEqualsReference) {
  std::vector<Fragment> fs = {
      frag(0, 0, 0.5f, 0.25f, 0.5f, 1.0f, 0.5f),
      frag(1, 0, 0.25f, 1.0f, 0.75f, 0.0f, 0.25f),
      frag(2, 0, 0.5f, 0.5f, 0.5f, 0.5f, 1.0f),
      frag(0, 1, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f, kOpaqueDraw),  // opaque bg (black) behind
      frag(0, 1, 0.5f, 1.0f, 0.5f, 0.25f, 0.75f),
      frag(1, 1, 0.75f, 0.5f, 0.25f, 1.0f, 1.0f, kOpaqueDraw),  // opaque bg behind
      frag(1, 1, 0.5f, 0.25f, 0.25f, 0.25f, 0.5f),
  };
  RenderOptions opt;
  opt.clear_colour = {0.25f, 0.5f, 0.75f};
  auto expect = [&](uint32_t x, uint32_t y, float a, Rgb c, Rgb bg) {
    return Rgb{a * c.r + (1 - a) * bg.r, a * c.g + (1 - a) * bg.g, a * c.b + (1 - a) * bg.b};
  };
  const Rgb cc = opt.clear_colour;
  const std::vector<Rgb> want = {
      expect(0, 0, 0.5f, {0.25f, 0.5f, 1.0f}, cc),   expect(1, 0, 0.25f, {1.0f, 0.75f, 0.0f}, cc),
      expect(2, 0, 1.0f, {0.5f, 0.5f, 0.5f}, cc),    expect(0, 1, 0.75f, {1.0f, 0.5f, 0.25f}, {0, 0, 0}),
      expect(1, 1, 0.5f, {0.25f, 0.25f, 0.25f}, {0.5f, 0.25f, 1.0f}), cc,
  };
  for (const std::string& name : kAll) {
    for (unsigned k : {1u, 4u}) {
      const RenderResult r = render(name, layers(k), fs, 3, 2, opt);
      const std::vector<size_t> px = {0, 1, 2, 3, 4, 5};
      for (size_t i : px) {
        EXPECT_EQ(r.image.pixels[i], want[i]) << name << " k=" << k << " pixel " << i << " got "
                                              << r.image.pixels[i].r << "," << r.image.pixels[i].g << ","
                                              << r.image.pixels[i].b;
      }
    }
  }
}

TEST(Exactness, OneRandomFragmentPerPixelWithin1e6) {
  const auto fs = randomScene(16, 16, 1, 7);
  const Image ref = render("abuffer", {}, fs, 16, 16).image;
  for (const std::string& name : kAll) {
    // mlcb quantises a random alpha to b mask bits: its own bound is tested in
    // test_mlcb.cpp (MlcbExactness.OneRandomFragmentWithinQuantisationBound).
    if (name == "mlcb") continue;
    EXPECT_LT(maxDiff(render(name, layers(1), fs, 16, 16).image, ref), 1e-6) << name;
  }
}

TEST(Exactness, EnoughLayersEqualReference) {
  const auto fs = randomScene(12, 12, 6, 11);
  const Image ref = render("abuffer", {}, fs, 12, 12).image;
  // hybrid k = 6: 5 core rows and at most one fragment in the tail, which a
  // one-fragment average represents exactly.
  for (const std::string name : {"mlab", "hybrid", "adaptive", "kbuffer"})
    for (unsigned k : {6u, 7u, 16u}) {
      const RenderResult r = render(name, layers(k), fs, 12, 12);
      EXPECT_LT(maxDiff(r.image, ref), 1e-6) << name << " k=" << k;
    }
  // Too few layers is not exact (the comparison above can fail).
  for (const std::string name : {"mlab", "hybrid", "adaptive", "kbuffer"})
    EXPECT_GT(maxDiff(render(name, layers(2), fs, 12, 12).image, ref), 1e-3) << name;
}

TEST(Mlab, OneLayerExactForSortedInput) {
  // Pixel (0,0) front to back, (1,0) back to front, 10 fragments each.
  std::vector<Fragment> fs;
  for (int i = 0; i < 10; ++i) {
    const float c = 0.1f * i;
    fs.push_back(frag(0, 0, 0.05f + 0.09f * i, c, 1 - c, 0.5f, 0.2f + 0.07f * i));
    fs.push_back(frag(1, 0, 0.95f - 0.09f * i, 1 - c, 0.3f, c, 0.9f - 0.08f * i));
  }
  RenderOptions opt;
  opt.clear_colour = {0.2f, 0.4f, 0.6f};
  const Image ref = render("abuffer", {}, fs, 2, 1, opt).image;
  const RenderResult r = render("mlab", layers(1), fs, 2, 1, opt);
  EXPECT_LT(maxDiff(r.image, ref), 1e-6);
  EXPECT_EQ(r.counts.merged, 18u);  // every fragment after the first of a pixel
  EXPECT_EQ(r.counts.stored, 2u);
  // k-buffer with one layer keeps only the nearest: far from the reference.
  EXPECT_GT(maxDiff(render("kbuffer", layers(1), fs, 2, 1, opt).image, ref), 0.05);
}

TEST(Mlab, FragmentBetweenMergedRowsIsCompositedBehind) {
  // k = 1: z .5 and .9 merge into one row at z .5; then z .7 arrives and lands
  // behind the merged row (MLAB's approximation), not between.
  const float a1 = 0.5f, a2 = 0.5f, a3 = 0.5f;
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 1, 0, 0, a1), frag(0, 0, 0.9f, 0, 1, 0, a2),
                              frag(0, 0, 0.7f, 0, 0, 1, a3)};
  const Rgb got = render("mlab", layers(1), fs, 1, 1).image.pixels[0];
  EXPECT_EQ(got, (Rgb{0.5f, 0.25f, 0.125f}));  // red, then green, then blue behind
  const Rgb ref = render("abuffer", {}, fs, 1, 1).image.pixels[0];
  EXPECT_EQ(ref, (Rgb{0.5f, 0.125f, 0.25f}));  // red, blue, green
  // k = 2 has room: exact.
  EXPECT_EQ(render("mlab", layers(2), fs, 1, 1).image.pixels[0], ref);
}

TEST(Mlab, QuantisedRowsRoundToNearest) {
  // p = a c = (.125, .25, .5), T = .5 -> unorm8 codes 32, 64, 128 (round to nearest).
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 0.25f, 0.5f, 1.0f, 0.5f)};
  const Rgb got = render("mlab", layers(2, StorageFormat::Rgba8T8Z32), fs, 1, 1).image.pixels[0];
  EXPECT_EQ(got, (Rgb{32 / 255.0f, 64 / 255.0f, 128 / 255.0f}));
}

// Equal depths: the later-submitted fragment is in front.
TEST(TieRule, LaterSubmittedIsInFront) {
  // red (first) and blue (later) at the same depth, a = .5 each, black bg:
  // blue in front -> (.25, 0, .5).
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 1, 0, 0, 0.5f), frag(0, 0, 0.5f, 0, 0, 1, 0.5f),
                              // pixel 1: a third, nearer fragment and the tie behind it
                              frag(1, 0, 0.5f, 1, 0, 0, 0.5f), frag(1, 0, 0.25f, 0, 1, 0, 0.5f),
                              frag(1, 0, 0.5f, 0, 0, 1, 0.5f)};
  const Rgb want0{0.25f, 0.0f, 0.5f};
  const Rgb want1{0.125f, 0.5f, 0.25f};
  for (const std::string& name : kOrdered) {
    const unsigned k = name == "hybrid" ? 4 : 3;  // hybrid: 3 core rows
    const Image img = render(name, layers(k), fs, 2, 1).image;
    EXPECT_EQ(img.pixels[0], want0) << name;
    EXPECT_EQ(img.pixels[1], want1) << name;
  }
  // One layer: the front (later) fragment of the tie keeps the layer.
  EXPECT_EQ(render("kbuffer", layers(1), fs, 2, 1).image.pixels[0], (Rgb{0, 0, 0.5f}));
  EXPECT_EQ(render("mlab", layers(1), fs, 2, 1).image.pixels[0], want0);
  // hybrid k = 2: the later one in the core, the earlier in the tail.
  EXPECT_EQ(render("hybrid", layers(2), fs, 2, 1).image.pixels[0], want0);
}

TEST(TieRule, AlphaBlendingFollowsSubmissionOrder) {
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 1, 0, 0, 0.5f), frag(0, 0, 0.5f, 0, 0, 1, 0.5f)};
  EXPECT_EQ(render("alpha", {}, fs, 1, 1).image.pixels[0], (Rgb{0.25f, 0.0f, 0.5f}));
}

// Three fragments of mixed depth over a clear colour, hand-computed.
namespace {
const Rgb kBg{0.25f, 0.5f, 0.75f};
std::vector<Fragment> threeFragments() {
  return {frag(0, 0, 0.2f, 1, 0, 0, 0.5f), frag(0, 0, 0.8f, 0, 1, 0, 0.25f), frag(0, 0, 0.5f, 0, 0, 1, 0.75f)};
}
Rgb renderThree(std::string_view name, AlgorithmParams p = {}) {
  RenderOptions opt;
  opt.clear_colour = kBg;
  return render(name, p, threeFragments(), 1, 1, opt).image.pixels[0];
}
void expectNear(Rgb got, double r, double g, double b, double tol, const std::string& what) {
  EXPECT_NEAR(got.r, r, tol) << what;
  EXPECT_NEAR(got.g, g, tol) << what;
  EXPECT_NEAR(got.b, b, tol) << what;
}
}  // namespace

TEST(Alpha, OverBlendingInSubmissionOrder) {
  // C1 = .5 red + .5 bg; C2 = .25 green + .75 C1; C3 = .75 blue + .25 C2.
  EXPECT_EQ(renderThree("alpha"), (Rgb{0.1171875f, 0.109375f, 0.8203125f}));
  // The reference sorts by depth: red, blue, green.
  // T = .5 * .75 * .25 = .09375.
  expectNear(renderThree("abuffer"), 0.5 + 0.25 * 0.09375, 0.5 * 0.25 * 0.25 + 0.5 * 0.09375,
             0.5 * 0.75 + 0.75 * 0.09375, 1e-7, "abuffer");
}

TEST(Weighted, WeightedSumByHand) {
  // S = (.5, .25, .75), sum a = 1.5: C = bg + S - 1.5 bg.
  EXPECT_EQ(renderThree("wsum"), (Rgb{0.375f, 0.0f, 0.375f}));
  // Leaves [0,1] below: clamped.
  RenderOptions opt;
  opt.clear_colour = {1, 1, 1};
  std::vector<Fragment> fs = {frag(0, 0, 0.2f, 0, 0, 0, 0.75f), frag(0, 0, 0.3f, 0, 0, 0, 0.75f)};
  EXPECT_EQ(render("wsum", {}, fs, 1, 1, opt).image.pixels[0], (Rgb{0, 0, 0}));
}

TEST(Weighted, WeightedAverageByHand) {
  // avg = S / 1.5 = (1/3, 1/6, 1/2); T = (1 - 1.5/3)^3 = .125.
  expectNear(renderThree("wavg"), 0.875 / 3 + 0.125 * 0.25, 0.875 / 6 + 0.125 * 0.5, 0.4375 + 0.125 * 0.75,
             1e-6, "wavg");
}

TEST(Weighted, WeightedAverageEmptyAndZeroAlphaGiveBackground) {
  RenderOptions opt;
  opt.clear_colour = kBg;
  std::vector<Fragment> fs = {frag(0, 0, 0.2f, 1, 1, 1, 0.0f)};  // pixel 1 gets nothing
  const Image img = render("wavg", {}, fs, 2, 1, opt).image;
  EXPECT_EQ(img.pixels[0], kBg);
  EXPECT_EQ(img.pixels[1], kBg);
}

TEST(Weighted, WboitEq10ByHand) {
  // w = a max(.01, 3e3 (1-d)^3): .5*1536 = 768, .25*24 = 6, .75*375 = 281.25; the
  // accumulator adds w (a c, a): a w = 384, 1.5 and 210.9375 (a enters twice).
  const double A = 384 + 1.5 + 210.9375, R = 0.5 * 0.75 * 0.25;
  expectNear(renderThree("wboit"), 384 / A * (1 - R) + 0.25 * R, 1.5 / A * (1 - R) + 0.5 * R,
             210.9375 / A * (1 - R) + 0.75 * R, 1e-6, "wboit eq10");
}

TEST(Weighted, WboitViewSpaceWeightsNeedCamera) {
  AlgorithmParams p;
  p.weight = 7;
  EXPECT_THROW(renderThree("wboit", p), std::invalid_argument);
  p.camera = CameraPlanes{1.0f, 101.0f};
  // z_view = n f / (f - d (f - n)) = 101 / (101 - 100 d).
  auto zv = [](double d) { return 101.0 / (101.0 - 100.0 * d); };
  auto w7 = [](double z) {
    return std::clamp(10.0 / (1e-5 + std::pow(z / 5, 2) + std::pow(z / 200, 6)), 1e-2, 3e3);
  };
  auto w8 = [](double z) {
    return std::clamp(10.0 / (1e-5 + std::pow(z / 10, 3) + std::pow(z / 200, 6)), 1e-2, 3e3);
  };
  auto w9 = [](double z) { return std::clamp(0.03 / (1e-5 + std::pow(z / 200, 4)), 1e-2, 3e3); };
  const double R = 0.5 * 0.75 * 0.25;
  for (int eq : {7, 8, 9}) {
    p.weight = eq;
    auto w = [&](double d) { return eq == 7 ? w7(zv(d)) : eq == 8 ? w8(zv(d)) : w9(zv(d)); };
    // a w(z, a) = a^2 clamp(...): alphas .5, .25, .75.
    const double wr = 0.25 * w(0.2), wg = 0.0625 * w(0.8), wb = 0.5625 * w(0.5), A = wr + wg + wb;
    expectNear(renderThree("wboit", p), wr / A * (1 - R) + 0.25 * R, wg / A * (1 - R) + 0.5 * R,
               wb / A * (1 - R) + 0.75 * R, 1e-5, "wboit eq" + std::to_string(eq));
  }
  // Camera from the trace header works too: the same pixel as from the parameters.
  p.weight = 8;
  const auto from_params = renderThree("wboit", p);
  TraceHeader h = header(1, 1);
  h.camera = CameraPlanes{1.0f, 101.0f};
  p.camera.reset();
  RenderOptions opt;
  opt.clear_colour = kBg;
  const Rgb from_header = render("wboit", p, threeFragments(), 1, 1, opt, h).image.pixels[0];
  EXPECT_EQ(from_header.r, from_params.r);
  EXPECT_EQ(from_header.g, from_params.g);
  EXPECT_EQ(from_header.b, from_params.b);
}

TEST(Outcomes, CountsPerAlgorithm) {
  // Three fragments at one pixel, depth order 1 < 3 < 2 as submitted.
  const auto fs = threeFragments();
  auto counts = [&](std::string_view name, unsigned k) { return render(name, layers(k), fs, 1, 1).counts; };
  RenderCounts c = counts("mlab", 2);
  EXPECT_EQ(c.stored, 2u);
  EXPECT_EQ(c.merged, 1u);
  c = counts("kbuffer", 2);  // the third (z .5) evicts z .8: merged
  EXPECT_EQ(c.stored, 2u);
  EXPECT_EQ(c.merged, 1u);
  c = counts("kbuffer", 1);  // z .8 and .5 arrive behind z .2: dropped, state untouched
  EXPECT_EQ(c.stored, 1u);
  EXPECT_EQ(c.discarded, 2u);
  c = counts("hybrid", 2);  // one core row: every later fragment overflows into the tail
  EXPECT_EQ(c.stored, 1u);
  EXPECT_EQ(c.merged, 2u);
  c = counts("adaptive", 2);
  EXPECT_EQ(c.stored, 2u);
  EXPECT_EQ(c.merged, 1u);
  EXPECT_EQ(c.pass_outcomes.size(), 2u);
  EXPECT_EQ(c.pass_outcomes[1][0], 3u);  // composite pass: all accumulated
  for (const std::string& name : kAll) EXPECT_TRUE(counts(name, 2).balanced()) << name;
}

TEST(Outcomes, ZeroAlphaIsDiscardedWithoutTakingALayer) {
  std::vector<Fragment> fs = {frag(0, 0, 0.1f, 1, 1, 1, 0.0f), frag(0, 0, 0.5f, 1, 0, 0, 0.5f)};
  for (const std::string& name : kAll) {
    if (name == "abuffer") continue;
    const RenderResult r = render(name, layers(1), fs, 1, 1);
    EXPECT_EQ(r.counts.discarded, 1u) << name;
    EXPECT_EQ(r.image.pixels[0], (Rgb{0.5f, 0, 0})) << name;
  }
}

TEST(Robustness, NoNanOrInfForAnyFormat) {
  // 64 fragments per pixel with alphas of exactly 1 and tiny ones.
  auto fs = randomScene(4, 4, 64, 3, 64);
  for (size_t i = 0; i < fs.size(); i += 3) fs[i].a = (i % 2) ? 1.0f : 1e-7f;
  for (const std::string& name : kAll)
    for (StorageFormat f : {StorageFormat::Fp32, StorageFormat::Fp16, StorageFormat::Rgba8T8Z32}) {
      std::unique_ptr<OitAlgorithm> probe;
      try {
        probe = makeAlgorithm(name, layers(4, f));
      } catch (const std::invalid_argument&) {
        continue;  // format not offered by this algorithm
      }
      const RenderResult r = render(name, layers(4, f), fs, 4, 4);
      EXPECT_TRUE(allFinite(r.image)) << name << " " << toString(f);
      EXPECT_TRUE(r.counts.balanced()) << name;
    }
}

TEST(Determinism, SameImageEveryRunAndBatchSize) {
  const auto fs = randomScene(8, 8, 12, 5);
  for (const std::string& name : kAll) {
    const Image a = render(name, layers(3), fs, 8, 8).image;
    MemorySource src(header(8, 8), fs, 1u << 16);
    auto algo = makeAlgorithm(name, layers(3));
    const Image b = FunctionalRenderer().render(src, *algo).image;
    const Image c = FunctionalRenderer().render(src, *algo).image;  // same object reused
    EXPECT_EQ(a.pixels, b.pixels) << name;
    EXPECT_EQ(b.pixels, c.pixels) << name;
  }
}

TEST(Interface, DirectPerPixelCallsWithoutRenderer) {
  // The timing model's view: caller-owned words, clear / insert / resolve.
  auto algo = makeAlgorithm("mlab", layers(2));
  std::vector<uint32_t> words(algo->stateWords());
  algo->beginFrame(header(1, 1));
  algo->clear(words.data());
  EXPECT_EQ(algo->resolve(words.data(), {0.5f, 0.5f, 0.5f}), (Rgb{0.5f, 0.5f, 0.5f}));
  InsertContext ctx;
  EXPECT_EQ(algo->insert(words.data(), frag(0, 0, 0.5f, 1, 0, 0, 0.5f), 0, ctx), InsertOutcome::Stored);
  EXPECT_EQ(algo->insert(words.data(), frag(0, 0, 0.25f, 0, 1, 0, 0.5f), 0, ctx), InsertOutcome::Stored);
  EXPECT_EQ(algo->insert(words.data(), frag(0, 0, 0.75f, 0, 0, 1, 0.5f), 0, ctx), InsertOutcome::Merged);
  EXPECT_EQ(algo->resolve(words.data(), {0, 0, 0}), (Rgb{0.25f, 0.5f, 0.125f}));
  EXPECT_EQ(algo->readBytes(0, InsertOutcome::Merged), 40u);
  EXPECT_EQ(algo->writeBytes(0, InsertOutcome::Discarded), 0u);
}

TEST(Interface, InsertFnEqualsInsertForEveryAlgorithm) {
  // The frame loops insert through insertFn() (mlab and kbuffer: their
  // per-format insert, no second dispatch): for every algorithm, format and
  // pass, the same outcomes and words as insert(), so the same resolve.
  uint64_t stored = 0, merged = 0, discarded = 0;
  for (const AlgorithmInfo& info : algorithmNames()) {
    const std::string name(info.name);
    for (StorageFormat fmt : {StorageFormat::Fp32, StorageFormat::Fp16, StorageFormat::Rgba8T8Z32}) {
      AlgorithmParams p;
      p.layers = 3;
      p.format = fmt;
      std::unique_ptr<OitAlgorithm> a, b;
      try {
        a = makeAlgorithm(name, p);
        b = makeAlgorithm(name, p);
      } catch (const std::invalid_argument&) {
        continue;  // combination not supported by this algorithm
      }
      a->beginFrame(header(4, 1));
      b->beginFrame(header(4, 1));
      const unsigned w = a->stateWords();
      std::vector<uint32_t> sa(4 * w), sb(4 * w);
      a->clearFrame(sa.data(), 4);
      b->clearFrame(sb.data(), 4);
      const OitAlgorithm::InsertFn direct = b->insertFn();
      uint32_t lcg = 12345;
      const auto next = [&] { return float((lcg = lcg * 1664525u + 1013904223u) >> 8) / float(1 << 24); };
      for (unsigned pass = 0; pass < a->passes(); ++pass) {
        lcg = 12345;  // every pass sees the same fragments in the same order
        InsertContext ctx;
        for (unsigned i = 0; i < 40; ++i) {
          const uint16_t x = uint16_t(i % 4);
          const float z = next(), r = next(), g = next(), bl = next();
          const float al = i % 9 == 0 ? 0.0f : next();
          const Fragment f = frag(x, 0, z, r, g, bl, al);
          const InsertOutcome oa = a->insert(sa.data() + x * w, f, pass, ctx);
          const InsertOutcome ob = direct(*b, sb.data() + x * w, f, pass, ctx);
          ASSERT_EQ(oa, ob) << name << " " << toString(fmt) << " pass " << pass << " insert " << i;
          ASSERT_EQ(sa, sb) << name << " " << toString(fmt) << " pass " << pass << " insert " << i;
          stored += oa == InsertOutcome::Stored;
          merged += oa == InsertOutcome::Merged;
          discarded += oa == InsertOutcome::Discarded;
        }
      }
      for (unsigned x = 0; x < 4; ++x)
        EXPECT_EQ(a->resolve(sa.data() + x * w, {0.1f, 0.2f, 0.3f}), b->resolve(sb.data() + x * w, {0.1f, 0.2f, 0.3f}))
            << name << " " << toString(fmt);
    }
  }
  EXPECT_GT(stored, 100u);  // every outcome was compared
  EXPECT_GT(merged, 100u);
  EXPECT_GT(discarded, 50u);
}

TEST(Interface, ClearFrameEqualsPerPixelClear) {
  // clearFrame replicates one clear(): valid only while clear() writes every
  // word with the same pattern for every pixel (renderer and front end rely on it).
  for (const AlgorithmInfo& info : algorithmNames()) {
    const std::string name(info.name);
    for (StorageFormat fmt : {StorageFormat::Fp32, StorageFormat::Fp16, StorageFormat::Rgba8T8Z32}) {
      for (unsigned k : {1u, 3u, 8u}) {
        AlgorithmParams p;
        p.layers = k;
        p.format = fmt;
        std::unique_ptr<OitAlgorithm> algo;
        try {
          algo = makeAlgorithm(name, p);
        } catch (const std::invalid_argument&) {
          continue;  // combination not supported by this algorithm
        }
        algo->beginFrame(header(37, 1));
        const unsigned w = algo->stateWords();
        for (size_t pixels : {size_t(1), size_t(2), size_t(37)}) {
          std::vector<uint32_t> per_pixel(pixels * w, 0xdeadbeefu), frame(pixels * w, 0x01234567u);
          for (size_t i = 0; i < pixels; ++i) algo->clear(per_pixel.data() + i * w);
          algo->clearFrame(frame.data(), pixels);
          EXPECT_EQ(per_pixel, frame) << name << " " << toString(fmt) << " k " << k << " pixels " << pixels;
        }
      }
    }
  }
}

TEST(Hash, DeterministicAndSensitiveToEveryKeyField) {
  const Fragment f = frag(3, 4, 0.5f, 1, 1, 1, 1, 2, 9);
  const uint64_t h = fragmentHash(f, 1, 0);
  EXPECT_EQ(h, fragmentHash(f, 1, 0));
  Fragment g = f;
  g.x = 4;
  EXPECT_NE(fragmentHash(g, 1, 0), h);
  g = f;
  g.prim = 10;
  EXPECT_NE(fragmentHash(g, 1, 0), h);
  g = f;
  g.draw = 1;
  EXPECT_NE(fragmentHash(g, 1, 0), h);
  EXPECT_NE(fragmentHash(f, 2, 0), h);
  EXPECT_NE(fragmentHash(f, 1, 1), h);
}

// ---------------------------------------------------------------- adaptive
// Stress-suite repro: more than k fragments at one depth. Every candidate
// node has zero area there; removing node 1 each time ("first minimum wins")
// left the front node with the whole stack's vis, so the second fragment was
// shaded with vis 2^-8 (green 0.052). Now the smallest visibility step goes
// (equal alphas: the last node), so the front k - 1 fragments stay exact.
TEST(Adaptive, EqualDepthStackKeepsFrontNodesExact) {
  // 8 fragments at z .5, a .5, green first, alternating: the last (red) is in front.
  std::vector<Fragment> fs;
  for (int i = 0; i < 8; ++i) fs.push_back(frag(0, 0, 0.5f, i % 2 ? 1.0f : 0.0f, i % 2 ? 0.0f : 1.0f, 0, 0.5f));
  RenderOptions opt;
  opt.clear_colour = {0.2f, 0.4f, 0.6f};
  const double T = 1.0 / 256, bgR = 0.2f, bgG = 0.4f, bgB = 0.6f;
  // Reference: front to back red, green, ... with vis 2^-i: red .5 + .125 +
  // 2^-5 + 2^-7, green .25 + 2^-4 + 2^-6 + 2^-8, plus T bg.
  const Rgb ref = render("abuffer", {}, fs, 1, 1, opt).image.pixels[0];
  expectNear(ref, 0.6640625 + T * bgR, 0.33203125 + T * bgG, T * bgB, 1e-7, "reference");
  // k = 4 keeps nodes (seq 7, 6, 5) exact: vis 1, .5, .25, then node seq 4
  // holds vis .125 for seq 4 and the total 2^-8 for everything behind it:
  // red .5 + .25 .5 + 2 (2^-8 .5), green .5 .5 + .125 .5 + 2 (2^-8 .5).
  const Rgb got = render("adaptive", layers(4), fs, 1, 1, opt).image.pixels[0];
  expectNear(got, 0.62890625 + T * bgR, 0.31640625 + T * bgG, T * bgB, 1e-7, "adaptive k 4");
  // Underestimate property: never more visibility than the reference, and
  // the total transmittance (blue = T bg) is exact.
  EXPECT_LE(got.r, ref.r);
  EXPECT_LE(got.g, ref.g);
  EXPECT_EQ(got.b, ref.b);
  // With k >= 8 nothing is removed: the reference.
  expectNear(render("adaptive", layers(8), fs, 1, 1, opt).image.pixels[0], ref.r, ref.g, ref.b, 1e-7, "k 8");
}

// ---------------------------------------------------------------- slab
TEST(Slab, BackToFrontWithEnoughLayersIsExact) {
  // Every new fragment is in front of all layers: nothing occludes it, P = 1
  // (a b >= 1), so all are kept and the colour pass is exact.
  std::vector<Fragment> fs;
  for (uint16_t x = 0; x < 8; ++x)
    for (int i = 0; i < 6; ++i)
      fs.push_back(frag(x, 0, 0.9f - 0.1f * i, 0.1f * i, 0.5f, 1.0f - 0.1f * x, 0.2f + 0.1f * i));
  const Image ref = render("abuffer", {}, fs, 8, 1).image;
  AlgorithmParams p = layers(6);
  const RenderResult r = render("slab", p, fs, 8, 1);
  EXPECT_LT(maxDiff(r.image, ref), 1e-6);
  EXPECT_EQ(r.counts.stored, fs.size());
  // Three layers: the furthest are evicted and the result is biased.
  p.layers = 3;
  EXPECT_GT(maxDiff(render("slab", p, fs, 8, 1).image, ref), 1e-3);
}

TEST(Slab, InsertionProbabilityFollowsTheStratifiedTable) {
  // Per pixel: F1 (front, a .5) then F2 (behind, a .5). With b = 8: s = 4
  // occluded bits, t = 4 -> P_8(4, 4) = 1 - (4)_4 / (8)_4 = 1 - 24/1680.
  const uint32_t w = 100, h = 100;
  std::vector<Fragment> fs;
  for (uint16_t y = 0; y < h; ++y)
    for (uint16_t x = 0; x < w; ++x) {
      fs.push_back(frag(x, y, 0.2f, 1, 0, 0, 0.5f, kTranspDraw, 2 * (y * w + x)));
      fs.push_back(frag(x, y, 0.8f, 0, 1, 0, 0.5f, kTranspDraw, 2 * (y * w + x) + 1));
    }
  const double pDiscard = 24.0 / 1680.0;  // 0.0143
  for (bool mask : {false, true}) {
    AlgorithmParams p = layers(4);
    p.bits = 8;
    p.coverage_mask = mask;
    const RenderResult r = render("slab", p, fs, w, h);
    const double frac = double(r.counts.discarded) / (w * h);
    EXPECT_NEAR(frac, pDiscard, 0.006) << "mask " << mask;  // ~5 sigma
    EXPECT_GT(r.counts.discarded, 0u);
    EXPECT_TRUE(allFinite(r.image));
  }
}

TEST(Slab, ManyBitsTieRuleLaterInFront) {
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 1, 0, 0, 0.5f), frag(0, 0, 0.5f, 0, 0, 1, 0.5f),
                              frag(1, 0, 0.5f, 1, 0, 0, 0.5f), frag(1, 0, 0.25f, 0, 1, 0, 0.5f),
                              frag(1, 0, 0.5f, 0, 0, 1, 0.5f)};
  AlgorithmParams p = layers(3);
  p.bits = 1024;  // P_b -> 1: a k-buffer with Enderton's normalisation
  const Image img = render("slab", p, fs, 2, 1).image;
  expectNear(img.pixels[0], 0.25, 0.0, 0.5, 1e-6, "pixel 0");
  expectNear(img.pixels[1], 0.125, 0.5, 0.25, 1e-6, "pixel 1");
}

TEST(Slab, RejectsBadBits) {
  AlgorithmParams p;
  p.bits = 0;
  EXPECT_THROW(makeAlgorithm("slab", p), std::invalid_argument);
  p.bits = 33;
  p.coverage_mask = true;
  EXPECT_THROW(makeAlgorithm("slab", p), std::invalid_argument);
  p.samples = 65;
  EXPECT_THROW(makeAlgorithm("stochastic", p), std::invalid_argument);
}

// ---------------------------------------------------------------- stochastic
TEST(Stochastic, TwoLayersAreExactWithStratifiedCoverage) {
  // With exactly round(a S) = 4 of 8 samples per fragment, the back fragment
  // of two always sees exactly half the samples: vis = .5 in either order.
  std::vector<Fragment> fs;
  for (uint16_t x = 0; x < 64; ++x) {
    const bool frontFirst = x % 2;
    Fragment f1 = frag(x, 0, 0.3f, 1, 0.5f, 0, 0.5f, kTranspDraw, 2 * x);
    Fragment f2 = frag(x, 0, 0.6f, 0, 0.25f, 1, 0.5f, kTranspDraw, 2 * x + 1);
    if (frontFirst) {
      fs.push_back(f1);
      fs.push_back(f2);
    } else {
      fs.push_back(f2);
      fs.push_back(f1);
    }
  }
  const Image ref = render("abuffer", {}, fs, 64, 1).image;
  AlgorithmParams p;
  p.samples = 8;
  EXPECT_LT(maxDiff(render("stochastic", p, fs, 64, 1).image, ref), 1e-6);
}

TEST(Stochastic, SeedChangesNoiseNotDeterminism) {
  const auto fs = randomScene(16, 16, 10, 9, 6);
  AlgorithmParams a;
  a.samples = 8;
  AlgorithmParams b = a;
  b.seed = 2;
  for (const std::string name : {"stochastic", "slab"}) {
    const Image i1 = render(name, a, fs, 16, 16).image;
    EXPECT_EQ(i1.pixels, render(name, a, fs, 16, 16).image.pixels) << name;
    EXPECT_NE(i1.pixels, render(name, b, fs, 16, 16).image.pixels) << name;
  }
}

// hybrid fp16: 1000 fragments of a = 2e-4, sent back to front, so each older
// core row falls into the tail. fp16 rounds T = 1 - 2e-4 to 1 (the spacing
// below 1 is 2^-11) but keeps the premultiplied colour 2e-4; the tail used to
// drop such rows and the pixel came out (0.0002, ...), 900x too dark. Exact:
// 1 - 0.9998^1000 = 0.18129 times the colour (1, .5, .25).
TEST(Hybrid, Fp16TailKeepsRowsWhoseTRoundedToOne) {
  std::vector<Fragment> fs;
  for (int i = 0; i < 1000; ++i) fs.push_back(frag(0, 0, 1.0f - float(i) / 1000.0f, 1, 0.5f, 0.25f, 0.0002f, 1, uint32_t(i)));
  const float exact = 1.0f - float(std::pow(0.9998, 1000.0));
  for (StorageFormat f : {StorageFormat::Fp32, StorageFormat::Fp16}) {
    const Rgb got = render("hybrid", layers(2, f), fs, 1, 1).image.pixels[0];
    // fp16's packed tail (10-bit colour ratio, fp16 alpha_sum) costs ~1 %.
    const float tol = f == StorageFormat::Fp32 ? 1e-4f : 0.01f;
    EXPECT_NEAR(got.r, exact, tol) << int(f);
    EXPECT_NEAR(got.g, exact * 0.5f, tol) << int(f);
    EXPECT_NEAR(got.b, exact * 0.25f, tol) << int(f);
  }
}

// The ranges an insert reads and writes (the timing model's cache lines come
// from them): inside the state, at most two, increasing, and as many bytes as
// readBytes / writeBytes (the A-buffer's write adds the node of its pool).
TEST(StateRanges, InsideTheStateAndAddUpToTheRmwBytes) {
  for (const AlgorithmInfo& info : algorithmNames()) {
    const std::string name(info.name);
    for (StorageFormat fmt : {StorageFormat::Fp32, StorageFormat::Fp16, StorageFormat::Rgba8T8Z32}) {
      AlgorithmParams p = layers(4);
      p.format = fmt;
      std::unique_ptr<OitAlgorithm> a;
      try {
        a = makeAlgorithm(name, p);
      } catch (const std::invalid_argument&) {
        continue;  // fp32-only algorithms
      }
      for (unsigned pass = 0; pass < a->passes(); ++pass)
        for (unsigned o = 0; o < kOutcomeCount; ++o) {
          const auto out = InsertOutcome(o);
          for (const StateRanges& r : {a->readRanges(pass, out), a->writeRanges(pass, out)}) {
            ASSERT_LE(r.count, StateRanges::kMax) << name;
            for (unsigned i = 0; i < r.count; ++i) {
              EXPECT_LT(r.range[i].begin, r.range[i].end) << name;
              EXPECT_LE(r.range[i].end, a->bytesPerPixel()) << name;
              if (i) EXPECT_GE(r.range[i].begin, r.range[i - 1].end) << name;
            }
          }
          EXPECT_EQ(a->readRanges(pass, out).bytes(), a->readBytes(pass, out)) << name << " pass " << pass;
          if (a->bounded())
            EXPECT_EQ(a->writeRanges(pass, out).bytes(), a->writeBytes(pass, out)) << name << " pass " << pass;
        }
    }
  }
}

TEST(StateRanges, TwoPassAlgorithmsNameTheirWords) {
  // adaptive k = 4: nodes [0, 48), accumulator [48, 60), counters at 60 and 64.
  auto ad = makeAlgorithm("adaptive", layers(4));
  const StateRanges r1 = ad->readRanges(1, InsertOutcome::Stored), w1 = ad->writeRanges(1, InsertOutcome::Stored);
  ASSERT_EQ(r1.count, 2u);
  EXPECT_EQ(r1.range[0].end, 60u);
  EXPECT_EQ(r1.range[1].begin, 64u);
  ASSERT_EQ(w1.count, 2u);
  EXPECT_EQ(w1.range[0].begin, 48u);  // pass 1 writes the accumulator and its counter only
  EXPECT_EQ(w1.range[1].end, 68u);
  // stochastic S = 8: depths [0, 32), T [32, 36), U and U1 [36, 52).
  AlgorithmParams sp;
  sp.samples = 8;
  auto st = makeAlgorithm("stochastic", sp);
  EXPECT_EQ(st->writeRanges(0, InsertOutcome::Discarded).range[0].begin, 32u);  // T only
  EXPECT_EQ(st->writeRanges(1, InsertOutcome::Stored).range[0].begin, 36u);
  EXPECT_EQ(st->writeRanges(1, InsertOutcome::Stored).bytes(), 16u);
}

TEST(StateRanges, KBufferRejectionReadsOnlyTheLastRow) {
  AlgorithmParams p = layers(4);
  p.format = StorageFormat::Rgba8T8Z32;  // 8-byte rows
  auto kb = makeAlgorithm("kbuffer", p);
  const StateRanges r = kb->readRanges(0, InsertOutcome::Discarded);
  ASSERT_EQ(r.count, 1u);
  EXPECT_EQ(r.range[0].begin, 24u);
  EXPECT_EQ(r.range[0].end, 32u);
  EXPECT_EQ(kb->readBytes(0, InsertOutcome::Stored), 32u);
  // The decision really needs that row alone: k = 2 full of depths .2 and .4,
  // a fragment at .5 is behind the last row and is rejected.
  auto k2 = makeAlgorithm("kbuffer", layers(2));
  std::vector<uint32_t> w(k2->stateWords());
  k2->clear(w.data());
  InsertContext ctx;
  k2->insert(w.data(), frag(0, 0, 0.4f, 1, 0, 0, 0.5f), 0, ctx);
  k2->insert(w.data(), frag(0, 0, 0.2f, 1, 0, 0, 0.5f), 0, ctx);
  EXPECT_EQ(k2->insert(w.data(), frag(0, 0, 0.5f, 1, 0, 0, 0.5f), 0, ctx), InsertOutcome::Discarded);
}

TEST(StateRanges, SortedRowsResolveStopsAtTheFirstEmptyRowOrFullOpacity) {
  // mlab k = 4 fp32 (20-byte rows).
  auto m = makeAlgorithm("mlab", layers(4));
  std::vector<uint32_t> w(m->stateWords());
  m->clear(w.data());
  EXPECT_EQ(m->resolveBytes(w.data()), 20u);  // row 0 is read to see it is empty
  InsertContext ctx;
  m->insert(w.data(), frag(0, 0, 0.5f, 1, 0, 0, 0.5f), 0, ctx);
  EXPECT_EQ(m->resolveBytes(w.data()), 40u);  // one row, then the empty row 1
  m->insert(w.data(), frag(0, 0, 0.2f, 0, 1, 0, 1.0f), 0, ctx);  // opaque in front: T = 0 after row 0
  EXPECT_EQ(m->resolveBytes(w.data()), 20u);
  // The other algorithms read their whole state.
  auto alpha = makeAlgorithm("alpha", layers(4));
  std::vector<uint32_t> a(alpha->stateWords());
  alpha->clear(a.data());
  EXPECT_EQ(alpha->resolveBytes(a.data()), alpha->bytesPerPixel());
}
