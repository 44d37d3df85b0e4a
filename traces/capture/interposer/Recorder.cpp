#include "traces/capture/interposer/Recorder.hpp"

#include <dlfcn.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <iterator>

#include "traces/capture/interposer/BlendClass.hpp"

namespace oit::capture::interposer {

using namespace stream;

namespace {

constexpr GLsizeiptr kRecordHeaderBytes = 16;  // the counter, padded to the records' alignment

uint16_t enum16(GLint v) { return static_cast<uint16_t>(v); }

}  // namespace

Recorder& Recorder::get() {
  static Recorder r;
  return r;
}

Recorder::Recorder() {
  const char* path = std::getenv("OITSIM_STREAM");
  if (!path || !*path) return;
  const char* frames = std::getenv("OITSIM_FRAMES");
  unsigned a = 0, b = 0;
  if (!frames || std::sscanf(frames, "%u-%u", &a, &b) != 2 || a > b) return;
  out_ = std::fopen(path, "wb");
  if (!out_) return;
  static char buffer[1 << 20];
  std::setvbuf(out_, buffer, _IOFBF, sizeof buffer);
  first_ = a;
  last_ = b;
  verify_ = std::getenv("OITSIM_VERIFY") && std::strcmp(std::getenv("OITSIM_VERIFY"), "1") == 0;
  if (const char* m = std::getenv("OITSIM_MAX_RECORDS")) max_records_ = std::strtoull(m, nullptr, 10);
  if (const char* k = std::getenv("OITSIM_RECORDS_PER_PIXEL")) records_per_pixel_ = std::strtod(k, nullptr);
  StreamHeader h{};
  std::memcpy(h.magic, kMagic, sizeof h.magic);
  h.first_frame = first_;
  h.last_frame = last_;
  std::fwrite(&h, sizeof h, 1, out_);
  active_ = true;
}

void Recorder::write(uint32_t tag, const void* payload, uint32_t bytes, const void* extra, uint64_t extra_bytes) {
  const ChunkHeader c{tag, bytes};
  std::fwrite(&c, sizeof c, 1, out_);
  if (bytes) std::fwrite(payload, bytes, 1, out_);
  if (extra_bytes) std::fwrite(extra, extra_bytes, 1, out_);
}

void Recorder::finishStream(bool range_done) {
  if (!active_ || ended_) return;
  ended_ = true;
  EndChunk e{frame_, range_done ? 1u : 0u, capacity_, limit_, {}, 0};
  std::copy(std::begin(deleted_), std::end(deleted_), std::begin(e.deleted));
  write(kEnd, &e, sizeof e);
  std::fclose(out_);
  out_ = nullptr;
}

void Recorder::fail(const std::string& message) {
  write(kError, message.data(), static_cast<uint32_t>(message.size()));
  finishStream(false);
  std::_Exit(3);  // the retracer stops here; oitsim reports the error
}

void Recorder::atExit() { finishStream(false); }

void Recorder::ensureGl() {
  if (gl_ready_) return;
  if (const char* missing = gl().load(); *missing)
    fail(std::string("the GL library has no ") + missing + " (the capture needs OpenGL 4.3 or OpenGL ES 3.1)");
  RealGl& g = gl();
  GLint bindings = 0;
  g.glGetIntegerv(GL_MAX_SHADER_STORAGE_BUFFER_BINDINGS, &bindings);
  if (bindings < 2) fail("the context has fewer than 2 shader storage buffer bindings (OpenGL 4.3 needed)");
  record_binding_ = static_cast<GLuint>(bindings - 1);
  count_binding_ = static_cast<GLuint>(bindings - 2);
  gl_ready_ = true;
}

// ---------------------------------------------------------------- programs

void Recorder::forgetProgram(GLuint program) {
  if (active_ && programs_.erase(program)) ++deleted_[kDeletedProgram];
}

// ---------------------------------------------------------------- draws

bool Recorder::drawableSize(uint32_t& w, uint32_t& h) const {
  using GetCurrent = void* (*)();
  using GetSurface = void* (*)(int);
  using Query = unsigned (*)(void*, void*, int, int*);
  static void* egl = dlopen("libEGL.so.1", RTLD_LAZY | RTLD_NOLOAD);
  if (egl) {
    static auto display = reinterpret_cast<GetCurrent>(dlsym(egl, "eglGetCurrentDisplay"));
    static auto surface = reinterpret_cast<GetSurface>(dlsym(egl, "eglGetCurrentSurface"));
    static auto query = reinterpret_cast<Query>(dlsym(egl, "eglQuerySurface"));
    if (display && surface && query) {
      void* d = display();
      void* s = surface(0x3059);  // EGL_DRAW
      int ew = 0, eh = 0;
      if (d && s && query(d, s, 0x3057, &ew) && query(d, s, 0x3056, &eh) && ew > 0 && eh > 0) {
        w = static_cast<uint32_t>(ew);
        h = static_cast<uint32_t>(eh);
        return true;
      }
    }
  }
  using GlxDisplay = void* (*)();
  using GlxDrawable = unsigned long (*)();
  using GlxQuery = void (*)(void*, unsigned long, int, unsigned*);
  static auto gdisplay = reinterpret_cast<GlxDisplay>(realProc("glXGetCurrentDisplay"));
  static auto gdrawable = reinterpret_cast<GlxDrawable>(realProc("glXGetCurrentDrawable"));
  static auto gquery = reinterpret_cast<GlxQuery>(realProc("glXQueryDrawable"));
  if (gdisplay && gdrawable && gquery) {
    void* d = gdisplay();
    const unsigned long drawable = gdrawable();
    unsigned gw = 0, gh = 0;
    if (d && drawable) {
      gquery(d, drawable, 0x801D, &gw);  // GLX_WIDTH
      gquery(d, drawable, 0x801E, &gh);  // GLX_HEIGHT
      if (gw && gh) {
        w = gw;
        h = gh;
        return true;
      }
    }
  }
  return false;
}

void Recorder::targetSize(GLint fb, GLenum attachment, uint32_t& w, uint32_t& h) const {
  RealGl& g = gl();
  w = h = 0;
  if (fb == 0) {
    w = frame_w_;
    h = frame_h_;
    return;
  }
  GLint type = 0, name = 0, level = 0;
  g.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, attachment, GL_FRAMEBUFFER_ATTACHMENT_OBJECT_TYPE, &type);
  g.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, attachment, GL_FRAMEBUFFER_ATTACHMENT_OBJECT_NAME, &name);
  GLint iw = 0, ih = 0;
  if (type == GL_TEXTURE && g.glGetTextureLevelParameteriv) {
    g.glGetFramebufferAttachmentParameteriv(GL_DRAW_FRAMEBUFFER, attachment, GL_FRAMEBUFFER_ATTACHMENT_TEXTURE_LEVEL,
                                            &level);
    g.glGetTextureLevelParameteriv(static_cast<GLuint>(name), level, GL_TEXTURE_WIDTH, &iw);
    g.glGetTextureLevelParameteriv(static_cast<GLuint>(name), level, GL_TEXTURE_HEIGHT, &ih);
  } else if (type == GL_RENDERBUFFER && g.glGetNamedRenderbufferParameteriv) {
    g.glGetNamedRenderbufferParameteriv(static_cast<GLuint>(name), GL_RENDERBUFFER_WIDTH, &iw);
    g.glGetNamedRenderbufferParameteriv(static_cast<GLuint>(name), GL_RENDERBUFFER_HEIGHT, &ih);
  }
  w = static_cast<uint32_t>(std::max(iw, 0));
  h = static_cast<uint32_t>(std::max(ih, 0));
}

