// GL objects deleted during `oitsim capture --apitrace` (the interposer's stream,
// traces/capture/interposer/CaptureStream.hpp, EndChunk::deleted): the deletes the
// interposer is told of are counted by kind; a delete of its own --verify target
// that it is not told of (the trace deletes a texture name it never made) stops
// --verify with one line instead of a check against the wrong target; and a stream
// of another version is refused naming the interposer and both versions.
#include <gtest/gtest.h>

#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

#include <fmt/format.h>

#include "apps/CaptureVerify.hpp"
#include "capture/ApitraceTestFixture.hpp"
#include "traces/capture/ApitraceStream.hpp"
#include "traces/capture/interposer/CaptureStream.hpp"

namespace oit::capture {
namespace {

using namespace test_util;

// The application deletes each draw's program at the start of every frame and
// links it again (GL gives the freed name again), and makes and deletes a texture
// and a buffer (the interposer does not track those: not counted). Draw 0 goes
// into the framebuffer object (DEPTH24), draw 1 into glretrace's window, whose
// depth has a stencil (DEPTH24_STENCIL8), both with the depth test, so --verify
// copies depth of two formats into its own target. (With the stencil on the
// framebuffer object too, a GL_ALWAYS stencil draw, both formats are the same
// and no renderbuffer is replaced: measured 0.)
// Counts, for frames 1-1 (the stream ends at the swap of frame 1):
// - programs: 3 draws' programs deleted at the start of frames 0 and 1: 6;
// - verify renderbuffers: frame 1's draw 0 makes the first (nothing deleted),
//   draw 1 needs the window's depth format and replaces it: 1 (draw 2 has no
//   depth test); frames 1-2: draw 0 and draw 1 of frame 2 replace it again: 3,
//   and 9 programs;
// - verify textures: 0 (the frame's size never changes).
// The captured draws are still the mesh capture's and --verify passes: the
// recorder followed each new program and each depth format.
TEST_F(ApitraceCapture, DeletedObjectsAreCountedByKind) {
  const std::string trace = traceApp({"glsl330 over test",                // 0: FBO, DEPTH24
                                      "glsl330+window over test",         // 1: the window's depth
                                      "glsl120 over off"},                // 2: no depth test
                                     4, true, "churn 1\n");
  ApitraceOptions o = options(trace, 1);
  o.verify = true;
  const ApitraceResult one = captureApitrace(o);
  ASSERT_EQ(one.frames.size(), 1u);
  EXPECT_EQ(one.deleted[stream::kDeletedProgram], 6u);
  EXPECT_EQ(one.deleted[stream::kDeletedVerifyRenderbuffer], 1u);
  EXPECT_EQ(one.deleted[stream::kDeletedVerifyTexture], 0u);
  o.last_frame = 2;
  const ApitraceResult two = captureApitrace(o);
  ASSERT_EQ(two.frames.size(), 2u);
  EXPECT_EQ(two.deleted[stream::kDeletedProgram], 9u);
  EXPECT_EQ(two.deleted[stream::kDeletedVerifyRenderbuffer], 3u);
  EXPECT_EQ(two.deleted[stream::kDeletedVerifyTexture], 0u);
  for (const FrameCapture& f : two.frames) {
    SCOPED_TRACE(fmt::format("frame {}", f.frame));
    EXPECT_TRUE(f.uncaptured.empty());
    EXPECT_TRUE(same(ofDraw(f, 0), expected(0))) << firstDifference(ofDraw(f, 0), expected(0));
    EXPECT_EQ(sameUpToDepthUlp(ofDraw(f, 1), expected(1)), "");
    EXPECT_TRUE(same(ofDraw(f, 2), expected(2))) << firstDifference(ofDraw(f, 2), expected(2));
    const TransparentVerifyResult v = verifyTransparentDraws(f);
    EXPECT_TRUE(v.passes()) << v.first_difference << v.first_drawing_difference;
  }
}

// The trace deletes texture names 1-16, which the application never made, at the
// start of every frame, then makes a 4 x 4 texture of its own. glretrace passes
// names it has not seen made on unchanged, so in the replay frame 2's deletes take
// the interposer's --verify colour texture, made at frame 1's first check drawing,
// and GL gives its name, or another, to the application's new texture. The
// recorder is not told (it does not wrap glDeleteTextures); it finds its texture
// gone at frame 2's check drawing and stops, one line naming the frame and the
// texture, rather than check the frame against a target that is not its own (and
// later delete the application's texture by that name). Frame 1 alone passes
// (the deletes come before the texture is made); without --verify frames 1-2 are
// captured.
TEST_F(ApitraceCapture, VerifyStopsWhenItsTargetIsDeletedBehindItsBack) {
  const std::string trace = traceApp({"glsl330 over off"}, 4, true, "texturenames 1 16\n");
  ApitraceOptions o = options(trace, 1);
  o.verify = true;
  const ApitraceResult first = captureApitrace(o);
  ASSERT_EQ(first.frames.size(), 1u);
  EXPECT_TRUE(verifyTransparentDraws(first.frames[0]).passes());
  o.last_frame = 2;
  try {
    captureApitrace(o);
    ADD_FAILURE() << "frames 1-2 with --verify were captured";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(trace + ": frame 2: the interposer's --verify colour texture (GL name "), std::string::npos)
        << what;
    EXPECT_NE(what.find(") was deleted by a call the interposer does not see (found at draw 0's check drawing"),
              std::string::npos)
        << what;
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
  }
  o.verify = false;
  const ApitraceResult plain = captureApitrace(o);
  ASSERT_EQ(plain.frames.size(), 2u);
  for (const FrameCapture& f : plain.frames) EXPECT_TRUE(same(ofDraw(f, 0), expected(0))) << f.frame;
}

// A stream of another version (an interposer of another build, --interposer) is
// refused before any chunk is read: one line naming the trace, the interposer and
// both versions. No GL needed: the stream is written here.
TEST(ApitraceStreamVersion, AnotherVersionIsRefusedNamingBoth) {
  const std::filesystem::path dir = std::filesystem::path(OITSIM_BINARY_DIR) / "test-apitrace" / "stream-version";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string stream_path = (dir / "stream.bin").string(), log_path = (dir / "log.txt").string();
  std::ofstream(log_path) << "";
  {
    // A version 1 stream: its header and an end chunk of 24 bytes (no deleted counts).
    std::ofstream out(stream_path, std::ios::binary);
    stream::StreamHeader h{};
    std::memcpy(h.magic, "OITSIPS1", 8);
    out.write(reinterpret_cast<const char*>(&h), sizeof h);
    const stream::ChunkHeader c{stream::kEnd, 24};
    out.write(reinterpret_cast<const char*>(&c), sizeof c);
    const char end[24] = {};
    out.write(end, sizeof end);
  }
  ApitraceOptions o;
  o.trace = "app.trace";
  o.first_frame = o.last_frame = 1;
  try {
    readStream(o, "glretrace", "/old/liboitsim_interposer.so", 0, stream_path, log_path, nullptr);
    ADD_FAILURE() << "a version 1 stream was read";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()),
              fmt::format("app.trace: the interposer /old/liboitsim_interposer.so writes capture stream version 1, "
                          "this oitsim reads version {}: use the interposer built with this oitsim (next to it)",
                          stream::kVersion));
  }
  EXPECT_EQ(stream::kVersion, 2u);
  EXPECT_EQ(scanStream(stream_path).record_capacity, 0u);  // its chunks are not read either
}

}  // namespace
}  // namespace oit::capture
