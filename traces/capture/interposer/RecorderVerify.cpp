// --verify inside the retracer: each captured transparent draw is drawn a second
// time (the check drawing), before the recording draw, into the interposer's own
// RGBA32F target (cleared to 0 at the frame's first such draw) with the
// application's blend state and a copy of the application's depth buffer, the
// injected code counting fragments per pixel and recording them (kCheckDraw). At
// the swap, the target and the counts go into the stream (kVerify).
#include <algorithm>
#include <string>
#include <vector>

#include "traces/capture/interposer/Recorder.hpp"

namespace oit::capture::interposer {

using namespace stream;

namespace {
constexpr GLenum kClampFragmentColor = 0x891B;  // GL_CLAMP_FRAGMENT_COLOR (compatibility profile, glext.h)
}  // namespace

void Recorder::ensureVerifyTarget() {
  RealGl& g = gl();
  if (verify_fb_ && verify_w_ == frame_w_ && verify_h_ == frame_h_) return;
  GLint saved_tex = 0, saved_fb = 0;
  g.glGetIntegerv(GL_TEXTURE_BINDING_2D, &saved_tex);
  g.glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &saved_fb);
  if (!verify_fb_) {
    g.glGenFramebuffers(1, &verify_fb_);
    g.glGenBuffers(1, &count_buffer_);
  }
  // A new texture of the new size (immutable storage cannot be resized); the old
  // one is deleted (still attached to verify_fb_, which is not bound: GL frees it
  // when the new texture replaces it there), once it is known to be still ours: a
  // name the application deleted and GL gave to one of its own textures must not go.
  if (verify_colour_) {
    checkVerifyTarget("found when the frame's size changed");
    g.glDeleteTextures(1, &verify_colour_);
    ++deleted_[kDeletedVerifyTexture];
  }
  g.glGenTextures(1, &verify_colour_);
  g.glBindTexture(GL_TEXTURE_2D, verify_colour_);
  g.glTexStorage2D(GL_TEXTURE_2D, 1, GL_RGBA32F, static_cast<GLsizei>(frame_w_), static_cast<GLsizei>(frame_h_));
  g.glBindTexture(GL_TEXTURE_2D, static_cast<GLuint>(saved_tex));
  g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, verify_fb_);
  g.glFramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, verify_colour_, 0);
  g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(saved_fb));
  verify_depth_format_ = 0;  // re-created at the new size when needed
  GLint saved_buf = 0;
  g.glGetIntegerv(GL_COPY_WRITE_BUFFER_BINDING, &saved_buf);
  g.glBindBuffer(GL_COPY_WRITE_BUFFER, count_buffer_);
  g.glBufferData(GL_COPY_WRITE_BUFFER, static_cast<GLsizeiptr>(uint64_t(frame_w_) * frame_h_ * 4), nullptr,
                 GL_DYNAMIC_READ);
  g.glBindBuffer(GL_COPY_WRITE_BUFFER, static_cast<GLuint>(saved_buf));
  verify_w_ = frame_w_;
  verify_h_ = frame_h_;
  verify_used_ = false;
}

