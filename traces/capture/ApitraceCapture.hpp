// `oitsim capture --apitrace F.trace --frames A[-B]`: replays an apitrace trace of a
// GLX application with apitrace's own retracer (glretrace --headless, on a private
// Xvfb) with liboitsim_interposer.so as its libGL.so.1 (traces/capture/interposer/),
// reads the stream it
// writes (interposer/CaptureStream.hpp) and turns each frame into a trace of format
// v2: fragments in API order, a draw table with each draw's blend and depth state,
// and the draws the trace cannot express listed with why. See traces/CAPTURE.md.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "traces/Fragment.hpp"

namespace oit::capture {

struct ApitraceOptions {
  std::string trace;                // the apitrace file
  uint32_t first_frame = 0, last_frame = 0;  // swap-buffer counts, inclusive
  bool verify = false;              // GL's own blend and count of the transparent draws
  uint64_t max_records_per_draw = 0;  // 0 = the largest shader storage block
  // The record buffer first holds this many records per pixel of the frame (at most
  // the above); a draw that outgrows it makes the capture replay the trace once more
  // with room for it. 0 = the maximum from the start.
  double records_per_pixel = 2;
  std::string retracer;             // "" = glretrace on PATH
  std::string interposer;           // "" = liboitsim_interposer.so next to this executable
};

// A draw call of a frame that is not in the trace, and why.
struct UncapturedDraw {
  uint32_t index = 0;      // draw call number within the frame (the draw id it would have had)
  uint32_t reason = 0;     // stream::Reason
  std::string function;    // the GL entry point
  uint32_t program = 0;
  uint32_t width = 0, height = 0;  // its render target (0 when not looked at)
  uint64_t fragments = 0;  // counted by the shader (overflow only)
};

// GL's images of a frame's transparent draws (--verify): RGBA32F cleared to 0, the
// draws blended with the application's own blend state and depth buffer, and the
// fragments per pixel counted by that second drawing (the check drawing), with
// the records it made. Row 0 is the bottom row.
struct GlTransparentReference {
  uint32_t width = 0, height = 0;
  std::vector<float> rgba;
  std::vector<uint32_t> count;
  std::vector<Fragment> fragments;  // the check drawing's records, API order, as a trace holds them
};

struct FrameCapture {
  uint32_t frame = 0;
  TraceHeader header;               // version 2: frame size, draw table; every draw has its state (addDraw)
  std::vector<Fragment> fragments;  // API order: draw, primitive, then (y, x)
  std::vector<UncapturedDraw> uncaptured;
  uint64_t draw_calls = 0;          // every draw call of the frame
  uint64_t late_depth_draws = 0;    // programs that discard or write depth: recorded before the depth test
  uint64_t multi_draws = 0;         // instanced or multi-draw calls: primitive ids restart per instance
  std::vector<uint32_t> window_draws;  // captured draws drawn into the window, not a framebuffer object
  uint64_t colour_clamped = 0;      // colour outside [0,1] or not finite, clamped (NaN -> 0)
  uint64_t depth_clamped = 0;       // depth written outside [0,1] or not finite, clamped
  uint64_t premultiplied_zero_alpha = 0;  // premultiplied colour over alpha 0: straight colour unknown, 0
  uint64_t premultiplied_clamped = 0;     // premultiplied colour above its alpha: straight colour clamped to 1
  std::optional<GlTransparentReference> reference;  // with verify
};

struct ApitraceResult {
  std::vector<FrameCapture> frames;
  std::string renderer_log;  // the retracer's output (stdout and stderr)
  double seconds = 0;        // retracer run(s) + reading + sorting
  uint32_t replays = 1;      // 2 when a draw outgrew the first record buffer
  uint64_t first_record_capacity = 0;  // the first run's record buffer (records), with replays = 2
  uint64_t record_capacity = 0;        // the record buffer of the run kept (records; 0: nothing recorded)
  uint64_t record_limit = 0;           // records GL's largest storage block holds (0: not asked)
  // GL objects deleted while the interposer's stream was open (the run kept), by
  // the kind the interposer tracks (interposer/CaptureStream.hpp, DeletedKind):
  // the application's programs it knew, its own --verify textures and renderbuffers.
  std::array<uint32_t, 3> deleted{};
};

// Throws std::invalid_argument naming the file when it is not an apitrace trace
// (apitrace writes snappy-compressed files starting with "at"; old ones gzip).
void checkApitraceFile(const std::string& path);

// Runs the retracer over the trace and returns the frames of the range. Throws
// std::runtime_error, one line, naming the trace and the frame or program: a frame
// range past the end, a program that does not link after rewriting, a retracer
// that failed.
ApitraceResult captureApitrace(const ApitraceOptions& opts);

// Where the interposer is looked for by default.
std::string defaultInterposerPath();

// "fixed-function (no program)" ...
const char* uncapturedReasonName(uint32_t reason);

}  // namespace oit::capture

namespace oit::capture {

// The capture's summary of one frame, several lines: fragments and draws by blend
// mode, the draws not modelled, every draw not captured grouped by reason (draw
// numbers as ranges), and notes on what the trace approximates.
std::string frameSummary(const FrameCapture& f, const std::string& output);

}  // namespace oit::capture
