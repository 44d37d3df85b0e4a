// Headless GL capture: the trace must reproduce GL's own blended framebuffer and
// fragment counts, be deterministic, and agree with oitsim's own rasterizer.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <tuple>

#include <sys/wait.h>

#include <fmt/format.h>

#include "traces/TraceIO.hpp"
#include "traces/capture/GlCapture.hpp"
#include "apps/CaptureVerify.hpp"
#include "capture/CaptureTestUtil.hpp"
#include "traces/gen/Mesh.hpp"
#include "traces/gen/Scenes.hpp"

namespace oit::capture {
namespace {

namespace fs = std::filesystem;

using test_util::VectorSink;

// Skips only when EGL/GL truly cannot start here (or the mesh is not installed).
class Capture : public ::testing::Test {
 protected:
  void SetUp() override {
    static const std::optional<std::string> reason = glUnavailableReason();
    if (reason) GTEST_SKIP() << "EGL + OpenGL 4.5 core unavailable: " << *reason;
    dir_ = fs::path(OITSIM_BINARY_DIR) / "test-capture" /
           ::testing::UnitTest::GetInstance()->current_test_info()->name();
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  static void requireMesh(const std::string& name) {
    const gen::NamedMesh* m = gen::findNamedMesh(name);
    ASSERT_NE(m, nullptr);
    if (!gen::fileReadable(m->path)) GTEST_SKIP() << m->path << " missing: " << gen::meshInstallHint(*m);
  }
  static CaptureOptions small(const std::string& mesh = "bunny") {
    CaptureOptions o;
    o.width = 160;
    o.height = 120;
    o.meshes = {mesh};
    return o;
  }
  // The fragments Mesa records for o, and gen's for the same mesh scene
  // (size, mesh, azimuth, backdrop).
  static std::pair<std::vector<Fragment>, std::vector<Fragment>> mesaAndGen(const CaptureOptions& o) {
    Capturer cap(o);
    VectorSink mesa;
    cap.capture(mesa);
    gen::SceneOptions g;
    g.width = o.width;
    g.height = o.height;
    g.mesh = o.meshes.at(0);
    g.azimuth_deg = o.azimuth_deg;
    g.backdrop = o.backdrop;
    VectorSink ours;
    gen::generateScene("mesh", g, ours);
    return {std::move(mesa.fragments), std::move(ours.fragments)};
  }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  static std::string slurp(const std::string& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }
  // Captures frame `az_off` of cap into a file; returns the stats.
  CaptureStats captureTo(Capturer& cap, const std::string& file, double az_off = 0) {
    auto w = createTraceWriter(file, cap.header());
    CaptureStats st = cap.capture(*w, az_off);
    w->commit();
    return st;
  }
  fs::path dir_;
};

TEST_F(Capture, ReplayReproducesGlBlendAndCountsExactly) {
  requireMesh("bunny");
  Capturer cap(small());
  EXPECT_NE(cap.renderer(), "");
  const std::string file = path("bunny.oitt");
  const CaptureStats st = captureTo(cap, file);
  EXPECT_EQ(st.triangles, 69666u);
  // A bunny filling a 160x120 view: thousands of fragments, depth complexity > 1.
  EXPECT_GT(st.fragments, 10000u);
  const GlReference ref = cap.reference();
  const VerifyResult v = verifyTrace(file, ref);
  EXPECT_EQ(v.fragments, st.fragments);
  EXPECT_EQ(v.channels_compared, 3u * 160 * 120);
  // Same products and sums in the same order from a zero start: bit-exact.
  EXPECT_EQ(v.channels_differing, 0u) << v.first_difference;
  EXPECT_EQ(v.count_pixels_differing, 0u) << v.first_difference;
  EXPECT_FALSE(v.opaque_draws);
  EXPECT_TRUE(v.passes());
  // The check can fail: a non-black GL image and a count that is not all ones.
  double sum = 0, max_count = 0;
  for (size_t p = 0; p < ref.count.size(); ++p) sum += ref.rgba[4 * p], max_count = std::max(max_count, double(ref.count[p]));
  EXPECT_GT(sum, 100.0);
  EXPECT_GE(max_count, 4.0);
}

TEST_F(Capture, BackdropReplayWithinOneUlpPerBlendStep) {
  requireMesh("bunny");
  CaptureOptions o = small();
  o.backdrop = true;
  Capturer cap(o);
  ASSERT_EQ(cap.header().draws.size(), 3u);
  EXPECT_EQ(cap.header().draws[0].cls, DrawClass::Opaque);
  EXPECT_EQ(cap.header().draws[2].name, "bunny");
  const std::string file = path("backdrop.oitt");
  const CaptureStats st = captureTo(cap, file);
  EXPECT_EQ(st.fragments_per_draw[0] + st.fragments_per_draw[1] + st.fragments_per_draw[2], st.fragments);
  EXPECT_GE(st.fragments_per_draw[0], 160u * 120 * 9 / 10);  // the wall and floor fill the view
  const VerifyResult v = verifyTrace(file, cap.reference());
  EXPECT_EQ(v.count_pixels_differing, 0u) << v.first_difference;
  // Over an opaque background the model resolves A + T * bg once, while GL blends
  // into bg at every step: the same value with a different rounding sequence
  // (measured: 6,722 of 57,600 channels differ, by at most 2 ulp = 1.2e-7). Bound:
  // 8 ulp, 1e-6, still far below any real blending or ordering error (>= 1e-3).
  EXPECT_GT(v.channels_differing, 0u);  // the bound is needed: exact would be news
  EXPECT_LE(v.max_abs, 1e-6) << v.first_difference;
  EXPECT_LE(v.max_ulps, 8u) << v.first_difference;
  EXPECT_TRUE(v.opaque_draws);
  EXPECT_TRUE(v.passes());
  std::printf("backdrop: %llu of %llu channels differ, max %u ulp, %.3g abs\n",
              static_cast<unsigned long long>(v.channels_differing),
              static_cast<unsigned long long>(v.channels_compared), v.max_ulps, v.max_abs);
}

TEST_F(Capture, CapturesAreByteIdenticalAndSplittingChangesNothing) {
  requireMesh("bunny");
  Capturer cap(small());
  const CaptureStats a = captureTo(cap, path("a.oitt"));
  const CaptureStats b = captureTo(cap, path("b.oitt"));
  EXPECT_EQ(a.gl_draws, 1u);
  EXPECT_EQ(a.gl_redraws, 0u);
  CaptureOptions o = small();
  o.max_records_per_draw = 3000;  // forces many draw calls, each re-issued in halves
  Capturer split(o);
  const CaptureStats c = captureTo(split, path("c.oitt"));
  EXPECT_GT(c.gl_draws, a.fragments / 3000);
  EXPECT_GT(c.gl_redraws, 0u);
  EXPECT_EQ(a.fragments, b.fragments);
  EXPECT_EQ(a.fragments, c.fragments);
  const std::string bytes = slurp(path("a.oitt"));
  EXPECT_EQ(bytes.size(), 64u + 64u + 32u * a.fragments);
  EXPECT_TRUE(bytes == slurp(path("b.oitt")));
  EXPECT_TRUE(bytes == slurp(path("c.oitt")));
}

TEST_F(Capture, RecordsAreInApiOrder) {
  requireMesh("bunny");
  CaptureOptions o = small();
  o.backdrop = true;
  o.shading = gen::Shading::Constant;
  o.colours = {{0.2f, 0.4f, 0.6f}};
  o.alphas = {0.5f};
  Capturer cap(o);
  VectorSink sink;
  cap.capture(sink);
  const auto& f = sink.fragments;
  ASSERT_FALSE(f.empty());
  for (size_t i = 1; i < f.size(); ++i) {
    const auto k0 = std::tie(f[i - 1].draw, f[i - 1].prim, f[i - 1].y, f[i - 1].x);
    const auto k1 = std::tie(f[i].draw, f[i].prim, f[i].y, f[i].x);
    ASSERT_LT(k0, k1) << "record " << i;
  }
  for (const Fragment& x : f) {
    ASSERT_LT(x.prim, x.draw == 0 ? 256u : x.draw == 1 ? 12u : 69666u);
    ASSERT_TRUE(x.z >= 0 && x.z <= 1);
    if (x.draw == 2) {  // constant shading: exactly the asked colour
      ASSERT_EQ(x.r, 0.2f);
      ASSERT_EQ(x.b, 0.6f);
      ASSERT_EQ(x.a, 0.5f);
    } else {
      ASSERT_EQ(x.a, 1.0f);
    }
  }
}

// oitsim's rasterizer and Mesa's, from bitwise-equal clip-space vertices (the
// capture computes them with gen's own matrix code): both snap to 1/256 pixel
// and use a top-left fill rule; they differ only in which triangle owns a pixel
// centre lying exactly on a shared horizontal edge. The bunny stays inside the
// near/far planes and the guard band, so clipping plays no part here.
TEST_F(Capture, GenAndMesaProduceTheSameFragments) {
  requireMesh("bunny");
  for (double az : {30.0, 123.0}) {
    CaptureOptions o = small();
    o.width = 320;
    o.height = 240;
    o.azimuth_deg = az;
    const auto [mesa, ours] = mesaAndGen(o);
    using Key = std::tuple<uint32_t, uint16_t, uint16_t>;
    std::set<Key> a, b;
    for (const Fragment& f : mesa) a.insert({f.prim, f.y, f.x});
    for (const Fragment& f : ours) b.insert({f.prim, f.y, f.x});
    std::vector<Key> only_mesa, only_gen;
    std::set_difference(a.begin(), a.end(), b.begin(), b.end(), std::back_inserter(only_mesa));
    std::set_difference(b.begin(), b.end(), a.begin(), a.end(), std::back_inserter(only_gen));
    const double total = static_cast<double>(a.size());
    RecordProperty(fmt::format("az{}_mesa", az), static_cast<int>(a.size()));
    RecordProperty(fmt::format("az{}_only_mesa", az), static_cast<int>(only_mesa.size()));
    RecordProperty(fmt::format("az{}_only_gen", az), static_cast<int>(only_gen.size()));
    // A pixel on an edge shared by two triangles: both rasterizers give it to exactly
    // one of them (fill rule), possibly not the same one. Count those separately.
    std::set<std::pair<uint16_t, uint16_t>> pix_mesa, pix_gen;
    for (const Key& k : only_mesa) pix_mesa.insert({std::get<1>(k), std::get<2>(k)});
    for (const Key& k : only_gen) pix_gen.insert({std::get<1>(k), std::get<2>(k)});
    size_t swapped = 0;
    for (const auto& p : pix_mesa) swapped += pix_gen.count(p);
    for (const Key& k : only_mesa)
      std::printf("  only Mesa: prim %u at (%u, %u)\n", std::get<0>(k), std::get<2>(k), std::get<1>(k));
    for (const Key& k : only_gen)
      std::printf("  only gen:  prim %u at (%u, %u)\n", std::get<0>(k), std::get<2>(k), std::get<1>(k));
    std::printf("azimuth %g: Mesa %zu fragments, gen %zu; only Mesa %zu, only gen %zu; pixels given to "
                "another primitive: %zu\n", az, a.size(), b.size(), only_mesa.size(), only_gen.size(), swapped);
    EXPECT_GT(total, 40000);
    // Measured: the same fragment count, and 3 of 59,502 pixels (azimuth 30; 0 at
    // 123) given to the other triangle of a shared edge. All three are centres lying
    // exactly on a horizontal edge after 8-bit snapping: gen applies the top-left
    // rule in GL's y-up window coordinates (the lower triangle owns it), llvmpipe in
    // its y-down framebuffer coordinates (the upper one does). GL leaves the tie
    // rule to the implementation. Bound: no pixel gained or lost, at most 0.02%.
    EXPECT_EQ(a.size(), b.size()) << "azimuth " << az;
    EXPECT_EQ(swapped, only_mesa.size()) << "a pixel only one rasterizer covers, azimuth " << az;
    EXPECT_EQ(swapped, only_gen.size()) << "a pixel only one rasterizer covers, azimuth " << az;
    EXPECT_LE(static_cast<double>(swapped), 2e-4 * total) << "azimuth " << az;
  }
}

// With the backdrop the wall and pillar are culled back-facing, as gen draws
// them: the same fragments per draw (the pillar's back faces once doubled it).
TEST_F(Capture, BackdropDrawsMatchGenPerDraw) {
  requireMesh("bunny");
  CaptureOptions o = small();
  o.backdrop = true;
  const auto [mesa, ours] = mesaAndGen(o);
  std::map<uint32_t, std::set<std::tuple<uint32_t, uint16_t, uint16_t>>> a, b;  // draw -> (prim, y, x)
  for (const Fragment& f : mesa) a[f.draw].insert({f.prim, f.y, f.x});
  for (const Fragment& f : ours) b[f.draw].insert({f.prim, f.y, f.x});
  for (uint32_t d : {0u, 1u}) {  // backdrop, pillar
    SCOPED_TRACE(d);
    EXPECT_GT(b[d].size(), 0u);
    EXPECT_EQ(a[d].size(), b[d].size());
    std::set<uint32_t> prims_a, prims_b;
    for (const auto& k : a[d]) prims_a.insert(std::get<0>(k));
    for (const auto& k : b[d]) prims_b.insert(std::get<0>(k));
    EXPECT_EQ(prims_a, prims_b);  // the same (front-facing) triangles
  }
}

TEST_F(Capture, OrbitFramesTurnTheCamera) {
  requireMesh("bunny");
  Capturer cap(small());
  VectorSink turned;
  cap.capture(turned, 25.0);
  CaptureOptions o = small();
  o.azimuth_deg = 55.0;  // gen's default 30 + 25
  Capturer direct(o);
  VectorSink at55;
  direct.capture(at55);
  ASSERT_EQ(turned.fragments.size(), at55.fragments.size());
  EXPECT_EQ(0, std::memcmp(turned.fragments.data(), at55.fragments.data(),
                           turned.fragments.size() * sizeof(Fragment)));
  VectorSink first;
  cap.capture(first, 0.0);
  EXPECT_NE(first.fragments.size(), turned.fragments.size());
  EXPECT_EQ(frameFileName("out/bunny.oitt", 3, 10), "out/bunny-0003.oitt");
  EXPECT_EQ(frameFileName("bunny.oitt", 0, 1), "bunny.oitt");
}

TEST_F(Capture, SeveralMeshesAreSeveralDraws) {
  requireMesh("dragon");
  requireMesh("cow");
  CaptureOptions o = small("dragon");
  o.meshes.push_back("cow");
  o.colours = {{0.9f, 0.2f, 0.1f}, {0.1f, 0.3f, 0.9f}};
  o.alphas = {0.4f, 0.6f};
  Capturer cap(o);
  ASSERT_EQ(cap.header().draws.size(), 2u);
  EXPECT_EQ(cap.header().draws[0].name, "dragon");
  EXPECT_EQ(cap.header().draws[1].name, "cow");
  const std::string file = path("two.oitt");
  const CaptureStats st = captureTo(cap, file);
  EXPECT_EQ(st.triangles, 19994u + 5804u);
  EXPECT_GT(st.fragments_per_draw[0], 1000u);
  EXPECT_GT(st.fragments_per_draw[1], 1000u);
  const VerifyResult v = verifyTrace(file, cap.reference());
  EXPECT_EQ(v.channels_differing, 0u) << v.first_difference;
  EXPECT_EQ(v.count_pixels_differing, 0u) << v.first_difference;
}

TEST_F(Capture, ErrorsNameTheProblem) {
  requireMesh("bunny");
  CaptureOptions o = small();
  o.max_records_per_draw = 2;  // one triangle covers more pixels than that
  Capturer cap(o);
  VectorSink sink;
  try {
    cap.capture(sink);
    FAIL() << "expected an overflow error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("--max-records-per-draw"), std::string::npos) << e.what();
  }
  o = small();
  o.alphas = {0.1f, 0.2f};
  EXPECT_THROW(Capturer{o}, std::invalid_argument);
  o = small();
  o.max_records_per_draw = uint64_t(1) << 40;
  try {
    Capturer c(o);
    FAIL() << "expected a storage block limit error";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("GL_MAX_SHADER_STORAGE_BLOCK_SIZE"), std::string::npos) << e.what();
  }
  o = small((dir_ / "missing.obj").string());
  EXPECT_THROW(Capturer{o}, std::runtime_error);
  // Coordinates near fp32's limit: the bounding sphere cannot be scaled into view.
  const fs::path huge = dir_ / "huge.obj";
  std::ofstream(huge) << "v 3e38 3e38 3e38\nv -3e38 -3e38 -3e38\nv 3e38 -3e38 0\nf 1 2 3\n";
  o = small(huge.string());
  try {
    Capturer c(o);
    FAIL() << "expected a framing error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be framed"), std::string::npos) << e.what();
  }
}