void Recorder::readState(DrawState& s) {
  RealGl& g = gl();
  GLint v = 0;
  s.depth_test = g.glIsEnabled(GL_DEPTH_TEST) ? 1 : 0;
  GLboolean mask = GL_FALSE;
  g.glGetIntegerv(GL_DEPTH_WRITEMASK, &v);
  mask = v ? GL_TRUE : GL_FALSE;
  s.depth_write = s.depth_test && mask ? 1 : 0;  // no depth writes without the test
  if (s.depth_test) {
    g.glGetIntegerv(GL_DEPTH_FUNC, &v);
    s.depth_func = enum16(v);
  }
  const bool blend = g.glIsEnabled(GL_BLEND);
  if (blend) {
    GLint e[6] = {};
    g.glGetIntegerv(GL_BLEND_EQUATION_RGB, &e[0]);
    g.glGetIntegerv(GL_BLEND_SRC_RGB, &e[1]);
    g.glGetIntegerv(GL_BLEND_DST_RGB, &e[2]);
    g.glGetIntegerv(GL_BLEND_EQUATION_ALPHA, &e[3]);
    g.glGetIntegerv(GL_BLEND_SRC_ALPHA, &e[4]);
    g.glGetIntegerv(GL_BLEND_DST_ALPHA, &e[5]);
    s.blend_eq_rgb = enum16(e[0]);
    s.blend_src_rgb = enum16(e[1]);
    s.blend_dst_rgb = enum16(e[2]);
    s.blend_eq_alpha = enum16(e[3]);
    s.blend_src_alpha = enum16(e[4]);
    s.blend_dst_alpha = enum16(e[5]);
    s.blend_mode = classifyBlend(true, static_cast<uint32_t>(e[0]), static_cast<uint32_t>(e[1]),
                                 static_cast<uint32_t>(e[2]));
  } else {
    s.blend_mode = kBlendOff;
  }
}

