#include "traces/capture/GlCapture.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <memory>
#include <utility>

#include <fmt/format.h>

#include "traces/capture/CaptureScene.hpp"
#include "traces/capture/EglContext.hpp"
#include "traces/capture/GlEntryPoints.hpp"
#include "traces/capture/interposer/CaptureStream.hpp"

namespace oit::capture {

using namespace gl;  // the entry points, loaded at run time (GlEntryPoints.hpp)

namespace {

// One record of the storage buffer (std430, 32 bytes): the same layout as the
// apitrace interposer's records.
using stream::GpuRecord;

constexpr const char* kVertexShader = R"(#version 450 core
layout(location = 0) in vec4 a_clip;    // computed on the CPU exactly as oitsim gen does
layout(location = 1) in vec3 a_world;
layout(location = 2) in vec3 a_normal;  // the face normal, same on all three vertices
out vec3 v_world;
flat out vec3 v_normal;
void main() {
  v_world = a_world;
  v_normal = a_normal;
  gl_Position = a_clip;
}
)";

// No layout(early_fragment_tests): the record pass runs with every test off, and
// the record must not depend on any later pass's depth state.
constexpr const char* kFragmentShader = R"(#version 450 core
struct Rec { uint xy; float z; uint prim; uint draw; vec4 rgba; };
layout(std430, binding = 0) restrict writeonly buffer Records { Rec recs[]; };
layout(binding = 0, offset = 0) uniform atomic_uint u_counter;
uniform int u_pass;      // 0 = record, 1 = colour, 2 = count
uniform int u_shade;     // ShadeMode
uniform uint u_draw, u_prim_base, u_capacity;
uniform vec3 u_colour, u_dark, u_light, u_axis_u, u_axis_v;
uniform float u_alpha;
in vec3 v_world;
flat in vec3 v_normal;
layout(location = 0) out vec4 o_colour;

vec4 shade() {
  if (u_shade == 1) return vec4(u_colour * (0.35 + 0.65 * abs(dot(v_normal, u_light))), u_alpha);
  if (u_shade == 2) return vec4(u_colour * (0.35 + 0.65 * max(0.0, dot(v_normal, u_light))), u_alpha);
  if (u_shade == 3) {
    // Checker squares of 0.25 world units along the two surface axes.
    int odd = (int(floor(dot(v_world, u_axis_u) / 0.25)) + int(floor(dot(v_world, u_axis_v) / 0.25))) & 1;
    return vec4(odd != 0 ? u_dark : u_colour, u_alpha);
  }
  return vec4(u_colour, u_alpha);
}

void main() {
  // The trace format demands [0, 1]; the same clamped value is recorded and blended.
  vec4 c = clamp(shade(), 0.0, 1.0);
  if (u_pass == 0) {
    uint i = atomicCounterIncrement(u_counter);
    // Past the capacity only the count grows: the host sees the overflow and splits.
    if (i < u_capacity)
      recs[i] = Rec(uint(gl_FragCoord.x) | (uint(gl_FragCoord.y) << 16), gl_FragCoord.z,
                    u_prim_base + uint(gl_PrimitiveID), u_draw, c);
    o_colour = c;
  } else if (u_pass == 1) {
    o_colour = c;
  } else {
    o_colour = vec4(1.0);
  }
}
)";

}  // namespace

struct Capturer::Impl {
  CaptureOptions opts;
  std::unique_ptr<CaptureScene> scene;  // the meshes, camera and draw table (CaptureScene.hpp)
  TraceHeader header;
  std::unique_ptr<EglContext> egl;
  GLuint program = 0, vao = 0, vbo = 0, ssbo = 0, counter = 0, fbo = 0, colour_tex = 0, depth_rb = 0;
  uint64_t capacity = 0;
  std::string renderer, version;

  GLint uniform(const char* name) const { return glGetUniformLocation(program, name); }

  void initGl() {
    egl = std::make_unique<EglContext>();
    renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 45)
      throw GlError(fmt::format("OpenGL {}.{} ({}) is older than the 4.5 core the capture needs; {}",
                                major, minor, renderer, kGlInstallHint));

