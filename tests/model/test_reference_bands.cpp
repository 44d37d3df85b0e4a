// FunctionalRenderer::renderInBands: the A-buffer reference in bands that fit
// a memory limit gives the same image, bit for bit, and the same counts as
// render(), whatever the number of bands; the band file leaves nothing behind.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <cstring>
#include <filesystem>

#include "AlgoTestUtil.hpp"

using namespace oit;
using namespace oit::model;
using namespace oit::model::testutil;

namespace {

// A fresh folder for the band file, removed with its contents.
struct SpillDir {
  std::filesystem::path path;
  SpillDir() {
    std::string t = (std::filesystem::temp_directory_path() / "oitsim-bands-XXXXXX").string();
    if (!::mkdtemp(t.data())) throw std::runtime_error("mkdtemp");
    path = t;
  }
  ~SpillDir() { std::filesystem::remove_all(path); }
  bool empty() const { return std::filesystem::is_empty(path); }
};

bool sameImage(const Image& a, const Image& b) {
  return a.sameSize(b) && std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(Rgb)) == 0;
}

// 24 x 16, up to 9 transparent fragments per pixel, opaque fragments over a
// third of the pixels (some transparent ones culled), runs of equal depths.
std::vector<Fragment> scene() {
  auto fs = randomScene(24, 16, 9, 5);
  for (size_t i = 0; i < fs.size(); i += 13) fs[i].z = 0.5f;  // ties: the later one is in front
  for (uint16_t i = 0; i < 128; ++i)
    fs.insert(fs.begin() + 7 * i, frag(uint16_t(i * 3 % 24), uint16_t(i * 3 / 24), 0.3f + 0.003f * i, 0.2f, 0.3f,
                                       0.4f, 1, kOpaqueDraw));
  return fs;
}

}  // namespace

// Pixel needs: 4 B of head each, 24 B per fragment: {28, 28, 4, 52, 4}.
// Limit 60: 28 + 28 + 4 = 60 fits, + 52 does not -> bands {0, 1, 2} and {3, 4}.
// Limit 52: 28 + 28 > 52 -> {0}, {1, 2} (32), {3} (52), {4}.
TEST(ReferenceBands, PlanFillsEachBandUpToTheLimit) {
  EXPECT_EQ(planBands({1, 1, 0, 2, 0}, 5, 4, 24, 60), (std::vector<uint64_t>{0, 3}));
  EXPECT_EQ(planBands({1, 1, 0, 2, 0}, 5, 4, 24, 1000), (std::vector<uint64_t>{0}));
  EXPECT_EQ(planBands({1, 1, 0, 2, 0}, 5, 4, 24, 52), (std::vector<uint64_t>{0, 1, 3, 4}));
  try {
    planBands({1, 1, 0, 2, 0}, 5, 4, 24, 51);
    ADD_FAILURE() << "a pixel over the limit was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_STREQ(e.what(),
                 "pixel (3, 0) alone holds 2 fragments for the reference, 52 bytes, more than the 51 bytes one band "
                 "may take");
  }
}

TEST(ReferenceBands, AnyNumberOfBandsGivesTheImageOfOneRender) {
  const std::vector<Fragment> fs = scene();
  const TraceHeader hd = header(24, 16);
  RenderOptions opt;
  opt.clear_colour = {0.1f, 0.2f, 0.3f};
  MemorySource whole(hd, fs, 7);
  auto ref = makeAlgorithm("abuffer", {});
  const RenderResult want = FunctionalRenderer(opt).render(whole, *ref);
  ASSERT_GT(want.counts.culled, 0u);
  // All in one band (the fragment count shows it fits), one band after a
  // count, a few bands, and bands of a pixel or two.
  const uint64_t all = 24 * 16 * 4 + fs.size() * 24;
  for (uint64_t limit : {all, all - 1, uint64_t(2000), uint64_t(300)}) {
    SpillDir dir;
    MemorySource src(hd, fs, 7);
    auto algo = makeAlgorithm("abuffer", {});
    const BandedRender got = FunctionalRenderer(opt).renderInBands(src, *algo, {limit, dir.path.string()});
    EXPECT_TRUE(sameImage(got.result.image, want.image)) << "limit " << limit << ", " << got.bands << " bands";
    EXPECT_EQ(got.result.counts.fragments_in, want.counts.fragments_in);
    EXPECT_EQ(got.result.counts.opaque, want.counts.opaque);
    EXPECT_EQ(got.result.counts.culled, want.counts.culled);
    EXPECT_EQ(got.result.counts.stored, want.counts.stored);
    EXPECT_EQ(got.result.counts.bytes_written, want.counts.bytes_written);
    EXPECT_TRUE(got.result.counts.balanced());
    EXPECT_LE(got.largest_band_bytes, limit);
    EXPECT_TRUE(dir.empty()) << "the band file has no name: nothing is left in the folder";
    if (limit == all) {
      EXPECT_EQ(got.bands, 1u);
      EXPECT_EQ(got.spill_bytes, 0u);
      EXPECT_EQ(got.result.counts.source_passes, 2u);  // opaque, then the render
    } else if (limit == all - 1) {
      // The count of fragments that reach the A-buffer (culled ones do not) fits.
      EXPECT_EQ(got.bands, 1u);
      EXPECT_EQ(got.result.counts.source_passes, 3u);  // opaque, count, render
    } else {
      EXPECT_GT(got.bands, limit == 300 ? 20u : 2u);
      EXPECT_EQ(got.spill_bytes, want.counts.stored * sizeof(Fragment));
      EXPECT_EQ(got.result.counts.source_passes, 3u);  // opaque, count, band file
    }
  }
}

TEST(ReferenceBands, APixelOverTheLimitIsRefusedBeforeTheBands) {
  const std::vector<Fragment> fs = randomScene(4, 4, 20, 3, 20);  // 20 fragments at every pixel: 484 B
  SpillDir dir;
  MemorySource src(header(4, 4), fs, 7);
  auto algo = makeAlgorithm("abuffer", {});
  try {
    FunctionalRenderer().renderInBands(src, *algo, {483, dir.path.string()});
    ADD_FAILURE() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("alone holds 20 fragments for the reference, 484 bytes"), std::string::npos)
        << e.what();
  }
  EXPECT_TRUE(dir.empty());
}