TEST(CaptureUlp, DistanceCountsRepresentableSteps) {
  EXPECT_EQ(ulpDistance(1.0f, 1.0f), 0u);
  EXPECT_EQ(ulpDistance(1.0f, std::nextafter(1.0f, 2.0f)), 1u);
  EXPECT_EQ(ulpDistance(-0.0f, 0.0f), 0u);
  EXPECT_EQ(ulpDistance(std::nextafter(0.0f, -1.0f), std::nextafter(0.0f, 1.0f)), 2u);
}

}  // namespace
}  // namespace oit::capture

namespace oit::capture {
namespace {

// The checks catch what they are for: a swapped submission order changes the
// replayed colours, a lost fragment the counts.
TEST_F(Capture, VerifyCatchesReorderedAndLostFragments) {
  requireMesh("bunny");
  Capturer cap(small());
  VectorSink sink;
  cap.capture(sink);
  const GlReference ref = cap.reference();
  auto& f = sink.fragments;
  // Two fragments of one pixel from different primitives, with different colours.
  size_t i = 0, j = 0;
  for (i = 0; i < f.size() && !j; ++i)
    for (size_t k = i + 1; k < f.size(); ++k)
      if (f[k].x == f[i].x && f[k].y == f[i].y && f[k].r != f[i].r) {
        j = k;
        break;
      }
  --i;
  ASSERT_NE(j, 0u) << "no pixel with two differently shaded fragments";
  std::vector<Fragment> swapped = f;
  std::swap(swapped[i], swapped[j]);
  auto write = [&](const std::vector<Fragment>& frags, const std::string& file) {
    auto w = createTraceWriter(file, cap.header());
    w->write(std::span<const Fragment>(frags));
    w->commit();
  };
  write(swapped, path("swapped.oitt"));
  const VerifyResult vs = verifyTrace(path("swapped.oitt"), ref);
  EXPECT_GT(vs.channels_differing, 0u);
  EXPECT_EQ(vs.count_pixels_differing, 0u);
  EXPECT_FALSE(vs.passes());
  std::vector<Fragment> lost = f;
  lost.erase(lost.begin() + static_cast<std::ptrdiff_t>(j));
  write(lost, path("lost.oitt"));
  const VerifyResult vl = verifyTrace(path("lost.oitt"), ref);
  EXPECT_EQ(vl.count_pixels_differing, 1u);
  EXPECT_FALSE(vl.passes());
}

// The command line end to end: orbit frames, file names, --verify, `oitsim info`.
TEST_F(Capture, CommandLineWritesOrbitFramesAndVerifies) {
  requireMesh("bunny");
  const std::string oitsim = std::string(OITSIM_BINARY_DIR) + "/apps/oitsim";
  auto run = [&](const std::string& args, std::string* out) { return test_util::runCommand(oitsim + " " + args, out); };
  std::string out;
  ASSERT_EQ(run(fmt::format("capture --mesh bunny --width 160 --height 120 --frames 2 --orbit-step 15 "
                            "--verify -o {}", path("orbit.oitt")), &out), 0) << out;
  EXPECT_NE(out.find("0 of 57600 channels differ"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(path("orbit-0000.oitt")));
  EXPECT_TRUE(fs::exists(path("orbit-0001.oitt")));
  EXPECT_FALSE(fs::exists(path("orbit.oitt")));
  // Frame 1 is the frame at azimuth 30 + 15.
  Capturer cap(small());
  auto w = createTraceWriter(path("az45.oitt"), cap.header());
  cap.capture(*w, 15.0);
  w->commit();
  EXPECT_TRUE(slurp(path("orbit-0001.oitt")) == slurp(path("az45.oitt")));
  out.clear();
  ASSERT_EQ(run("info " + path("orbit-0000.oitt"), &out), 0) << out;
  EXPECT_NE(out.find("bunny"), std::string::npos) << out;
  EXPECT_NE(out.find("160 x 120"), std::string::npos) << out;
  out.clear();
  EXPECT_NE(run("capture --mesh no-such-mesh -o " + path("x.oitt"), &out), 0);
  EXPECT_NE(out.find("neither an existing file nor a known mesh name"), std::string::npos) << out;
}

}  // namespace
}  // namespace oit::capture