// Copies the application's depth buffer into the verify target's, in the same
// format (a blit of depth demands it); no depth attachment when the application
// has no depth buffer (the test then passes, as in GL).
void Recorder::copyDepth(GLint app_fb) {
  RealGl& g = gl();
  const GLenum attachment = app_fb ? GL_DEPTH_ATTACHMENT : GL_DEPTH;
  GLint type = GL_NONE;
  g.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, attachment, GL_FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE,
                                          &type);
  GLint depth_bits = 0, stencil_bits = 0, component = 0;
  if (type != GL_NONE) {
    g.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, attachment, GL_FRAMEBUFFER_ATTACHMENT_DEPTH_SIZE,
                                            &depth_bits);
    g.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, attachment,
                                            GL_FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE, &component);
    const GLenum stencil_attachment = app_fb ? GL_STENCIL_ATTACHMENT : GL_STENCIL;
    GLint stype = GL_NONE;
    g.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, stencil_attachment,
                                            GL_FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE, &stype);
    if (stype != GL_NONE)
      g.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, stencil_attachment,
                                              GL_FRAMEBUFFER_ATTACHMENT_STENCIL_SIZE, &stencil_bits);
  }
  GLint saved_read = 0;
  g.glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &saved_read);
  g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, verify_fb_);
  if (depth_bits == 0) {
    g.glFramebufferRenderbuffer(GL_DRAW_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, 0);
    return;
  }
  const GLenum format = [&]() -> GLenum {
    const bool is_float = component == GL_FLOAT;
    if (stencil_bits > 0) return is_float ? GL_DEPTH32F_STENCIL8 : GL_DEPTH24_STENCIL8;
    if (is_float) return static_cast<GLenum>(GL_DEPTH_COMPONENT32F);
    if (depth_bits <= 16) return static_cast<GLenum>(GL_DEPTH_COMPONENT16);
    if (depth_bits <= 24) return static_cast<GLenum>(GL_DEPTH_COMPONENT24);
    return static_cast<GLenum>(GL_DEPTH_COMPONENT32);
  }();
  if (format != verify_depth_format_) {
    GLint saved_rb = 0;
    g.glGetIntegerv(GL_RENDERBUFFER_BINDING, &saved_rb);
    // The old renderbuffer (another size or format) goes: verify_fb_ is bound, so
    // deleting it also detaches it there.
    if (verify_depth_) {
      g.glDeleteRenderbuffers(1, &verify_depth_);
      ++deleted_[kDeletedVerifyRenderbuffer];
    }
    g.glGenRenderbuffers(1, &verify_depth_);
    g.glBindRenderbuffer(GL_RENDERBUFFER, verify_depth_);
    g.glRenderbufferStorage(GL_RENDERBUFFER, format, static_cast<GLsizei>(verify_w_), static_cast<GLsizei>(verify_h_));
    g.glBindRenderbuffer(GL_RENDERBUFFER, static_cast<GLuint>(saved_rb));
    verify_depth_format_ = format;
  }
  g.glFramebufferRenderbuffer(GL_DRAW_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, 0);
  const GLenum ours = stencil_bits > 0 ? GL_DEPTH_STENCIL_ATTACHMENT : GL_DEPTH_ATTACHMENT;
  g.glFramebufferRenderbuffer(GL_DRAW_FRAMEBUFFER, ours, GL_RENDERBUFFER, verify_depth_);
  g.glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(app_fb));
  const bool scissor = g.glIsEnabled(GL_SCISSOR_TEST);
  if (scissor) g.glDisable(GL_SCISSOR_TEST);
  const GLint w = static_cast<GLint>(verify_w_), h = static_cast<GLint>(verify_h_);
  g.glBlitFramebuffer(0, 0, w, h, 0, 0, w, h, GL_DEPTH_BUFFER_BIT, GL_NEAREST);
  if (scissor) g.glEnable(GL_SCISSOR_TEST);
  g.glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(saved_read));
}

void Recorder::checkVerifyTarget(const std::string& when) {
  RealGl& g = gl();
  bool ours = g.glIsTexture(verify_colour_);
  if (ours && g.glGetTextureLevelParameteriv) {  // a name GL gave again: not our RGBA32F of the frame's size
    GLint format = 0, w = 0, h = 0;
    g.glGetTextureLevelParameteriv(verify_colour_, 0, GL_TEXTURE_INTERNAL_FORMAT, &format);
    g.glGetTextureLevelParameteriv(verify_colour_, 0, GL_TEXTURE_WIDTH, &w);
    g.glGetTextureLevelParameteriv(verify_colour_, 0, GL_TEXTURE_HEIGHT, &h);
    ours = format == GL_RGBA32F && w == static_cast<GLint>(verify_w_) && h == static_cast<GLint>(verify_h_);
  }
  if (!ours)
    fail("frame " + std::to_string(frame_) + ": the interposer's --verify colour texture (GL name " + std::to_string(verify_colour_) + ") was deleted " +
         "by a call the interposer does not see (" + when + "; the trace deletes a texture name it never created, " +
         "which glretrace passes on unchanged): --verify cannot check the frame; capture it without --verify");
}

void Recorder::enterVerify(Pending& p) {
  RealGl& g = gl();
  ensureVerifyTarget();
  checkVerifyTarget("found at draw " + std::to_string(p.chunk.index) + "'s check drawing");
  g.glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &p.saved_draw_fb);
  g.glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &p.saved_read_fb);
  if (!verify_used_) {
    // The frame's first verify drawing: clear the target and the counters. Clears
    // obey the scissor and the colour mask: both off for the clear.
    g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, verify_fb_);
    const bool scissor = g.glIsEnabled(GL_SCISSOR_TEST);
    if (scissor) g.glDisable(GL_SCISSOR_TEST);
    GLboolean mask[4] = {};
    g.glGetBooleani_v(GL_COLOR_WRITEMASK, 0, mask);
    g.glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    const float zero[4] = {0, 0, 0, 0};
    g.glClearBufferfv(GL_COLOR, 0, zero);
    g.glColorMask(mask[0], mask[1], mask[2], mask[3]);
    if (scissor) g.glEnable(GL_SCISSOR_TEST);
    g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(p.saved_draw_fb));
    zeroBuffer(count_buffer_, static_cast<GLsizeiptr>(uint64_t(verify_w_) * verify_h_ * 4));
    verify_used_ = true;
  }
  if (p.chunk.state.depth_test)
    copyDepth(p.saved_draw_fb);  // leaves the verify target bound for drawing
  else {
    g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, verify_fb_);
    g.glFramebufferRenderbuffer(GL_DRAW_FRAMEBUFFER, GL_DEPTH_STENCIL_ATTACHMENT, GL_RENDERBUFFER, 0);
  }
  // The trace holds colours clamped into [0, 1], which is also what the
  // application's usual fixed-point target blends; clamp the verify drawing into
  // the float target the same way (compatibility contexts; a core context has no
  // clamp and its unclamped colours are reported, CAPTURE.md).
  if (g.glClampColor) {
    GLint clamp = 0;
    g.glGetIntegerv(kClampFragmentColor, &clamp);
    if (g.glGetError() == GL_NO_ERROR) {
      g.glClampColor(kClampFragmentColor, GL_TRUE);
      if (g.glGetError() == GL_NO_ERROR) p.saved_clamp = clamp;
    }
  }
  p.counts = bindStorage(count_binding_, count_buffer_);
  g.glProgramUniform1ui(p.chunk.program, p.info->loc_width, verify_w_);
  // The check drawing records its own fragments too: GL's blend is compared with
  // the records GL blended, and those with the application's drawing's records
  // (llvmpipe shades a draw per render-target format: the two drawings' colours
  // can differ, traces/CAPTURE.md).
  arm(p);
  g.glProgramUniform1ui(p.chunk.program, p.info->loc_mode, 3);
}

