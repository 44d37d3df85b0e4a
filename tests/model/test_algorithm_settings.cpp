// model/AlgorithmSettings: a setting an algorithm is declared to ignore leaves
// its image, outcome counts and state size unchanged; one it is declared to use
// changes one of them (or is refused). The sweep's deduplication and `oitsim
// run`'s summary rely on this table.
#include <gtest/gtest.h>

#include <functional>

#include "AlgoTestUtil.hpp"
#include "model/AlgorithmSettings.hpp"

using namespace oit::model;
using oit::Fragment;
using namespace oit::model::testutil;

namespace {

struct Outcome {
  bool refused = false;
  Image image;
  RenderCounts counts;
  unsigned bytes_per_pixel = 0;
};

Outcome run(const std::string& algo, const AlgorithmParams& p, const std::vector<Fragment>& fs) {
  Outcome o;
  try {
    o.bytes_per_pixel = makeAlgorithm(algo, p)->bytesPerPixel();
    RenderResult r = render(algo, p, fs, 8, 8);
    o.image = std::move(r.image);
    o.counts = r.counts;
  } catch (const std::invalid_argument&) {
    o.refused = true;
  }
  return o;
}

bool same(const Outcome& a, const Outcome& b) {
  return !a.refused && !b.refused && a.image.pixels == b.image.pixels && a.bytes_per_pixel == b.bytes_per_pixel &&
         a.counts.stored == b.counts.stored && a.counts.merged == b.counts.merged &&
         a.counts.discarded == b.counts.discarded;
}

TEST(AlgorithmSettings, IgnoredSettingsChangeNothingAndUsedOnesChangeSomething) {
  // Up to 12 fragments per pixel: k = 2 and k = 4 keep different layers.
  const std::vector<Fragment> fs = randomScene(8, 8, 12, 5, 6);
  const AlgorithmParams base = layers(4);
  // Each setting and another value for it.
  const std::vector<std::pair<std::string, std::function<void(AlgorithmParams&)>>> changes = {
      {"layers", [](AlgorithmParams& p) { p.layers = 2; }},
      {"format", [](AlgorithmParams& p) { p.format = StorageFormat::Fp16; }},
      {"bits", [](AlgorithmParams& p) { p.bits = 3; }},
      {"samples", [](AlgorithmParams& p) { p.samples = 3; }},
      {"weight", [](AlgorithmParams& p) { p.weight = 7; }},  // eq. 7 needs camera planes: refused here
      {"seed", [](AlgorithmParams& p) { p.seed = 99; }},
  };
  for (const auto& info : algorithmNames()) {
    const std::string algo(info.name);
    const Outcome ref = run(algo, base, fs);
    ASSERT_FALSE(ref.refused) << algo;
    const std::vector<std::string> ignored = ignoredSettings(algo);
    for (const auto& [name, change] : changes) {
      AlgorithmParams p = base;
      change(p);
      const bool is_ignored = std::find(ignored.begin(), ignored.end(), name) != ignored.end();
      const Outcome o = run(algo, p, fs);
      if (is_ignored)
        EXPECT_TRUE(same(ref, o)) << algo << " is declared to ignore " << name << " but it changed the result";
      else
        EXPECT_FALSE(same(ref, o)) << algo << " is declared to use " << name << " but nothing changed";
    }
  }
}

TEST(AlgorithmSettings, UnknownAlgorithmIsAnErrorNamingTheValidOnes) {
  try {
    algorithmSettings("nosuch");
    FAIL() << "no exception";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("unknown OIT algorithm 'nosuch' (valid: abuffer, alpha, mlab"),
              std::string::npos)
        << e.what();
  }
  // The A-buffer under test stores its nodes' colour in the format (rgba8t8z32: the published 12-byte node).
  EXPECT_EQ(ignoredSettings("abuffer"), (std::vector<std::string>{"layers", "bits", "samples", "weight", "seed"}));
  EXPECT_EQ(ignoredSettings("mlab"), (std::vector<std::string>{"bits", "samples", "weight", "seed"}));
}

}  // namespace