    const GLuint vs = compileShader(GL_VERTEX_SHADER, kVertexShader, "vertex shader");
    const GLuint fs = compileShader(GL_FRAGMENT_SHADER, kFragmentShader, "fragment shader");
    program = glCreateProgram();
    glAttachShader(program, vs);
    glAttachShader(program, fs);
    glLinkProgram(program);
    glDeleteShader(vs);
    glDeleteShader(fs);
    GLint ok = 0;
    glGetProgramiv(program, GL_LINK_STATUS, &ok);
    if (!ok) {
      char log[4096] = {};
      glGetProgramInfoLog(program, sizeof log, nullptr, log);
      throw GlError(fmt::format("glLinkProgram failed: {}", log));
    }
    checkGl("shader program creation");

    GLint64 max_block = 0;
    glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
    const uint64_t limit = static_cast<uint64_t>(max_block) / sizeof(GpuRecord);
    if (opts.max_records_per_draw > limit)
      throw std::invalid_argument(fmt::format(
          "--max-records-per-draw {} exceeds what one shader storage block holds here: {} records of "
          "{} bytes ({} MiB, GL_MAX_SHADER_STORAGE_BLOCK_SIZE)",
          opts.max_records_per_draw, limit, sizeof(GpuRecord), max_block >> 20));
    capacity = opts.max_records_per_draw ? opts.max_records_per_draw : limit;

    glCreateVertexArrays(1, &vao);
    glCreateBuffers(1, &vbo);
    glCreateBuffers(1, &ssbo);
    glCreateBuffers(1, &counter);
    glNamedBufferStorage(ssbo, static_cast<GLsizeiptr>(capacity * sizeof(GpuRecord)), nullptr,
                         GL_DYNAMIC_STORAGE_BIT);
    const GLuint zero = 0;
    glNamedBufferStorage(counter, sizeof zero, &zero, GL_DYNAMIC_STORAGE_BIT);
    checkGl(fmt::format("record buffer allocation ({} MiB)", capacity * sizeof(GpuRecord) >> 20).c_str());
    glVertexArrayVertexBuffer(vao, 0, vbo, 0, sizeof(Vertex));
    const GLuint offsets[3] = {offsetof(Vertex, clip), offsetof(Vertex, world), offsetof(Vertex, normal)};
    const GLint sizes[3] = {4, 3, 3};
    for (GLuint i = 0; i < 3; ++i) {
      glEnableVertexArrayAttrib(vao, i);
      glVertexArrayAttribFormat(vao, i, sizes[i], GL_FLOAT, GL_FALSE, offsets[i]);
      glVertexArrayAttribBinding(vao, i, 0);
    }

    // Colour (RGBA32F: the reference blend and the count) and a float depth buffer,
    // so depth tests compare exactly the window depths the trace records.
    glCreateTextures(GL_TEXTURE_2D, 1, &colour_tex);
    glTextureStorage2D(colour_tex, 1, GL_RGBA32F, opts.width, opts.height);
    glCreateRenderbuffers(1, &depth_rb);
    glNamedRenderbufferStorage(depth_rb, GL_DEPTH_COMPONENT32F, opts.width, opts.height);
    glCreateFramebuffers(1, &fbo);
    glNamedFramebufferTexture(fbo, GL_COLOR_ATTACHMENT0, colour_tex, 0);
    glNamedFramebufferRenderbuffer(fbo, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_rb);
    const GLenum status = glCheckNamedFramebufferStatus(fbo, GL_FRAMEBUFFER);
    if (status != GL_FRAMEBUFFER_COMPLETE)
      throw GlError(fmt::format("glCheckNamedFramebufferStatus: RGBA32F + DEPTH32F {}x{} framebuffer "
                                "incomplete (0x{:04X})", opts.width, opts.height, status));
    checkGl("framebuffer creation");