uint32_t Recorder::classify(Pending& p, GLint program) {
  RealGl& g = gl();
  if (g.glIsEnabled(GL_RASTERIZER_DISCARD)) return kRasterizerDiscard;
  if (program == 0) {
    GLint pipeline = 0;
    g.glGetIntegerv(GL_PROGRAM_PIPELINE_BINDING, &pipeline);
    return pipeline ? kSeparablePipeline : kFixedFunction;
  }
  auto it = programs_.find(static_cast<GLuint>(program));
  if (it == programs_.end()) return kNotRewritten;
  if (!it->second.rewritten) return it->second.reason;
  p.info = &it->second;
  p.chunk.state.early_tests = it->second.early_tests ? 1 : 0;

  GLint fb = 0;
  g.glGetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &fb);
  p.chunk.window = fb == 0 ? 1 : 0;
  GLint max_buffers = 1;
  g.glGetIntegerv(GL_MAX_DRAW_BUFFERS, &max_buffers);
  int active = 0;
  GLint first = GL_NONE, first_slot = -1;
  for (GLint i = 0; i < max_buffers && i < 16; ++i) {
    GLint b = GL_NONE;
    g.glGetIntegerv(GL_DRAW_BUFFER0 + i, &b);
    if (b == GL_NONE) continue;
    if (active++ == 0) first = b, first_slot = i;
  }
  GLboolean m[4] = {};
  g.glGetBooleani_v(GL_COLOR_WRITEMASK, 0, m);
  if (active == 0 || !(m[0] || m[1] || m[2] || m[3])) return kColourWritesOff;
  if (active > 1 || first_slot != 0) return kSeveralTargets;
  GLint samples = 0;
  g.glGetIntegerv(GL_SAMPLE_BUFFERS, &samples);
  if (samples > 0) return kMultisample;
  if (g.glIsEnabled(GL_STENCIL_TEST)) {
    GLint front = GL_ALWAYS, back = GL_ALWAYS;
    g.glGetIntegerv(GL_STENCIL_FUNC, &front);
    g.glGetIntegerv(GL_STENCIL_BACK_FUNC, &back);
    if (front != GL_ALWAYS || back != GL_ALWAYS) return kStencil;
  }
  uint32_t w = 0, h = 0;
  targetSize(fb, fb ? static_cast<GLenum>(first) : GL_BACK, w, h);
  p.chunk.width = w;
  p.chunk.height = h;
  if (w != frame_w_ || h != frame_h_ || w == 0) return kTargetSize;
  return kCaptured;
}

// What every listed draw's chunk says: its place in the frame, the function, the
// program and the state; returns the program.
GLint Recorder::describe(const char* function, bool multi, DrawChunk& c) {
  ensureGl();
  c.frame = frame_;
  c.index = draw_index_++;
  c.instanced = multi ? 1 : 0;
  std::strncpy(c.function, function, sizeof c.function - 1);
  GLint program = 0;
  gl().glGetIntegerv(GL_CURRENT_PROGRAM, &program);
  c.program = static_cast<uint32_t>(program);
  readState(c.state);
  return program;
}

