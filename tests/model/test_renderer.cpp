// FunctionalRenderer conventions: opaque pre-pass, culling, clear colour,
// counts, passes, progress, errors.
#include <gtest/gtest.h>

#include <stdexcept>

#include "AlgoTestUtil.hpp"

using namespace oit;
using namespace oit::model;
using namespace oit::model::testutil;

TEST(Renderer, OpaqueDepthLessFirstWinsOnTies) {
  std::vector<Fragment> fs = {
      frag(0, 0, 0.5f, 0, 1, 0, 1, kOpaqueDraw), frag(0, 0, 0.5f, 1, 0, 0, 1, kOpaqueDraw),  // tie: green
      frag(1, 0, 0.6f, 1, 0, 0, 1, kOpaqueDraw), frag(1, 0, 0.4f, 0, 0, 1, 1, kOpaqueDraw),  // nearer: blue
  };
  RenderOptions opt;
  opt.clear_colour = {0.5f, 0.5f, 0.5f};
  const RenderResult r = render("mlab", {}, fs, 3, 1, opt);
  EXPECT_EQ(r.image.pixels[0], (Rgb{0, 1, 0}));
  EXPECT_EQ(r.image.pixels[1], (Rgb{0, 0, 1}));
  EXPECT_EQ(r.image.pixels[2], (Rgb{0.5f, 0.5f, 0.5f}));  // nothing landed: clear colour
  EXPECT_EQ(r.counts.opaque, 4u);
  EXPECT_EQ(r.counts.fragments_in, 4u);
}

TEST(Renderer, TransparentAtOrBehindFinalOpaqueDepthIsCulled) {
  // Grey opaque at z .5, submitted last: culling uses the final depth.
  std::vector<Fragment> fs = {
      frag(0, 0, 0.7f, 1, 0, 0, 0.5f),                 // behind: culled
      frag(0, 0, 0.5f, 0, 1, 0, 0.5f),                 // at: culled
      frag(0, 0, 0.25f, 0, 0, 1, 0.5f),                // in front
      frag(0, 0, 0.5f, 0.5f, 0.5f, 0.5f, 1, kOpaqueDraw),
      frag(1, 0, 0.9f, 1, 0, 0, 0.5f),                 // no opaque here: kept
  };
  for (const std::string name : {"abuffer", "mlab", "adaptive", "wboit", "alpha"}) {
    const RenderResult r = render(name, {}, fs, 2, 1);
    EXPECT_EQ(r.image.pixels[0], (Rgb{0.25f, 0.25f, 0.75f})) << name;  // .5 blue + .5 grey
    EXPECT_EQ(r.image.pixels[1], (Rgb{0.5f, 0, 0})) << name;           // over black clear colour
    EXPECT_EQ(r.counts.fragments_in, 5u);
    EXPECT_EQ(r.counts.opaque, 1u);
    EXPECT_EQ(r.counts.culled, 2u);
    EXPECT_EQ(r.counts.stored, 2u);
    EXPECT_TRUE(r.counts.balanced());
  }
}

TEST(Renderer, CountsBalanceOnAMixedScene) {
  auto fs = randomScene(10, 10, 8, 21);
  // Opaque fragments over half the pixels, some zero-alpha transparent ones.
  std::vector<float> depth(100, 2.0f);
  for (uint16_t i = 0; i < 50; ++i) {
    const float z = 0.3f + 0.01f * i;
    fs.insert(fs.begin() + 3 * i, frag(i % 10, i / 10, z, 0.2f, 0.3f, 0.4f, 1, kOpaqueDraw));
    depth[i] = z;
  }
  for (size_t i = 0; i < fs.size(); i += 9)
    if (fs[i].draw != kOpaqueDraw) fs[i].a = 0.0f;
  uint64_t culled = 0, opaque = 0;
  for (const Fragment& f : fs) {
    if (f.draw == kOpaqueDraw) ++opaque;
    else if (f.z >= depth[f.y * 10 + f.x]) ++culled;
  }
  for (const AlgorithmInfo& info : algorithmNames()) {
    const RenderResult r = render(info.name, layers(3), fs, 10, 10);
    EXPECT_EQ(r.counts.fragments_in, fs.size()) << info.name;
    EXPECT_EQ(r.counts.opaque, opaque) << info.name;
    EXPECT_EQ(r.counts.culled, culled) << info.name;
    EXPECT_TRUE(r.counts.balanced()) << info.name;
    EXPECT_TRUE(allFinite(r.image)) << info.name;
  }
}