    glBindFramebuffer(GL_FRAMEBUFFER, fbo);
    glViewport(0, 0, static_cast<GLsizei>(opts.width), static_cast<GLsizei>(opts.height));
    glUseProgram(program);
    glBindVertexArray(vao);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, ssbo);
    glBindBufferBase(GL_ATOMIC_COUNTER_BUFFER, 0, counter);
    // Nothing may drop a fragment: no scissor, no multisampling; culling only
    // where gen culls (DrawGeom::cull_back, set per draw).
    glDisable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);  // gen's front faces: counter-clockwise in window coordinates
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_MULTISAMPLE);
    glDisable(GL_STENCIL_TEST);
    glUniform1ui(uniform("u_capacity"), static_cast<GLuint>(std::min<uint64_t>(capacity, UINT32_MAX)));
    checkGl("pipeline state");
  }

  void upload(const Scene& s) {
    // Orphan and refill: one buffer for the whole frame's soup.
    glNamedBufferData(vbo, static_cast<GLsizeiptr>(s.soup.size() * sizeof(Vertex)), s.soup.data(),
                      GL_STATIC_DRAW);
    checkGl(fmt::format("vertex upload ({} MiB)", s.soup.size() * sizeof(Vertex) >> 20).c_str());
  }

  void setPart(const Scene& s, uint32_t draw, const Part& p) {
    glUniform1i(uniform("u_shade"), p.shade);
    glUniform1ui(uniform("u_draw"), draw);
    glUniform3f(uniform("u_colour"), p.colour[0], p.colour[1], p.colour[2]);
    glUniform3f(uniform("u_dark"), p.dark[0], p.dark[1], p.dark[2]);
    glUniform3f(uniform("u_light"), s.light.x, s.light.y, s.light.z);
    glUniform3f(uniform("u_axis_u"), p.axis_u.x, p.axis_u.y, p.axis_u.z);
    glUniform3f(uniform("u_axis_v"), p.axis_v.x, p.axis_v.y, p.axis_v.z);
    glUniform1f(uniform("u_alpha"), p.alpha);
  }

  GLuint readCounter() {
    GLuint n = 0;
    glGetNamedBufferSubData(counter, 0, sizeof n, &n);
    return n;
  }
};

Capturer::Capturer(CaptureOptions opts) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  auto bad = [](const std::string& what) { throw std::invalid_argument(what); };
  if (opts.width < 1 || opts.height < 1 || opts.width > 16384 || opts.height > 16384)
    bad(fmt::format("frame size {}x{} is outside 1..16384 per axis (GL's framebuffer limit)", opts.width,
                    opts.height));
  if (opts.meshes.empty()) bad("no mesh to capture (--mesh NAME_OR_PATH)");
  if (opts.colours.size() > 1 && opts.colours.size() != opts.meshes.size())
    bad(fmt::format("{} colours for {} meshes: give one colour, or one per mesh", opts.colours.size(),
                    opts.meshes.size()));
  if (opts.alphas.size() > 1 && opts.alphas.size() != opts.meshes.size())
    bad(fmt::format("{} alphas for {} meshes: give one alpha, or one per mesh", opts.alphas.size(),
                    opts.meshes.size()));
  for (float a : opts.alphas)
    if (!(a >= 0 && a <= 1)) bad(fmt::format("alpha {} is outside [0, 1]", a));
  for (const auto& c : opts.colours)
    for (float v : c)
      if (!(v >= 0 && v <= 1)) bad(fmt::format("colour component {} is outside [0, 1]", v));
  if (opts.azimuth_deg && !std::isfinite(*opts.azimuth_deg)) bad("azimuth must be a finite angle");
  if (opts.elevation_deg && !(*opts.elevation_deg >= -89 && *opts.elevation_deg <= 89))
    bad(fmt::format("elevation {} is outside -89..89 degrees", *opts.elevation_deg));
  if (!std::isfinite(opts.distance) || opts.distance < 0)
    bad(fmt::format("distance {} must be >= 0 (0 fits the meshes)", opts.distance));
  if (opts.fov_deg && !(*opts.fov_deg > 1 && *opts.fov_deg < 170))
    bad(fmt::format("field of view {} is outside (1, 170) degrees", *opts.fov_deg));
  if (opts.meshes.size() > 1000) bad("at most 1000 meshes");
  m.opts = std::move(opts);
  m.scene = std::make_unique<CaptureScene>(m.opts);
  m.header = m.scene->header();
  m.initGl();
}