bool Recorder::begin(const char* function, bool multi, Pending& p) {
  if (!inRange()) return false;
  const GLint program = describe(function, multi, p.chunk);
  uint32_t w = 0, h = 0;
  if (drawableSize(w, h)) frame_w_ = w, frame_h_ = h;
  DrawChunk& c = p.chunk;
  c.reason = classify(p, program);
  p.verify = verify_ && c.reason == kCaptured &&
             (c.state.blend_mode == kBlendOver || c.state.blend_mode == kBlendPremulOver);
  return true;
}

void Recorder::uncapturable(const char* function, uint32_t reason_with_program, uint32_t reason_without) {
  if (!inRange()) return;
  DrawChunk c{};
  c.reason = describe(function, false, c) ? reason_with_program : reason_without;
  write(kDraw, &c, sizeof c);
}

Recorder::SavedBinding Recorder::bindStorage(GLuint index, GLuint buffer) {
  RealGl& g = gl();
  SavedBinding s;
  g.glGetIntegeri_v(GL_SHADER_STORAGE_BUFFER_BINDING, index, &s.buffer);
  g.glGetInteger64i_v(GL_SHADER_STORAGE_BUFFER_START, index, &s.start);
  g.glGetInteger64i_v(GL_SHADER_STORAGE_BUFFER_SIZE, index, &s.size);
  GLint generic = 0;
  g.glGetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &generic);
  g.glBindBufferBase(GL_SHADER_STORAGE_BUFFER, index, buffer);
  g.glBindBuffer(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(generic));
  return s;
}

void Recorder::restoreStorage(GLuint index, const SavedBinding& s) {
  RealGl& g = gl();
  GLint generic = 0;
  g.glGetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &generic);
  if (s.buffer && s.size > 0)
    g.glBindBufferRange(GL_SHADER_STORAGE_BUFFER, index, static_cast<GLuint>(s.buffer), s.start, s.size);
  else
    g.glBindBufferBase(GL_SHADER_STORAGE_BUFFER, index, static_cast<GLuint>(s.buffer));
  g.glBindBuffer(GL_SHADER_STORAGE_BUFFER, static_cast<GLuint>(generic));
}

// Buffer updates and reads go through GL_COPY_WRITE_BUFFER, saved and restored,
// so no binding the application sees changes.
void Recorder::zeroBuffer(GLuint buffer, GLsizeiptr bytes) {
  RealGl& g = gl();
  GLint saved = 0;
  g.glGetIntegerv(GL_COPY_WRITE_BUFFER_BINDING, &saved);
  g.glBindBuffer(GL_COPY_WRITE_BUFFER, buffer);
  std::vector<uint8_t> zeros(static_cast<size_t>(bytes), 0);
  g.glBufferSubData(GL_COPY_WRITE_BUFFER, 0, bytes, zeros.data());
  g.glBindBuffer(GL_COPY_WRITE_BUFFER, static_cast<GLuint>(saved));
}

void Recorder::readBuffer(GLuint buffer, GLintptr offset, GLsizeiptr bytes, void* out) {
  mapBuffer(buffer, offset, bytes, [&](const void* p) { std::memcpy(out, p, static_cast<size_t>(bytes)); });
}

void Recorder::mapBuffer(GLuint buffer, GLintptr offset, GLsizeiptr bytes, const std::function<void(const void*)>& use) {
  if (bytes <= 0) return;
  RealGl& g = gl();
  GLint saved = 0;
  g.glGetIntegerv(GL_COPY_WRITE_BUFFER_BINDING, &saved);
  g.glBindBuffer(GL_COPY_WRITE_BUFFER, buffer);
  const void* p = g.glMapBufferRange(GL_COPY_WRITE_BUFFER, offset, bytes, GL_MAP_READ_BIT);
  if (!p) fail("glMapBufferRange of the record buffer failed (GL error " + std::to_string(g.glGetError()) + ")");
  use(p);
  g.glUnmapBuffer(GL_COPY_WRITE_BUFFER);
  g.glBindBuffer(GL_COPY_WRITE_BUFFER, static_cast<GLuint>(saved));
}

