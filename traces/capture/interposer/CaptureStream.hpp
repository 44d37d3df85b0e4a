// The stream the interposed GL library (liboitsim_interposer.so, loaded by
// apitrace's retracer as its libGL.so.1) writes for `oitsim capture --apitrace`:
// one file, native little-endian structs, read back by traces/capture/ApitraceStream.cpp.
// Both sides include this header, so the layout cannot drift.
//
//   StreamHeader, then chunks: ChunkHeader + payload.
//   kDraw:  DrawChunk, then DrawChunk::records GpuRecords (only when captured)
//   kFrame: FrameChunk at each swap of a frame in the range
//   kError: text (a program that fails to link after rewriting, a GL failure)
//   kEnd:   EndChunk when the retracer exits or the range is done (with the record
//           buffer's capacity: a draw that overflowed a buffer sized by
//           OITSIM_RECORDS_PER_PIXEL is captured again with a larger one; and the
//           GL objects deleted while the stream was open, by kind)
//   kVerify: FrameChunk, then width x height RGBA float (GL's blend of the frame's
//           transparent draws into an RGBA32F target cleared to 0) and width x height
//           u32 (fragments per pixel counted by the same second drawing), before kFrame
//   kCheckDraw: DrawChunk + records, as kDraw, of that second drawing (the check
//           drawing) of one draw, before the draw's own kDraw: the records GL
//           blended into the kVerify image
#pragma once

#include <cstdint>