TEST(Renderer, MultiPassAlgorithmsReplayTheSource) {
  std::vector<Fragment> fs = {frag(0, 0, 0.5f, 1, 0, 0, 0.5f)};
  {
    MemorySource src(header(1, 1), fs);
    auto a = makeAlgorithm("adaptive", {});
    const RenderResult r = FunctionalRenderer().render(src, *a);
    EXPECT_EQ(r.counts.source_passes, 3u);  // opaque pre-pass (table has an opaque draw) + 2
    EXPECT_EQ(src.rewinds(), 3u);
    EXPECT_EQ(r.image.pixels[0], (Rgb{0.5f, 0, 0}));
  }
  TraceHeader h = header(1, 1);
  h.draws = {{kTranspDraw, DrawClass::Transparent, "glass"}};
  MemorySource src(h, fs);
  auto a = makeAlgorithm("mlab", {});
  EXPECT_EQ(FunctionalRenderer().render(src, *a).counts.source_passes, 1u);  // no opaque pre-pass
}

TEST(Renderer, ProgressReportsEveryPass) {
  const auto fs = randomScene(5, 5, 8, 2);
  std::vector<RenderProgress> seen;
  RenderOptions opt;
  opt.progress_every = 10;
  opt.progress = [&](const RenderProgress& p) { seen.push_back(p); };
  render("adaptive", {}, fs, 5, 5, opt);
  ASSERT_GE(seen.size(), 3u);
  EXPECT_EQ(seen.front().pass, 0u);
  EXPECT_EQ(seen.front().what, "opaque");
  EXPECT_EQ(seen.back().pass, 2u);
  EXPECT_EQ(seen.back().passes, 3u);
  EXPECT_EQ(seen.back().fragments_done, fs.size());
  EXPECT_EQ(seen.back().fragments_total, fs.size());
  EXPECT_EQ(seen.back().what, "composite");
  EXPECT_GT(seen.size(), 2 * fs.size() / 10 / 2);  // intermediate reports too
}

TEST(Renderer, RejectsFragmentsOutsideTheFrameOrOfUnknownDraws) {
  EXPECT_THROW(render("mlab", {}, {frag(4, 0, 0.5f, 1, 1, 1, 1)}, 4, 4), std::runtime_error);
  EXPECT_THROW(render("mlab", {}, {frag(0, 0, 0.5f, 1, 1, 1, 1, 77)}, 4, 4), std::runtime_error);
  EXPECT_THROW(render("mlab", {}, {frag(0, 0, 0.5f, 1, 1, 1, 1, 1u << 25)}, 4, 4), std::runtime_error);
}

TEST(Renderer, BandwidthCountsFollowOutcomes) {
  // mlab k = 2 fp32 (40 B/pixel): 3 inserts read 40 B each and write 40 B each.
  const RenderResult r = render("mlab", layers(2),
                                {frag(0, 0, 0.2f, 1, 0, 0, 0.5f), frag(0, 0, 0.8f, 0, 1, 0, 0.5f),
                                 frag(0, 0, 0.5f, 0, 0, 1, 0.5f), frag(0, 0, 0.1f, 0, 0, 1, 0.0f)},
                                1, 1);
  EXPECT_EQ(r.counts.bytes_read, 4u * 40);
  EXPECT_EQ(r.counts.bytes_written, 3u * 40);  // the a = 0 insert writes nothing
  EXPECT_EQ(r.state_bytes, 40u);
}