void Recorder::arm(Pending& p) {
  RealGl& g = gl();
  if (!record_buffer_) {
    GLint64 max_block = 0;
    g.glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
    limit_ = (static_cast<uint64_t>(max_block) - kRecordHeaderBytes) / sizeof(GpuRecord);
    capacity_ = max_records_ ? std::min(max_records_, limit_) : limit_;
    // llvmpipe zero-fills the whole buffer when it is created: at GL's largest
    // block (128 MiB on Mesa 22) the kernel's zeroing of its pages was the
    // retracer's largest cost. Sized to the frame instead; a draw that outgrows it
    // is reported as overflowing, with its count, and oitsim captures again with
    // room for it (ApitraceCapture.cpp).
    if (records_per_pixel_ > 0)
      capacity_ = std::min(capacity_, std::max<uint64_t>(1, static_cast<uint64_t>(records_per_pixel_ * frame_w_ *
                                                                                   double(frame_h_))));
    GLint saved = 0;
    g.glGetIntegerv(GL_COPY_WRITE_BUFFER_BINDING, &saved);
    g.glGenBuffers(1, &record_buffer_);
    g.glBindBuffer(GL_COPY_WRITE_BUFFER, record_buffer_);
    g.glBufferData(GL_COPY_WRITE_BUFFER, kRecordHeaderBytes + static_cast<GLsizeiptr>(capacity_ * sizeof(GpuRecord)),
                   nullptr, GL_DYNAMIC_READ);
    g.glBindBuffer(GL_COPY_WRITE_BUFFER, static_cast<GLuint>(saved));
    if (GLenum e = g.glGetError(); e != GL_NO_ERROR)
      fail("allocating the record buffer (" + std::to_string(capacity_) + " records) failed: GL error " +
           std::to_string(e));
  }
  zeroBuffer(record_buffer_, kRecordHeaderBytes);
  p.records = bindStorage(record_binding_, record_buffer_);
  const GLuint prog = p.chunk.program;
  g.glProgramUniform1ui(prog, p.info->loc_draw, p.chunk.index);
  g.glProgramUniform1ui(prog, p.info->loc_capacity, static_cast<GLuint>(std::min<uint64_t>(capacity_, UINT32_MAX)));
  g.glProgramUniform1ui(prog, p.info->loc_mode, 1);
}

void Recorder::takeRecords(const Pending& p, DrawChunk c, uint32_t tag) {
  RealGl& g = gl();
  g.glProgramUniform1ui(c.program, p.info->loc_mode, 0);
  restoreStorage(record_binding_, p.records);  // bound only for the draw
  g.glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_SHADER_STORAGE_BARRIER_BIT);
  uint32_t count = 0;
  readBuffer(record_buffer_, 0, sizeof count, &count);
  c.fragments = count;
  if (count > capacity_) {
    c.reason = kOverflow;
    write(tag, &c, sizeof c);
    return;
  }
  c.records = count;
  // Straight from the mapping to the stream: a copy in between cost a 46 MB
  // allocation and its page faults per draw on the glmark2 frame.
  const auto bytes = static_cast<GLsizeiptr>(uint64_t(count) * sizeof(GpuRecord));
  if (bytes == 0) write(tag, &c, sizeof c);
  mapBuffer(record_buffer_, kRecordHeaderBytes, bytes,
            [&](const void* records) { write(tag, &c, sizeof c, records, static_cast<uint64_t>(bytes)); });
}

void Recorder::finish(Pending& p) {
  if (p.chunk.reason != kCaptured) {
    write(kDraw, &p.chunk, sizeof p.chunk);
    return;
  }
  takeRecords(p, p.chunk, kDraw);
}

void Recorder::swap() {
  if (!active_ || ended_) return;
  if (inRange()) {
    uint32_t w = 0, h = 0;
    if (drawableSize(w, h)) frame_w_ = w, frame_h_ = h;
    if (verify_) writeVerify();
    const FrameChunk f{frame_, frame_w_, frame_h_, 0};
    write(kFrame, &f, sizeof f);
    std::fflush(out_);
  }
  ++frame_;
  draw_index_ = 0;
  verify_used_ = false;
  if (frame_ > last_) {
    finishStream(true);
    std::_Exit(0);  // nothing after the range is needed
  }
}

}  // namespace oit::capture::interposer