void Recorder::leaveVerify(Pending& p) {
  RealGl& g = gl();
  takeRecords(p, p.chunk, kCheckDraw);  // recording off, the application's binding back
  if (p.saved_clamp >= 0) g.glClampColor(kClampFragmentColor, static_cast<GLenum>(p.saved_clamp));
  restoreStorage(count_binding_, p.counts);
  g.glBindFramebuffer(GL_DRAW_FRAMEBUFFER, static_cast<GLuint>(p.saved_draw_fb));
  g.glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(p.saved_read_fb));
}

void Recorder::writeVerify() {
  RealGl& g = gl();
  const FrameChunk f{frame_, frame_w_, frame_h_, 0};
  const size_t pixels = size_t(frame_w_) * frame_h_;
  std::vector<float> rgba(pixels * 4, 0.0f);
  std::vector<uint32_t> counts(pixels, 0);
  if (verify_used_ && verify_w_ == frame_w_ && verify_h_ == frame_h_) {
    checkVerifyTarget("found at the frame's end");
    g.glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT | GL_FRAMEBUFFER_BARRIER_BIT);
    GLint saved_read = 0, saved_pack = 0, align = 4, row = 0, skip_rows = 0, skip_pixels = 0;
    g.glGetIntegerv(GL_READ_FRAMEBUFFER_BINDING, &saved_read);
    g.glGetIntegerv(GL_PIXEL_PACK_BUFFER_BINDING, &saved_pack);
    g.glGetIntegerv(GL_PACK_ALIGNMENT, &align);
    g.glGetIntegerv(GL_PACK_ROW_LENGTH, &row);
    g.glGetIntegerv(GL_PACK_SKIP_ROWS, &skip_rows);
    g.glGetIntegerv(GL_PACK_SKIP_PIXELS, &skip_pixels);
    g.glBindBuffer(GL_PIXEL_PACK_BUFFER, 0);
    g.glPixelStorei(GL_PACK_ALIGNMENT, 4);
    g.glPixelStorei(GL_PACK_ROW_LENGTH, 0);
    g.glPixelStorei(GL_PACK_SKIP_ROWS, 0);
    g.glPixelStorei(GL_PACK_SKIP_PIXELS, 0);
    g.glBindFramebuffer(GL_READ_FRAMEBUFFER, verify_fb_);
    g.glReadPixels(0, 0, static_cast<GLsizei>(frame_w_), static_cast<GLsizei>(frame_h_), GL_RGBA, GL_FLOAT,
                   rgba.data());
    g.glBindFramebuffer(GL_READ_FRAMEBUFFER, static_cast<GLuint>(saved_read));
    g.glBindBuffer(GL_PIXEL_PACK_BUFFER, static_cast<GLuint>(saved_pack));
    g.glPixelStorei(GL_PACK_ALIGNMENT, align);
    g.glPixelStorei(GL_PACK_ROW_LENGTH, row);
    g.glPixelStorei(GL_PACK_SKIP_ROWS, skip_rows);
    g.glPixelStorei(GL_PACK_SKIP_PIXELS, skip_pixels);
    readBuffer(count_buffer_, 0, static_cast<GLsizeiptr>(pixels * 4), counts.data());
  }
  // Payload: the frame chunk; then the image and the counts.
  write(kVerify, &f, sizeof f, rgba.data(), rgba.size() * sizeof(float));
  std::fwrite(counts.data(), sizeof(uint32_t), counts.size(), out_);
}

}  // namespace oit::capture::interposer
