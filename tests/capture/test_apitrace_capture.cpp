// `oitsim capture --apitrace`: a small GLX application of our own
// (apitrace_app/GlTestApp.cpp) draws the mesh capture's own clip-space triangles
// with different shaders and GL states; it is traced with `apitrace trace` under
// Xvfb, and the capture replays the trace through the interposer. Each captured
// draw must hold exactly the fragments the mesh capture records for the same
// triangles, filtered as GL's state says (discard, the depth test).
#include <gtest/gtest.h>

#include <cstring>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <map>
#include <set>
#include <tuple>

#include <fmt/format.h>

#include "traces/TraceIO.hpp"
#include "traces/capture/ApitraceCapture.hpp"
#include "traces/capture/GlCapture.hpp"
#include "traces/capture/interposer/CaptureStream.hpp"
#include "apps/CaptureVerify.hpp"
#include "capture/ApitraceTestFixture.hpp"

namespace oit::capture {
namespace {

namespace fs = std::filesystem;
using namespace test_util;

// One frame with every kind of draw the issue lists: GLSL 1.20 gl_FragColor, GLSL
// 3.30 core `out`, discard, an additive draw, a fixed-function draw, depth test off
// and on. Each captured draw equals the mesh capture of the same triangles.
TEST_F(ApitraceCapture, EveryDrawKindMatchesTheMeshCapture) {
  ASSERT_GT(mesh_.fragments.size(), 500u);
  const std::string trace = traceApp({
      "glsl120 over off",   // 0: gl_FragColor, depth test off
      "glsl330 over test",  // 1: `out`, depth test LESS without writes: all pass (depth is 1.0)
      "discard over off",   // 2: discards pixels with odd x + y
      "glsl330 additive off",  // 3: additive: in the table, not modelled
      "fixed over off",     // 4: fixed function: not captured
      "glsl120 off write",  // 5: opaque, depth test LESS with writes
  });
  const ApitraceResult r = captureApitrace(options(trace, 1));
  ASSERT_EQ(r.frames.size(), 1u);
  const FrameCapture& f = r.frames[0];
  EXPECT_EQ(f.frame, 1u);
  EXPECT_EQ(f.header.width, kWidth);
  EXPECT_EQ(f.header.height, kHeight);
  EXPECT_EQ(f.header.version, 2u);
  EXPECT_EQ(f.draw_calls, 6u);

  const std::vector<Fragment> d0 = ofDraw(f, 0), d1 = ofDraw(f, 1), d2 = ofDraw(f, 2), d5 = ofDraw(f, 5);
  EXPECT_TRUE(same(d0, expected(0))) << firstDifference(d0, expected(0));
  EXPECT_TRUE(same(d1, expected(1))) << firstDifference(d1, expected(1));
  const auto even = [](const Fragment& x) { return ((x.x + x.y) & 1) == 0; };
  EXPECT_TRUE(same(d2, expected(2, even))) << firstDifference(d2, expected(2, even));
  EXPECT_LT(d2.size(), mesh_.fragments.size() * 6 / 10);

  // Draw 5: depth test LESS with writes, nothing drawn before wrote depth: a
  // fragment is kept when it is nearer than every earlier one of the draw at its
  // pixel (API order: primitive, then row, then x).
  std::map<std::pair<uint16_t, uint16_t>, float> depth;
  const auto passes = [&](const Fragment& x) {
    auto [it, fresh] = depth.try_emplace({x.x, x.y}, 1.0f);
    if (!(x.z < it->second)) return false;
    it->second = x.z;
    return true;
  };
  const std::vector<Fragment> e5 = expected(5, passes);
  EXPECT_TRUE(same(d5, e5)) << firstDifference(d5, e5);
  EXPECT_LT(e5.size(), mesh_.fragments.size());  // the cube's back faces fail

  // The draw table keeps each draw's state; the additive draw is listed with its
  // mode and fragment count, its records are not in the trace.
  for (const DrawInfo& d : f.header.draws) EXPECT_TRUE(d.state) << "draw " << d.id << " has no state";
  const DrawInfo* a = drawOf(f, 3);
  ASSERT_NE(a, nullptr);
  ASSERT_TRUE(a->state);
  EXPECT_EQ(a->state->blend, BlendMode::Additive);
  EXPECT_EQ(a->state->blend_src_rgb, 1u);  // GL_ONE
  EXPECT_EQ(a->state->blend_dst_rgb, 1u);
  EXPECT_EQ(a->state->fragments, mesh_.fragments.size());
  EXPECT_TRUE(ofDraw(f, 3).empty());
  EXPECT_EQ(drawOf(f, 0)->state->blend, BlendMode::Over);
  EXPECT_FALSE(drawOf(f, 0)->state->depth_test);
  EXPECT_TRUE(drawOf(f, 1)->state->depth_test);
  EXPECT_FALSE(drawOf(f, 1)->state->depth_write);
  EXPECT_EQ(drawOf(f, 1)->state->depth_func, 0x0201u);  // GL_LESS
  EXPECT_EQ(drawOf(f, 5)->state->blend, BlendMode::Off);
  EXPECT_EQ(drawOf(f, 5)->cls, DrawClass::Opaque);
  EXPECT_TRUE(drawOf(f, 5)->state->depth_write);
  // The fixed-function draw is counted as not captured, never silently dropped.
  EXPECT_EQ(drawOf(f, 4), nullptr);
  ASSERT_EQ(f.uncaptured.size(), 1u);
  EXPECT_EQ(f.uncaptured[0].index, 4u);
  EXPECT_EQ(f.uncaptured[0].reason, static_cast<uint32_t>(stream::kFixedFunction));
  const std::string summary = frameSummary(f, "out.oitt");
  EXPECT_NE(summary.find("fixed-function (no program): draw 4"), std::string::npos) << summary;
  EXPECT_NE(summary.find("1 additive"), std::string::npos) << summary;
}

// frameSummary reads every draw's state: a captured frame always has them
// (readStream's addDraw sets each), so a draw without one is refused as a
// programming error instead of dereferencing an empty optional. No GL needed.
TEST(ApitraceSummary, ADrawWithoutStateIsRefused) {
  FrameCapture f;
  f.frame = 7;
  f.header.version = 2;
  f.header.width = f.header.height = 4;
  DrawInfo with;
  with.id = 0;
  with.cls = DrawClass::Transparent;
  with.state = DrawState{};
  with.state->blend = BlendMode::Over;
  with.state->fragments = 3;
  f.header.draws.push_back(with);
  EXPECT_NE(frameSummary(f, "out.oitt").find("1 over (3 fragments)"), std::string::npos) << frameSummary(f, "out.oitt");
  DrawInfo without;
  without.id = 1;
  f.header.draws.push_back(without);
  try {
    frameSummary(f, "out.oitt");
    FAIL() << "no exception";
  } catch (const std::logic_error& e) {
    EXPECT_STREQ(e.what(), "frameSummary: frame 7: draw 1 has no draw state");
  }
}

// --verify: the transparent draws replayed with `alpha` equal GL's own blend of
// them, bit for bit (straight over, colours in [0, 1]); per-pixel counts agree.
// Then the command line writes a v2 trace that reads back as the capture. This
// application draws into its window (no FBO).
TEST_F(ApitraceCapture, VerifyAndCommandLine) {
  const std::string trace = traceApp({"glsl120 over off", "glsl330 over test", "discard over off"}, 3, false);
  const ApitraceResult r = verifiedCapture(trace);
  ASSERT_EQ(r.frames.size(), 1u);
  ASSERT_TRUE(r.frames[0].reference);
  EXPECT_EQ(sameUpToDepthUlp(ofDraw(r.frames[0], 0), expected(0)), "");
  const TransparentVerifyResult v = verifyTransparentDraws(r.frames[0]);
  EXPECT_EQ(v.fragments, r.frames[0].fragments.size());
  EXPECT_EQ(v.channels_compared, 3u * kWidth * kHeight);
  EXPECT_EQ(v.channels_differing, 0u) << v.first_difference;
  EXPECT_EQ(v.count_pixels_differing, 0u) << v.first_difference;
  // Drawn into the window: the same fragments as the check drawing (an FBO), depth
  // within the window's rounding (CAPTURE.md), colours equal (no textures).
  EXPECT_EQ(r.frames[0].window_draws, (std::vector<uint32_t>{0, 1, 2}));
  EXPECT_EQ(v.drawing_mismatches, 0u) << v.first_drawing_difference;
  EXPECT_EQ(v.colour_differing, 0u) << v.first_drawing_difference;
  EXPECT_LE(v.max_depth_diff, 2 * 6e-8);  // 2 ulp below 1.0 (measured)
  EXPECT_TRUE(v.passes());

  const std::string oitsim = std::string(OITSIM_BINARY_DIR) + "/apps/oitsim";
  std::string out;
  ASSERT_EQ(run(fmt::format("{} capture --apitrace {} --frames 1-2 --verify -o {}", oitsim, trace, path("f.oitt")),
                &out),
            0)
      << out;
  EXPECT_NE(out.find("0 of 9216 channels differ"), std::string::npos) << out;
  for (const char* name : {"f-0001.oitt", "f-0002.oitt"}) {
    auto src = openTrace(path(name));
    EXPECT_EQ(src->header().version, 2u);
    std::vector<Fragment> all;
    for (auto chunk = src->next(); !chunk.empty(); chunk = src->next()) all.insert(all.end(), chunk.begin(), chunk.end());
    EXPECT_TRUE(same(all, r.frames[0].fragments)) << name;
  }
}

// --verify compares like with like: GL's blend with the records of the drawing GL
// blended (the check drawing), the trace's per-pixel counts with GL's, and the
// trace with the check drawing one to one. A real mismatch in the trace fails it:
// a colour, an order, a dropped fragment, a depth; and so does a blend the records
// do not reproduce. The application draws into a framebuffer object here, so the
// two drawings agree bit for bit (depth included).
TEST_F(ApitraceCapture, VerifyCatchesARealMismatch) {
  const ApitraceResult r =
      verifiedCapture(traceApp({"glsl120 over off", "glsl330 over test", "discard over off"}, 3, true));
  ASSERT_EQ(r.frames.size(), 1u);
  const FrameCapture& good = r.frames[0];
  ASSERT_TRUE(good.reference);
  const TransparentVerifyResult v = verifyTransparentDraws(good);
  EXPECT_TRUE(v.passes());
  EXPECT_EQ(v.check_fragments, good.fragments.size());
  EXPECT_EQ(v.channels_differing, 0u) << v.first_difference;
  EXPECT_EQ(v.drawing_mismatches, 0u) << v.first_drawing_difference;
  EXPECT_EQ(v.colour_differing, 0u) << v.first_drawing_difference;
  EXPECT_EQ(v.depth_differing, 0u);
  EXPECT_TRUE(good.window_draws.empty());

  // Two fragments of one pixel from different primitives of draw 0 (the cube's
  // front and back faces), and a fragment alone at its pixel.
  size_t i = 0, j = 0, alone = 0;
  std::map<std::pair<uint16_t, uint16_t>, std::vector<size_t>> at;
  for (size_t k = 0; k < good.fragments.size(); ++k)
    if (good.fragments[k].draw == 0) at[{good.fragments[k].x, good.fragments[k].y}].push_back(k);
  for (const auto& [pixel, ks] : at) {
    if (ks.size() == 2 && good.fragments[ks[0]].prim != good.fragments[ks[1]].prim && i == j) i = ks[0], j = ks[1];
  }
  for (size_t k = 0; k < good.fragments.size(); ++k) {
    const Fragment& f = good.fragments[k];
    size_t n = 0;
    for (const Fragment& g : good.fragments) n += g.x == f.x && g.y == f.y;
    if (n == 1) {
      alone = k;
      break;
    }
  }
  ASSERT_NE(i, j);
  auto fails = [&](const char* what, auto change) {
    FrameCapture bad = good;
    change(bad);
    const TransparentVerifyResult b = verifyTransparentDraws(bad);
    EXPECT_FALSE(b.passes()) << what;
    return b;
  };
  // A colour 0.1 off: beyond the drawings' bound (4/255).
  const auto colour = fails("colour", [&](FrameCapture& f) { f.fragments[i].r += 0.1f; });
  EXPECT_EQ(colour.colour_differing, 1u);
  EXPECT_NEAR(colour.max_colour_diff, 0.1, 1e-6);
  // The two fragments of one pixel in the wrong order.
  const auto order = fails("order", [&](FrameCapture& f) { std::swap(f.fragments[i], f.fragments[j]); });
  EXPECT_EQ(order.drawing_mismatches, 2u);
  // A fragment dropped: its pixel's count and every later fragment's place.
  const auto dropped = fails("dropped", [&](FrameCapture& f) {
    f.fragments.erase(f.fragments.begin() + static_cast<std::ptrdiff_t>(alone));
  });
  EXPECT_EQ(dropped.count_pixels_differing, 1u);
  // A depth one ulp off (drawn into an FBO: depths must be equal).
  const auto depth = fails("depth", [&](FrameCapture& f) { f.fragments[i].z = std::nextafter(f.fragments[i].z, 2.0f); });
  EXPECT_EQ(depth.drawing_mismatches, 1u);
  // GL's blend not what the check drawing's records give.
  const auto blend = fails("blend", [&](FrameCapture& f) { f.reference->rgba[4 * (f.fragments[i].y * kWidth + f.fragments[i].x)] += 1e-3f; });
  EXPECT_EQ(blend.channels_differing, 1u);
  EXPECT_EQ(blend.drawing_mismatches, 0u);
}

// The record buffer starts sized to the frame (ApitraceOptions::records_per_pixel);
// a draw that outgrows it has blended already, so the capture replays the trace
// with room for the largest such draw. Here 0.1 records per pixel: 307 records for
// the 64 x 48 frame, against more than 500 per cube draw; the second replay's
// buffer holds the largest draw's count, and the frame equals a capture whose
// buffer was GL's largest block from the start.
TEST_F(ApitraceCapture, ADrawThatOutgrowsTheFirstRecordBufferIsCapturedByASecondReplay) {
  const std::string trace = traceApp({"glsl120 over off", "glsl330 over test", "discard over off"});
  ApitraceOptions o = options(trace, 1);
  o.records_per_pixel = 0;
  const ApitraceResult full = captureApitrace(o);
  ASSERT_EQ(full.frames.size(), 1u);
  EXPECT_EQ(full.replays, 1u);
  EXPECT_EQ(full.record_capacity, full.record_limit);
  EXPECT_TRUE(full.frames[0].uncaptured.empty());
  o.records_per_pixel = 0.1;
  const ApitraceResult r = captureApitrace(o);
  ASSERT_EQ(r.frames.size(), 1u);
  EXPECT_EQ(r.replays, 2u);
  EXPECT_EQ(r.first_record_capacity, 307u);  // floor(0.1 * 64 * 48)
  EXPECT_EQ(r.record_capacity, mesh_.fragments.size());  // draws 0 and 1 record every cube fragment
  EXPECT_TRUE(r.frames[0].uncaptured.empty());
  EXPECT_TRUE(same(r.frames[0].fragments, full.frames[0].fragments))
      << firstDifference(r.frames[0].fragments, full.frames[0].fragments);
  // The same with --verify: the check drawings' records (also in the stream) do not
  // hide the overflow, and the second replay's frame passes the check.
  o.verify = true;
  const ApitraceResult checked = captureApitrace(o);
  ASSERT_EQ(checked.frames.size(), 1u);
  EXPECT_EQ(checked.replays, 2u);
  EXPECT_TRUE(same(checked.frames[0].fragments, full.frames[0].fragments));
  EXPECT_TRUE(verifyTransparentDraws(checked.frames[0]).passes());
  o.verify = false;
  // --max-records-per-draw caps the second buffer: a draw above the cap stays listed.
  o.max_records_per_draw = 400;
  const ApitraceResult capped = captureApitrace(o);
  EXPECT_EQ(capped.replays, 2u);
  EXPECT_EQ(capped.record_capacity, 400u);
  ASSERT_EQ(capped.frames[0].uncaptured.size(), 3u);
  EXPECT_EQ(capped.frames[0].uncaptured[0].reason, static_cast<uint32_t>(stream::kOverflow));
  EXPECT_EQ(capped.frames[0].uncaptured[0].fragments, mesh_.fragments.size());
}

// GLSL ES shaders on desktop GL (ARB_ES3_compatibility / ARB_ES2_compatibility):
// a `#version 300 es` program with an `out` variable and a `#version 100` program
// with gl_FragColor and mediump. The capture rewrites them as GLSL ES 3.20
// (ShaderRewrite.cpp); each captured draw equals the mesh capture of the same
// triangles bit for bit, and --verify passes on the frame.
TEST_F(ApitraceCapture, GlslEsShadersMatchTheMeshCapture) {
  const std::string trace = traceApp({
      "es300 over off",   // 0: GLSL ES 3.00, `out`, depth test off
      "es100 over test",  // 1: GLSL ES 1.00, gl_FragColor; depth test LESS without writes: all pass
  });
  const ApitraceResult r = verifiedCapture(trace);
  ASSERT_EQ(r.frames.size(), 1u);
  const FrameCapture& f = r.frames[0];
  EXPECT_EQ(f.draw_calls, 2u);
  EXPECT_TRUE(f.uncaptured.empty()) << frameSummary(f, "out.oitt");
  const std::vector<Fragment> d0 = ofDraw(f, 0), d1 = ofDraw(f, 1);
  EXPECT_TRUE(same(d0, expected(0))) << firstDifference(d0, expected(0));
  EXPECT_TRUE(same(d1, expected(1))) << firstDifference(d1, expected(1));
  EXPECT_EQ(f.fragments.size(), 2 * mesh_.fragments.size());
  ASSERT_NE(drawOf(f, 0), nullptr);
  ASSERT_NE(drawOf(f, 1), nullptr);
  EXPECT_EQ(drawOf(f, 0)->state->blend, BlendMode::Over);
  EXPECT_TRUE(drawOf(f, 1)->state->depth_test);
  const TransparentVerifyResult v = verifyTransparentDraws(f);
  EXPECT_TRUE(v.passes()) << v.first_difference << v.first_drawing_difference;
  EXPECT_EQ(v.channels_differing, 0u) << v.first_difference;
}

// Draws the trace cannot express are counted and listed per frame, never dropped
// silently, and none of their fragments is in the trace: several render targets
// (glDrawBuffers of two attachments), a multisampled framebuffer object (4
// samples), the stencil test deciding coverage (GL_EQUAL). The stencil test on
// with GL_ALWAYS does not decide coverage: that draw is captured.
TEST_F(ApitraceCapture, DrawsTheTraceCannotExpressAreListedPerFrame) {
  const std::string trace = traceApp({
      "glsl330 over off",                // 0: captured
      "mrt over off",                    // 1: two draw buffers
      "glsl330+msaa over off",           // 2: 4-sample framebuffer object
      "glsl330+stencil over off",        // 3: stencil test, GL_EQUAL 0
      "glsl120+stencilalways over off",  // 4: stencil test, GL_ALWAYS: captured
  });
  ApitraceOptions o = options(trace, 1);
  o.last_frame = 2;
  const ApitraceResult r = captureApitrace(o);
  ASSERT_EQ(r.frames.size(), 2u);
  for (const FrameCapture& f : r.frames) {
    SCOPED_TRACE(fmt::format("frame {}", f.frame));
    EXPECT_EQ(f.draw_calls, 5u);
    ASSERT_EQ(f.uncaptured.size(), 3u);
    const uint32_t reasons[3] = {stream::kSeveralTargets, stream::kMultisample, stream::kStencil};
    for (uint32_t k = 0; k < 3; ++k) {
      EXPECT_EQ(f.uncaptured[k].index, k + 1);
      EXPECT_EQ(f.uncaptured[k].reason, reasons[k]);
      EXPECT_EQ(f.uncaptured[k].function, "glDrawArrays");
      EXPECT_EQ(drawOf(f, k + 1), nullptr);  // not in the draw table
      EXPECT_TRUE(ofDraw(f, k + 1).empty());  // no fragment of it in the trace
    }
    // Exactly the two captured draws' fragments, each the mesh capture's.
    EXPECT_EQ(f.fragments.size(), 2 * mesh_.fragments.size());
    const std::vector<Fragment> d0 = ofDraw(f, 0), d4 = ofDraw(f, 4);
    EXPECT_TRUE(same(d0, expected(0))) << firstDifference(d0, expected(0));
    EXPECT_TRUE(same(d4, expected(4))) << firstDifference(d4, expected(4));
    const std::string summary = frameSummary(f, "out.oitt");
    EXPECT_NE(summary.find("\n  not captured: 3 draws\n    several render targets: draw 1\n"
                           "    multisampled framebuffer: draw 2\n    stencil test: draw 3"),
              std::string::npos)
        << summary;
  }
}

// --strict turns a draw the trace cannot express into an error: one line naming
// the trace, the frame, the first such draw and why; exit 1; nothing written.
// Without --strict the same frame is written and the summary lists the draw.
TEST_F(ApitraceCapture, StrictRefusesAMultisampledDraw) {
  const std::string oitsim = std::string(OITSIM_BINARY_DIR) + "/apps/oitsim";
  const std::string trace = traceApp({"glsl330 over off", "glsl330+msaa over off"});
  std::string out;
  EXPECT_EQ(run(fmt::format("{} capture --apitrace {} --frames 1 --strict -o {}", oitsim, trace, path("x.oitt")), &out),
            1)
      << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  EXPECT_NE(out.find(trace + ": frame 1: 1 draw call not captured (--strict), the first draw 1 (glDrawArrays, program "),
            std::string::npos)
      << out;
  EXPECT_NE(out.find("): multisampled framebuffer\n"), std::string::npos) << out;
  EXPECT_FALSE(fs::exists(path("x.oitt")));
  ASSERT_EQ(run(fmt::format("{} capture --apitrace {} --frames 1 -o {}", oitsim, trace, path("y.oitt")), &out), 0)
      << out;
  EXPECT_NE(out.find("\n  not captured: 1 draw\n    multisampled framebuffer: draw 1"), std::string::npos) << out;
  EXPECT_TRUE(fs::exists(path("y.oitt")));
}

// Bad input: one line naming the file, the frame or the program; exit 1; nothing written.
TEST_F(ApitraceCapture, ErrorsNameTheFileFrameOrProgram) {
  const std::string oitsim = std::string(OITSIM_BINARY_DIR) + "/apps/oitsim";
  auto fails = [&](const std::string& args, const std::string& expect) {
    std::string out;
    EXPECT_EQ(run(oitsim + " capture " + args + " -o " + path("x.oitt"), &out), 1) << out;
    EXPECT_NE(out.find(expect), std::string::npos) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
    EXPECT_FALSE(fs::exists(path("x.oitt")));
  };
  std::ofstream(path("not.trace")) << "# oitsim-trace v1\n";
  fails("--apitrace " + path("not.trace") + " --frames 0",
        path("not.trace") + ": not an apitrace trace: it starts with 23 20");
  const std::string trace = traceApp({"glsl330 over off", "fixed over off"}, 2);
  fails("--apitrace " + trace + " --frames 1-2",
        trace + ": frame range 1-2 is past the end: the trace has 2 frames (swap-buffer counts 0-1)");
  fails("--apitrace " + trace + " --frames 1 --strict",
        trace + ": frame 1: 1 draw call not captured (--strict), the first draw 1 (glDrawArrays, program 0): "
                "fixed-function (no program)");
  fails("--apitrace " + trace + " --frames 2-1", "--frames '2-1': expected a frame A or a range A-B");
  const std::string clash = traceApp({"clash over off"}, 1);
  fails("--apitrace " + clash + " --frames 0", clash + ": program ");
  std::string out;
  run(oitsim + " capture --apitrace " + clash + " --frames 0 -o " + path("x.oitt"), &out);
  EXPECT_NE(out.find("fails to link after rewriting"), std::string::npos) << out;
}

}  // namespace
}  // namespace oit::capture