Capturer::~Capturer() {
  if (!impl_ || !impl_->egl) return;
  Impl& m = *impl_;
  glDeleteFramebuffers(1, &m.fbo);
  glDeleteRenderbuffers(1, &m.depth_rb);
  glDeleteTextures(1, &m.colour_tex);
  const GLuint bufs[3] = {m.vbo, m.ssbo, m.counter};
  glDeleteBuffers(3, bufs);
  glDeleteVertexArrays(1, &m.vao);
  glDeleteProgram(m.program);
}

const TraceHeader& Capturer::header() const { return impl_->header; }
std::string Capturer::renderer() const { return impl_->renderer; }
std::string Capturer::glVersion() const { return impl_->version; }
uint64_t Capturer::recordsPerDraw() const { return impl_->capacity; }

CaptureStats Capturer::capture(FragmentSink& sink, double azimuth_offset_deg) {
  Impl& m = *impl_;
  const auto t0 = std::chrono::steady_clock::now();
  const Scene s = m.scene->build(azimuth_offset_deg);
  m.upload(s);
  CaptureStats st;
  st.capacity = m.capacity;
  st.fragments_per_draw.assign(m.header.draws.size(), 0);

  // Record pass: no depth test, no blending, no colour writes; every fragment lands.
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_BLEND);
  glDepthMask(GL_FALSE);
  glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
  glUniform1i(m.uniform("u_pass"), 0);
  const GLint prim_base_loc = m.uniform("u_prim_base");
  std::vector<GpuRecord> recs;
  std::vector<Fragment> frags;
  const GLuint zero = 0;
  for (const DrawGeom& d : s.draws) {
    frags.clear();
    d.cull_back ? glEnable(GL_CULL_FACE) : glDisable(GL_CULL_FACE);
    uint64_t prim_base = 0;
    for (const Part& p : d.parts) {
      m.setPart(s, d.id, p);
      uint64_t done = 0, chunk = p.tris;
      while (done < p.tris) {
        const uint64_t n = std::min(chunk, p.tris - done);
        glNamedBufferSubData(m.counter, 0, sizeof zero, &zero);
        glUniform1ui(prim_base_loc, static_cast<GLuint>(prim_base + done));
        glDrawArrays(GL_TRIANGLES, static_cast<GLint>(3 * (p.first_tri + done)), static_cast<GLsizei>(3 * n));
        // Shader writes (buffer and counter) must be visible to the reads below.
        glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT | GL_ATOMIC_COUNTER_BARRIER_BIT |
                        GL_SHADER_STORAGE_BARRIER_BIT);
        const GLuint count = m.readCounter();
        if (count > m.capacity) {
          if (n == 1)
            throw std::runtime_error(fmt::format(
                "draw '{}' triangle {} alone gives {} fragments, more than the {} records one draw may "
                "hold (--max-records-per-draw)", m.header.draws[d.id].name, prim_base + done, count,
                m.capacity));
          chunk = (n + 1) / 2;  // re-issue in halves until each part fits
          ++st.gl_redraws;
          continue;
        }
        recs.resize(count);
        if (count)
          glGetNamedBufferSubData(m.ssbo, 0, static_cast<GLsizeiptr>(count * sizeof(GpuRecord)), recs.data());
        checkGl("record pass draw and read back");
        for (const GpuRecord& r : recs)
          frags.push_back({static_cast<uint16_t>(r.xy & 0xFFFF), static_cast<uint16_t>(r.xy >> 16), r.z,
                           r.rgba[0], r.rgba[1], r.rgba[2], r.rgba[3], r.prim, r.draw});
        done += n;
        ++st.gl_draws;
      }
      prim_base += p.tris;
      st.triangles += p.tris;
    }
    // Threads append in any order; API order is (primitive, then pixel rows
    // bottom-up, then x), which is also how oitsim gen orders a primitive's fragments.
    std::sort(frags.begin(), frags.end(), [](const Fragment& a, const Fragment& b) {
      if (a.prim != b.prim) return a.prim < b.prim;
      if (a.y != b.y) return a.y < b.y;
      return a.x < b.x;
    });
    for (size_t i = 1; i < frags.size(); ++i)
      if (frags[i].prim == frags[i - 1].prim && frags[i].x == frags[i - 1].x && frags[i].y == frags[i - 1].y)
        throw std::logic_error(fmt::format("GL produced two fragments of draw {} primitive {} at ({}, {})",
                                           d.id, frags[i].prim, frags[i].x, frags[i].y));
    st.fragments_per_draw[d.id] = frags.size();
    st.fragments += frags.size();
    sink.write(std::span<const Fragment>(frags));
  }
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  st.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return st;
}

