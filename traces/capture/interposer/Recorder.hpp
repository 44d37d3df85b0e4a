// The interposer's state: which programs were rewritten, the frame count, and for
// each draw call of a frame in the range: its classification, the record pass and
// (with verify) a second drawing of transparent draws into the interposer's own
// RGBA32F target. Everything it learns goes into the stream (CaptureStream.hpp).
//
// Inert unless OITSIM_STREAM names the stream file (so a child process that
// inherits LD_LIBRARY_PATH is not affected). Environment:
//   OITSIM_STREAM=path   OITSIM_FRAMES=A-B   OITSIM_VERIFY=1   OITSIM_MAX_RECORDS=N
//   OITSIM_RECORDS_PER_PIXEL=K (the record buffer holds K records per pixel of the
//   frame, at most N or GL's largest storage block; 0 = that maximum)
#pragma once

#include <cstdint>
#include <cstdio>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

#include "traces/capture/interposer/CaptureStream.hpp"
#include "traces/capture/interposer/RealGl.hpp"

namespace oit::capture::interposer {

struct ProgramInfo {
  bool rewritten = false;
  uint32_t reason = stream::kNotRewritten;  // when not rewritten
  bool early_tests = false;
  GLint loc_mode = -1, loc_draw = -1, loc_capacity = -1, loc_width = -1;
};

class Recorder {
 public:
  static Recorder& get();

  // glLinkProgram has linked `program` as the application asked: rewrite its
  // fragment shader and link again.
  void afterLink(GLuint program);
  void forgetProgram(GLuint program);

  // One draw call: `call` issues it (possibly twice: the verify drawing, which
  // counts and records, first).
  template <typename Call>
  void draw(const char* function, bool multi, Call&& call) {
    Pending p;
    if (!begin(function, multi, p)) {
      call();
      return;
    }
    if (p.verify) {
      enterVerify(p);
      call();
      leaveVerify(p);
    }
    if (p.chunk.reason == stream::kCaptured) arm(p);
    call();
    finish(p);
  }
  // A draw that is listed but cannot be recorded (glBegin, glCallList).
  void uncapturable(const char* function, uint32_t reason_with_program, uint32_t reason_without);

  void swap();
  void atExit();

 private:
  struct SavedBinding {
    GLint buffer = 0;
    GLint64 start = 0, size = 0;
  };
  struct Pending {
    stream::DrawChunk chunk{};
    const ProgramInfo* info = nullptr;
    bool verify = false;
    SavedBinding records, counts;  // the application's bindings at the interposer's indices
    GLint saved_draw_fb = 0, saved_read_fb = 0;
    GLint saved_clamp = -1;  // GL_CLAMP_FRAGMENT_COLOR during the verify drawing (-1: not set)
  };

  Recorder();
  bool inRange() const { return active_ && frame_ >= first_ && frame_ <= last_; }
  void ensureGl();
  GLint describe(const char* function, bool multi, stream::DrawChunk& c);
  bool begin(const char* function, bool multi, Pending& p);
  void readState(stream::DrawState& s);
  uint32_t classify(Pending& p, GLint program);
  // Binds the record buffer (counter cleared) and turns recording on for the draw.
  void arm(Pending& p);
  // Turns recording off and writes the draw's records as a chunk `tag` (kDraw, or
  // kCheckDraw for the verify drawing), or the draw as overflowing.
  void takeRecords(const Pending& p, stream::DrawChunk c, uint32_t tag);
  void finish(Pending& p);
  void enterVerify(Pending& p);
  void leaveVerify(Pending& p);
  void ensureVerifyTarget();
  // Stops the capture when the verify colour texture is no longer the one the
  // recorder made: deleted (or its name taken by another texture) by a call the
  // interposer does not see, so the check drawing has no target of its own.
  void checkVerifyTarget(const std::string& when);
  void copyDepth(GLint app_fb);
  void writeVerify();
  SavedBinding bindStorage(GLuint index, GLuint buffer);
  void restoreStorage(GLuint index, const SavedBinding& s);
  void zeroBuffer(GLuint buffer, GLsizeiptr bytes);
  void readBuffer(GLuint buffer, GLintptr offset, GLsizeiptr bytes, void* out);
  // Maps [offset, offset + bytes) of `buffer` for reading and hands the pointer to `use`.
  void mapBuffer(GLuint buffer, GLintptr offset, GLsizeiptr bytes, const std::function<void(const void*)>& use);
  bool drawableSize(uint32_t& w, uint32_t& h) const;
  void targetSize(GLint fb, GLenum attachment, uint32_t& w, uint32_t& h) const;
  void write(uint32_t tag, const void* payload, uint32_t bytes, const void* extra = nullptr, uint64_t extra_bytes = 0);
  [[noreturn]] void fail(const std::string& message);
  void finishStream(bool range_done);

  bool active_ = false, verify_ = false, gl_ready_ = false, ended_ = false;
  uint32_t first_ = 0, last_ = 0, frame_ = 0, draw_index_ = 0;
  uint64_t max_records_ = 0, capacity_ = 0, limit_ = 0;
  double records_per_pixel_ = 0;
  std::FILE* out_ = nullptr;
  std::unordered_map<GLuint, ProgramInfo> programs_;
  GLuint record_binding_ = 0, count_binding_ = 0;
  GLuint record_buffer_ = 0;
  // Verify: the interposer's own target (RGBA32F + a depth renderbuffer in the
  // application's depth format) and per-pixel counters.
  GLuint verify_fb_ = 0, verify_colour_ = 0, verify_depth_ = 0, count_buffer_ = 0;
  GLenum verify_depth_format_ = 0;
  uint32_t frame_w_ = 0, frame_h_ = 0, verify_w_ = 0, verify_h_ = 0;
  bool verify_used_ = false;  // a verify drawing happened in this frame (target cleared)
  uint32_t deleted_[stream::kDeletedKindCount] = {};  // EndChunk::deleted
};

}  // namespace oit::capture::interposer