namespace oit::capture::stream {

// The stream's version is the magic's last character. 2: EndChunk::deleted.
// Reader and interposer come from one build; a stream of another version
// (an interposer from another build, --interposer) is refused, naming both.
inline constexpr uint32_t kVersion = 2;
inline constexpr char kMagic[8] = {'O', 'I', 'T', 'S', 'I', 'P', 'S', char('0' + kVersion)};
inline constexpr unsigned kMagicPrefix = 7;  // "OITSIPS": the same in every version

struct StreamHeader {
  char magic[8];
  uint32_t first_frame, last_frame;  // the range asked for (swap-buffer counts)
};

enum ChunkTag : uint32_t { kDraw = 1, kFrame = 2, kError = 3, kEnd = 4, kVerify = 5, kCheckDraw = 6 };

struct ChunkHeader {
  uint32_t tag;
  uint32_t bytes;  // payload bytes after this header (records of a draw excluded)
};

// Why a draw is not in the trace (DrawChunk::reason); kCaptured when it is.
enum Reason : uint32_t {
  kCaptured = 0,
  kFixedFunction,      // no program object: fixed-function pipeline (or ARB assembly programs)
  kSeparablePipeline,  // a program pipeline object (separate shader objects)
  kDisplayList,        // glCallList(s): the list's draws are not seen one by one
  kNoColourOutput,     // the program writes no colour (depth-only program)
  kIntegerOutput,      // colour output 0 is an integer type
  kColourWritesOff,    // colour mask all off or draw buffer NONE (depth-only pass)
  kSeveralTargets,     // more than one draw buffer enabled (MRT)
  kMultisample,        // the draw framebuffer is multisampled
  kStencil,            // the stencil test decides coverage
  kTargetSize,         // the render target's size differs from the frame's
  kOverflow,           // more fragments than one draw's record buffer holds
  kImmediateMode,      // glBegin/glEnd with a program: drawn without a draw call to repeat
  kRasterizerDiscard,  // GL_RASTERIZER_DISCARD: transform feedback only, no fragments
  kNotRewritten,       // the program's fragment shader has no source (e.g. glProgramBinary)
  kReasonCount
};

inline constexpr const char* reasonName(uint32_t r) {
  constexpr const char* names[kReasonCount] = {
      "captured",
      "fixed-function (no program)",
      "separate shader objects (program pipeline)",
      "display list",
      "program writes no colour",
      "integer colour output",
      "colour writes off (depth-only)",
      "several render targets",
      "multisampled framebuffer",
      "stencil test",
      "render target size differs from the frame",
      "more fragments than a draw's record buffer",
      "immediate mode (glBegin/glEnd)",
      "rasterizer discard (no fragments)",
      "program without fragment shader source"};
  return r < kReasonCount ? names[r] : "unknown";
}

// How the draw's colour reaches attachment 0 (from the blend state at the draw).
enum BlendMode : uint8_t {
  kBlendOff = 0,        // opaque
  kBlendOver = 1,       // SRC_ALPHA, ONE_MINUS_SRC_ALPHA (straight alpha): transparent
  kBlendPremulOver = 2, // ONE, ONE_MINUS_SRC_ALPHA (premultiplied alpha): transparent
  kBlendAdditive = 3,   // SRC_ALPHA or ONE, ONE
  kBlendMultiply = 4,   // DST_COLOR, ZERO or ZERO, SRC_COLOR
  kBlendOther = 5,      // any other equation or factors (constant colour, MIN/MAX, ...)
};

// The GL state of one draw call, as the interposer read it before the call.
struct DrawState {
  uint8_t blend_mode;      // BlendMode
  uint8_t depth_test;      // GL_DEPTH_TEST enabled
  uint8_t depth_write;     // depth mask
  uint8_t early_tests;     // the rewritten program runs the depth test before the shader
  uint16_t depth_func;     // GL enum (GL_LESS ...), 0 when the test is off
  uint16_t blend_eq_rgb, blend_src_rgb, blend_dst_rgb;  // GL enums, 0 when blending is off
  uint16_t blend_eq_alpha, blend_src_alpha, blend_dst_alpha;
};

struct DrawChunk {
  uint32_t frame;       // swap-buffer count of the frame
  uint32_t index;       // draw call number within the frame, from 0 (every draw call counts)
  uint32_t reason;      // Reason
  uint32_t program;     // current program object (0 = none)
  uint32_t width, height;  // size of the render target (0 when unknown)
  uint32_t instanced;   // the call draws instances or several sub-draws (primitive ids restart)
  uint32_t window;      // 1: drawn into the window (framebuffer 0), whose depth llvmpipe interpolates
                        // from the other edge (CAPTURE.md: within 2 ulp of an FBO's)
  uint64_t fragments;   // fragments the shader counted (also when not recorded, e.g. overflow)
  uint64_t records;     // GpuRecords that follow (0 unless captured)
  DrawState state;
  char function[40];    // the GL entry point, NUL-terminated
};

struct FrameChunk {
  uint32_t frame;
  uint32_t width, height;  // the application's drawable at the swap
  uint32_t pad;
};

// GL objects the recorder tracks, as it counts their deletion (EndChunk::deleted).
enum DeletedKind : uint32_t {
  kDeletedProgram = 0,       // an application's program the recorder knew (rewritten or refused),
                             // deleted with glDeleteProgram / glDeleteObjectARB
  kDeletedVerifyTexture,     // the recorder's own --verify colour texture, replaced at a new frame size
  kDeletedVerifyRenderbuffer,  // its --verify depth renderbuffer, replaced for another depth format or size
  kDeletedKindCount
};

struct EndChunk {
  uint32_t frames_seen;   // swaps replayed before the retracer stopped
  uint32_t range_done;    // 1 when the last frame of the range was completed
  uint64_t record_capacity;  // records the record buffer held (0: no draw was recorded)
  uint64_t record_limit;     // records the largest shader storage block holds (0: not asked)
  uint32_t deleted[kDeletedKindCount];  // objects deleted while the stream was open, by DeletedKind
  uint32_t pad;
};

// One record as the injected fragment code stores it (std430): 32 bytes.
struct GpuRecord {
  uint32_t xy;  // x | y << 16
  float z;
  uint32_t prim;
  uint32_t draw;
  float rgba[4];
};
static_assert(sizeof(GpuRecord) == 32);
static_assert(sizeof(DrawState) == 18);
static_assert(sizeof(DrawChunk) == 112);  // 32 + 16 + 18 + 40, padded to 8
static_assert(sizeof(EndChunk) == 40);    // 8 + 16 + 3 x 4 + 4

}  // namespace oit::capture::stream
