// Scene generators: the catalogue, headers, determinism per seed, stream validity,
// default sizes and each scene's stress property.
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <stdexcept>
#include <string>

#include "traces/gen/Mesh.hpp"
#include "traces/gen/Scenes.hpp"
#include "traces/test_gen_util.hpp"

namespace oit::gen {
namespace {

using oit::test::HashSink;
using oit::test::VectorSink;

const std::vector<std::string> kAllScenes = {"particles", "hair", "foliage", "glass", "mesh", "demo"};

bool bunnyInstalled() { return fileReadable(findNamedMesh("bunny")->path); }
// The scenes that draw the glmark2 bunny, when it is not installed.
bool bunnyMissingFor(const std::string& scene) { return (scene == "mesh" || scene == "demo") && !bunnyInstalled(); }

// Scenes that need the glmark2 bunny are skipped (with a reason) without it.
#define SKIP_WITHOUT_BUNNY(scene)                                                  \
  if (bunnyMissingFor(scene))                                                       \
  GTEST_SKIP() << "glmark2-data is not installed (apt-get install glmark2-data)"

SceneOptions small(uint32_t w = 320, uint32_t h = 180) {
  SceneOptions o;
  o.width = w;
  o.height = h;
  return o;
}

std::string invalidArgument(const std::string& scene, const SceneOptions& o) {
  try {
    SceneGenerator g(scene, o);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(SceneCatalog, ListsEveryScene) {
  std::vector<std::string> names;
  for (const SceneInfo& s : sceneCatalog()) {
    names.push_back(s.name);
    EXPECT_FALSE(s.description.empty()) << s.name;
    EXPECT_EQ(s.default_count == 0, s.count_unit.empty()) << s.name;
  }
  EXPECT_EQ(names, kAllScenes);
}

TEST(SceneOptionsCheck, UnknownSceneListsTheValidOnes) {
  EXPECT_EQ(invalidArgument("smoke", small()),
            "unknown scene 'smoke'; valid scenes: particles, hair, foliage, glass, mesh, demo");
}

TEST(SceneOptionsCheck, OutOfRangeOptionsAreRejected) {
  SceneOptions o = small();
  o.elevation_deg = 95;
  EXPECT_EQ(invalidArgument("glass", o), "elevation 95 is outside -89..89 degrees");
  o = small();
  o.density = 0;
  EXPECT_EQ(invalidArgument("glass", o), "density 0 must be a positive number");
  o = small();
  o.alpha = 1.5f;
  EXPECT_EQ(invalidArgument("glass", o), "alpha 1.5 is outside [0, 1]");
  o = small();
  o.fov_deg = 0.5;
  EXPECT_EQ(invalidArgument("glass", o), "field of view 0.5 is outside (1, 170) degrees");
  o = small();
  o.colour = std::array<float, 3>{0.5f, 2.0f, 0.0f};
  EXPECT_EQ(invalidArgument("glass", o), "colour component 2 is outside [0, 1]");
  o = small(0, 10);
  EXPECT_EQ(invalidArgument("glass", o), "frame size 0x10 is outside 1..65536 per axis");
}

TEST(SceneHeader, DrawTablesCameraAndEncoding) {
  SceneOptions o = small();
  o.encoding = ColourEncoding::Unorm8;
  TraceHeader h = sceneHeader("particles", o);
  EXPECT_EQ(h.width, 320u);
  EXPECT_EQ(h.height, 180u);
  EXPECT_EQ(h.encoding, ColourEncoding::Unorm8);
  ASSERT_EQ(h.draws.size(), 1u);
  EXPECT_EQ(h.draws[0].id, 0u);
  EXPECT_EQ(h.draws[0].name, "particles");
  EXPECT_EQ(h.draws[0].cls, DrawClass::Transparent);
  ASSERT_TRUE(h.camera.has_value());
  EXPECT_GT(h.camera->near_plane, 0.0f);
  EXPECT_GT(h.camera->far_plane, h.camera->near_plane);

  o.backdrop = true;
  h = sceneHeader("hair", o);
  ASSERT_EQ(h.draws.size(), 3u);
  const std::pair<const char*, DrawClass> want[] = {
      {"backdrop", DrawClass::Opaque}, {"pillar", DrawClass::Opaque}, {"hair", DrawClass::Transparent}};
  for (uint32_t i = 0; i < 3; ++i) {
    EXPECT_EQ(h.draws[i].id, i);
    EXPECT_EQ(h.draws[i].name, want[i].first);
    EXPECT_EQ(h.draws[i].cls, want[i].second);
  }
}

TEST(SceneHeader, DemoIsBackdropBunnyAndParticles) {
  SKIP_WITHOUT_BUNNY(std::string("demo"));
  TraceHeader h = sceneHeader("demo", small());
  std::vector<std::string> names;
  for (const DrawInfo& d : h.draws) names.push_back(d.name);
  EXPECT_EQ(names, (std::vector<std::string>{"backdrop", "pillar", "bunny", "particles"}));
  EXPECT_EQ(h.draws[2].cls, DrawClass::Transparent);
}

// Every fragment inside the frame, in range, and in submission order (draw, then
// primitive); the result's counts agree with the stream.
void checkStream(const std::string& scene, const SceneOptions& o) {
  SceneGenerator g(scene, o);
  VectorSink sink;
  GenResult r = g.generate(sink);
  ASSERT_EQ(r.fragments, sink.fragments.size());
  ASSERT_EQ(r.draws, g.header().draws.size());
  std::vector<uint64_t> per_draw(r.draws);
  uint32_t draw = 0, prim = 0;
  for (const Fragment& f : sink.fragments) {
    ASSERT_LT(f.x, o.width);
    ASSERT_LT(f.y, o.height);
    ASSERT_TRUE(f.z >= 0 && f.z <= 1) << f.z;
    for (float c : {f.r, f.g, f.b, f.a}) ASSERT_TRUE(c >= 0 && c <= 1) << c;
    ASSERT_LT(f.draw, r.draws);
    ASSERT_GE(f.draw, draw) << "draws in submission order";
    if (f.draw != draw) prim = 0;
    ASSERT_GE(f.prim, prim) << "primitives in submission order";
    ASSERT_LT(f.prim, r.primitives_per_draw[f.draw]);
    draw = f.draw, prim = f.prim;
    ++per_draw[f.draw];
    if (g.header().draws[f.draw].cls == DrawClass::Opaque) {
      ASSERT_EQ(f.a, 1.0f);
    }
  }
  EXPECT_EQ(per_draw, r.fragments_per_draw);
  uint64_t prims = 0;
  for (uint64_t p : r.primitives_per_draw) prims += p;
  EXPECT_EQ(prims, r.primitives);
}

// The mesh and demo scenes need glmark2-data's bunny: without it they are not
// checked, and the test says so as a skip (after checking every other scene;
// a failure before still fails the test) so the lost coverage shows.
void skipScenesWithoutBunny(const std::vector<std::string>& scenes) {
  if (scenes.empty()) return;
  std::string names;
  for (const auto& s : scenes) names += (names.empty() ? "" : ", ") + s;
  ::testing::Test::RecordProperty("scenes_not_checked", names);
  GTEST_SKIP() << "scenes " << names << " not checked: glmark2-data (bunny) absent (the other scenes were checked)";
}

TEST(SceneStreams, EveryScenePlainAndOverTheBackdropIsAValidOrderedStream) {
  std::vector<std::string> without_bunny;  // scenes not checked (reported as a skip below)
  for (const std::string& scene : kAllScenes) {
    if (bunnyMissingFor(scene)) {
      without_bunny.push_back(scene);
      continue;
    }
    SCOPED_TRACE(scene);
    SceneOptions o = small(160, 90);
    checkStream(scene, o);
    o.backdrop = true;
    checkStream(scene, o);
  }
  skipScenesWithoutBunny(without_bunny);
}

struct RunStats {
  uint64_t hash, count;
  uint32_t max_depth;
};
RunStats generateCounted(const std::string& scene, const SceneOptions& o) {
  HashSink sink(o.width, o.height);
  GenResult r = generateScene(scene, o, sink);
  EXPECT_EQ(sink.outsideFrame(), 0u);
  EXPECT_EQ(r.fragments, sink.written());
  return {sink.hash(), sink.written(), sink.maxDepthComplexity()};
}

TEST(SceneDeterminism, SameSeedSameStreamOtherSeedOtherStream) {
  std::vector<std::string> without_bunny;  // scenes not checked (reported as a skip below)
  for (const std::string& scene : kAllScenes) {
    if (bunnyMissingFor(scene)) {
      without_bunny.push_back(scene);
      continue;
    }
    SCOPED_TRACE(scene);
    SceneOptions o = small();
    o.backdrop = true;
    const RunStats a = generateCounted(scene, o), b = generateCounted(scene, o);
    EXPECT_GT(a.count, 1000u);
    EXPECT_EQ(a.hash, b.hash);
    EXPECT_EQ(a.count, b.count);
    o.seed = 2;
    const RunStats c = generateCounted(scene, o);
    if (scene == "mesh") {
      EXPECT_EQ(c.hash, a.hash) << "a mesh and a backdrop involve no randomness";
    } else {
      EXPECT_NE(c.hash, a.hash);
    }
  }
  skipScenesWithoutBunny(without_bunny);
}

// The same stream from every compiler: CI runs this test in the g++ Release
// build and in the clang sanitizer build, so a draw whose order the compiler
// picks (two draws in one call's arguments or in the operands of one +) fails
// one of them. The fingerprints are of the streams the committed traces and
// figures were made with (g++); they changed only when a scene's content did.
// Before the draws were sequenced (SceneContent.cpp), clang produced other
// particles, hair, foliage, glass and demo streams than g++.
TEST(SceneDeterminism, SameStreamFromEveryCompiler) {
  const std::map<std::string, uint64_t> fingerprint = {
      {"particles", 0xa11b7771da396506ull}, {"hair", 0x3c9639289050b067ull}, {"foliage", 0xe4de2d7e56724a7aull},
      {"glass", 0xdd26dd5ac44a5d95ull},     {"mesh", 0x1f5fa4d42c3b09c0ull}, {"demo", 0x7c463b51ca689500ull},
  };
  std::vector<std::string> without_bunny;
  for (const std::string& scene : kAllScenes) {
    if (bunnyMissingFor(scene)) {
      without_bunny.push_back(scene);
      continue;
    }
    SceneOptions o = small();
    o.backdrop = true;
    const RunStats a = generateCounted(scene, o);
    EXPECT_EQ(a.hash, fingerprint.at(scene)) << scene << ": 0x" << std::hex << a.hash;
  }
  skipScenesWithoutBunny(without_bunny);
}

TEST(SceneDeterminism, GeneratingTwiceFromOneGeneratorRepeatsTheStream) {
  SceneGenerator g("foliage", small());
  HashSink s1(320, 180), s2(320, 180);
  g.generate(s1);
  g.generate(s2);
  EXPECT_EQ(s1.hash(), s2.hash());
  EXPECT_EQ(s1.written(), s2.written());
}

TEST(SceneSizes, DefaultsAt1280x720GiveHalfToFourMillionFragments) {
  std::vector<std::string> without_bunny;  // scenes not checked (reported as a skip below)
  for (const std::string& scene : kAllScenes) {
    if (bunnyMissingFor(scene)) {
      without_bunny.push_back(scene);
      continue;
    }
    SCOPED_TRACE(scene);
    const RunStats r = generateCounted(scene, SceneOptions{});
    EXPECT_GE(r.count, 500'000u);
    EXPECT_LE(r.count, 4'000'000u);
  }
  skipScenesWithoutBunny(without_bunny);
}

TEST(SceneSizes, CountAndDensityScaleTheElements) {
  SceneOptions o = small();
  o.count = 10;
  VectorSink s1;
  EXPECT_EQ(generateScene("particles", o, s1).primitives, 20u);  // two triangles a quad
  o.density = 2.5;
  VectorSink s2;
  EXPECT_EQ(generateScene("particles", o, s2).primitives, 50u);
  o.count = 0;
  o.density = 1;
  VectorSink s3;
  EXPECT_EQ(generateScene("glass", o, s3).primitives, 12u);  // 6 panes
  o.count = 3;
  VectorSink s4;
  EXPECT_EQ(generateScene("hair", o, s4).primitives, 3u * 32u * 2u);  // 32 segments a strand
}

TEST(SceneProgress, ReportsIncreasingFractionsEndingAtOne) {
  std::vector<double> seen;
  VectorSink sink;
  generateScene("glass", small(), sink, [&](double f) { seen.push_back(f); });
  ASSERT_FALSE(seen.empty());
  EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end()));
  EXPECT_GT(seen.front(), 0.0);
  EXPECT_EQ(seen.back(), 1.0);
}

TEST(SceneStress, HairReachesDepthComplexityInTheHundreds) {
  const RunStats r = generateCounted("hair", small(320, 180));
  EXPECT_GE(r.max_depth, 100u);
}

TEST(SceneStress, FoliageAlphaIsExactlyZeroOutsideExactlyOneInTheCoreAndGradedBetween) {
  VectorSink sink;
  generateScene("foliage", small(), sink);
  uint64_t zero = 0, one = 0, between = 0;
  for (const Fragment& f : sink.fragments) (f.a == 0 ? zero : f.a == 1 ? one : between)++;
  const double n = static_cast<double>(sink.fragments.size());
  EXPECT_GT(zero / n, 0.1);
  EXPECT_GT(one / n, 0.1);
  EXPECT_GT(between / n, 0.02);
}

TEST(SceneStress, GlassPanesAreSubmittedOutOfDepthOrder) {
  VectorSink sink;
  SceneOptions o = small();
  generateScene("glass", o, sink);
  // Mean window depth of each pane (two primitives) in submission order.
  std::map<uint32_t, std::pair<double, uint64_t>> pane;
  for (const Fragment& f : sink.fragments) {
    auto& [sum, n] = pane[f.prim / 2];
    sum += f.z, ++n;
  }
  ASSERT_EQ(pane.size(), 6u) << "every pane is visible";
  std::vector<double> depth;
  for (const auto& [id, sn] : pane) depth.push_back(sn.first / sn.second);
  EXPECT_FALSE(std::is_sorted(depth.begin(), depth.end())) << "not front to back";
  EXPECT_FALSE(std::is_sorted(depth.rbegin(), depth.rend())) << "not back to front";
  // Per pixel, later fragments land both in front of and behind earlier ones.
  std::vector<float> last(size_t{o.width} * o.height, -1.0f);
  uint64_t nearer = 0, farther = 0;
  for (const Fragment& f : sink.fragments) {
    float& l = last[size_t{f.y} * o.width + f.x];
    if (l >= 0) (f.z < l ? nearer : farther)++;
    l = f.z;
  }
  EXPECT_GT(nearer, 1000u);
  EXPECT_GT(farther, 1000u);
}

TEST(SceneStress, ParticleQuadsShareTheirDiagonalAndFadeToZero) {
  VectorSink sink;
  SceneOptions o = small();
  o.count = 300;
  o.alpha = 0.5f;
  generateScene("particles", o, sink);
  // The two triangles of a quad (primitives 2k and 2k+1) never cover a pixel twice.
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> seen;  // (quad, pixel) -> hits
  float max_alpha = 0;
  uint64_t zero = 0;
  for (const Fragment& f : sink.fragments) {
    const std::pair<uint32_t, uint32_t> key{f.prim / 2, uint32_t{f.y} * o.width + f.x};
    ASSERT_EQ(++seen[key], 1u);
    max_alpha = std::max(max_alpha, f.a);
    zero += f.a == 0;
  }
  EXPECT_LE(max_alpha, 0.5f);
  EXPECT_GT(max_alpha, 0.45f);
  EXPECT_GT(zero, 0u) << "corners outside the inscribed circle are transparent";
}

TEST(SceneBackdrop, WallAndFloorCoverEveryPixelOnceAndThePillarIsConvex) {
  for (const std::string scene : {"particles", "hair", "glass"}) {
    SCOPED_TRACE(scene);
    SceneOptions o = small(200, 120);
    o.backdrop = true;
    SceneGenerator g(scene, o);
    VectorSink sink;
    g.generate(sink);
    std::vector<int> wall(200 * 120), pillar(200 * 120);
    bool transparent_seen = false;
    for (const Fragment& f : sink.fragments) {
      const bool opaque = g.header().draws[f.draw].cls == DrawClass::Opaque;
      if (opaque) {
        ASSERT_FALSE(transparent_seen) << "opaque draws come first";
      }
      transparent_seen |= !opaque;
      if (f.draw == 0) ++wall[f.y * 200 + f.x];
      if (f.draw == 1) ++pillar[f.y * 200 + f.x];
    }
    for (int c : wall) ASSERT_EQ(c, 1);
    EXPECT_GT(std::count(pillar.begin(), pillar.end(), 1), 200);
    EXPECT_EQ(std::count_if(pillar.begin(), pillar.end(), [](int c) { return c > 1; }), 0);
  }
}

TEST(SceneMesh, ColourAlphaAndShadingOptions) {
  if (!bunnyInstalled()) GTEST_SKIP() << "glmark2-data is not installed";
  SceneOptions o = small();
  o.colour = std::array<float, 3>{0.25f, 0.5f, 1.0f};
  o.alpha = 0.125f;
  o.shading = Shading::Constant;
  VectorSink flat;
  generateScene("mesh", o, flat);
  ASSERT_GT(flat.fragments.size(), 10000u);
  for (const Fragment& f : flat.fragments) {
    ASSERT_EQ(f.r, 0.25f);
    ASSERT_EQ(f.g, 0.5f);
    ASSERT_EQ(f.b, 1.0f);
    ASSERT_EQ(f.a, 0.125f);
  }
  o.shading = Shading::Lambert;
  VectorSink lit;
  generateScene("mesh", o, lit);
  ASSERT_EQ(lit.fragments.size(), flat.fragments.size()) << "shading changes colour only";
  float lo = 1, hi = 0;
  for (const Fragment& f : lit.fragments) {
    lo = std::min(lo, f.b), hi = std::max(hi, f.b);
    ASSERT_EQ(f.a, 0.125f);
  }
  EXPECT_LT(lo, 0.5f);
  EXPECT_GT(hi, 0.9f);
}

TEST(SceneMesh, LoadsAMeshFileAndNamesTheDrawAfterIt) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("oitsim_gen_" + std::to_string(::getpid()) + "_tetra.obj");
  std::ofstream(path) << "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  SceneOptions o = small();
  o.mesh = path.string();
  SceneGenerator g("mesh", o);
  EXPECT_EQ(g.header().draws.at(0).name, "oitsim_gen_" + std::to_string(::getpid()) + "_tetra");
  VectorSink sink;
  EXPECT_EQ(g.generate(sink).primitives, 4u);
  EXPECT_GT(sink.fragments.size(), 5000u) << "auto-fit fills the frame";
  std::filesystem::remove(path);

  o.mesh = "no-such-mesh";
  EXPECT_THROW(SceneGenerator("mesh", o), std::runtime_error);
}

// fp32 squares of coordinates beyond about 1e19 overflow: the bounding sphere
// came out infinite, the scale 0 and the trace empty (rc 0). The fit is
// scale-free now, and a mesh that fp32 cannot frame at all is an error.
TEST(SceneMesh, HugeAndTinyCoordinatesAreFramedLikeUnitOnes) {
  const auto path = std::filesystem::temp_directory_path() /
                    ("oitsim_gen_" + std::to_string(::getpid()) + "_scaled_tri.obj");
  auto fragmentsAt = [&](const std::string& s) {
    std::ofstream(path) << "v 0 0 0\nv " << s << " 0 0\nv 0 " << s << " 0\nf 1 2 3\n";
    SceneOptions o = small();
    o.mesh = path.string();
    VectorSink sink;
    SceneGenerator("mesh", o).generate(sink);
    return sink.fragments.size();
  };
  const size_t unit = fragmentsAt("1");
  ASSERT_GT(unit, 500u);
  for (const char* s : {"1e19", "1e20", "1e30", "1e-25"}) {
    SCOPED_TRACE(s);
    const size_t n = fragmentsAt(s);
    EXPECT_GE(n, unit - unit / 100);
    EXPECT_LE(n, unit + unit / 100);
  }
  std::ofstream(path) << "v -3e38 -3e38 -3e38\nv 3e38 3e38 3e38\nv 0 3e38 0\nf 1 2 3\n";
  SceneOptions o = small();
  o.mesh = path.string();
  try {
    VectorSink sink;
    SceneGenerator("mesh", o).generate(sink);
    ADD_FAILURE() << "expected an error";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), "mesh '" + path.string() +
                                         "' cannot be framed: its bounding-sphere radius inf does not scale to a "
                                         "finite fp32 placement; rescale its coordinates");
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace oit::gen