std::vector<std::array<float, 4>> Capturer::clipVertices(uint32_t draw, double azimuth_offset_deg) const {
  const Scene s = impl_->scene->build(azimuth_offset_deg);
  std::vector<std::array<float, 4>> out;
  for (const DrawGeom& d : s.draws) {
    if (d.id != draw) continue;
    for (const Part& p : d.parts)
      for (uint64_t v = 3 * p.first_tri; v < 3 * (p.first_tri + p.tris); ++v)
        out.push_back({s.soup[v].clip[0], s.soup[v].clip[1], s.soup[v].clip[2], s.soup[v].clip[3]});
  }
  return out;
}

GlReference Capturer::reference(double azimuth_offset_deg) {
  Impl& m = *impl_;
  const Scene s = m.scene->build(azimuth_offset_deg);
  m.upload(s);
  GlReference ref;
  ref.width = m.opts.width;
  ref.height = m.opts.height;
  const size_t pixels = static_cast<size_t>(ref.width) * ref.height;
  auto drawAll = [&](bool per_class_state) {
    for (const DrawGeom& d : s.draws) {
      if (per_class_state) {
        const bool opaque = d.cls == DrawClass::Opaque;
        // Opaque: first of equal depths wins (LESS) and writes depth; transparent:
        // tested against it, blended over in submission order.
        opaque ? glDisable(GL_BLEND) : glEnable(GL_BLEND);
        glDepthMask(opaque ? GL_TRUE : GL_FALSE);
      }
      d.cull_back ? glEnable(GL_CULL_FACE) : glDisable(GL_CULL_FACE);
      uint64_t prim_base = 0;
      for (const Part& p : d.parts) {
        m.setPart(s, d.id, p);
        glUniform1ui(m.uniform("u_prim_base"), static_cast<GLuint>(prim_base));
        glDrawArrays(GL_TRIANGLES, static_cast<GLint>(3 * p.first_tri), static_cast<GLsizei>(3 * p.tris));
        prim_base += p.tris;
      }
    }
  };
  const float clear0[4] = {0, 0, 0, 0};
  const float depth1 = 1.0f;

  glUniform1i(m.uniform("u_pass"), 1);
  // Clears obey the write masks, which the record pass turned off.
  glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
  glDepthMask(GL_TRUE);
  glClearNamedFramebufferfv(m.fbo, GL_COLOR, 0, clear0);
  glClearNamedFramebufferfv(m.fbo, GL_DEPTH, 0, &depth1);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
  drawAll(true);
  ref.rgba.resize(pixels * 4);
  glReadPixels(0, 0, static_cast<GLsizei>(ref.width), static_cast<GLsizei>(ref.height), GL_RGBA, GL_FLOAT,
               ref.rgba.data());
  checkGl("reference blend pass");

  glUniform1i(m.uniform("u_pass"), 2);
  glClearNamedFramebufferfv(m.fbo, GL_COLOR, 0, clear0);
  glDisable(GL_DEPTH_TEST);
  glDepthMask(GL_FALSE);
  glEnable(GL_BLEND);
  glBlendFunc(GL_ONE, GL_ONE);
  drawAll(false);
  std::vector<float> rgba(pixels * 4);
  glReadPixels(0, 0, static_cast<GLsizei>(ref.width), static_cast<GLsizei>(ref.height), GL_RGBA, GL_FLOAT,
               rgba.data());
  checkGl("reference count pass");
  ref.count.resize(pixels);
  for (size_t i = 0; i < pixels; ++i) ref.count[i] = rgba[4 * i];
  glDisable(GL_BLEND);
  return ref;
}

std::string frameFileName(const std::string& output, uint32_t frame, uint32_t frames) {
  if (frames <= 1) return output;
  const std::filesystem::path p(output);
  std::string ext = p.extension().string();
  std::string stem = p.stem().string();
  const auto dir = p.parent_path();
  return (dir / fmt::format("{}-{:04}{}", stem, frame, ext)).string();
}

}  // namespace oit::capture
