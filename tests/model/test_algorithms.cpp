// Per-pixel OIT algorithms: the registry, layouts, and what every algorithm must
// do (exactness where it is due, the tie rule, outcomes, determinism, the interface).
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "AlgoTestUtil.hpp"
#include "ThreeFragments.hpp"
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
