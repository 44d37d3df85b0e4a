// oitsim_gl_testapp: a small OpenGL application (Xlib + GLX, compatibility context)
// that the apitrace capture tests trace with `apitrace trace` under Xvfb and then
// capture with `oitsim capture --apitrace`. It draws the triangles of a scene file
// (clip-space vertices, so the geometry is exactly what the test asks for) with the
// program kind, blend mode and depth state given per draw, the same every frame.
//
// Scene file (text):
//   size W H
//   frames N
//   fbo 0|1        1: draw into a framebuffer object (RGBA8 + DEPTH24) and blit it
//                  to the window before each swap, as many applications do
//   churn 0|1      1: at the start of every frame, delete every draw's program and
//                  make it again (GL may give the name again), and make and delete a
//                  texture and a buffer
//   texturenames A B  at the start of every frame, glDeleteTextures of the names A to
//                  B, which the application never made, then make one texture of its
//                  own (4 x 4 RGBA8; GL gives the lowest free name)
//   draw KIND BLEND DEPTH R G B A VERTICES      then VERTICES lines "x y z w"
// KIND: glsl120 (gl_FragColor), glsl330 (core `out`), discard (3.30 core, discards
// the pixels with odd x + y), fixed (no program: fixed function, client arrays),
// clash (3.30 core declaring a uniform named like the capture's own: links as
// written, fails to link after the capture's rewrite), es300 (GLSL ES 3.00
// vertex and fragment shaders, `out`), es100 (GLSL ES 1.00, gl_FragColor,
// mediump), mrt (3.30 core writing two outputs, drawn with glDrawBuffers of
// colour attachments 0 and 1: several render targets; needs fbo 1).
// KIND may end in modifiers: +msaa (drawn into a 4-sample framebuffer object of
// the frame's size, resolved into the frame's target afterwards), +stencil (the
// stencil test on, GL_EQUAL 0 against a stencil buffer cleared to 0: every
// fragment passes, but coverage depends on the stencil; needs fbo 1),
// +stencilalways (the stencil test on with GL_ALWAYS: coverage does not depend on it),
// +window (drawn into the window, framebuffer 0, although the scene has fbo 1; the
// window's depth is cleared with the frame's target).
// BLEND: off, over (SRC_ALPHA, ONE_MINUS_SRC_ALPHA), premul (ONE,
// ONE_MINUS_SRC_ALPHA), additive (ONE, ONE). DEPTH: off, test (LESS, no writes),
// write (LESS and writes).
#include <GL/gl.h>
#include <GL/glext.h>
#include <GL/glx.h>
#include <X11/Xlib.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct Draw {
  std::string kind, blend, depth;
  bool msaa = false, stencil = false, stencil_always = false, window = false;
  float colour[4] = {};
  std::vector<float> clip;  // x y z w per vertex
};

struct Scene {
  int width = 0, height = 0, frames = 1, fbo = 0, churn = 0;
  unsigned texture_names[2] = {0, 0};  // texturenames A B (0 0: none)
  std::vector<Draw> draws;
};

[[noreturn]] void die(const std::string& msg) {
  std::cerr << "oitsim_gl_testapp: " << msg << "\n";
  std::exit(1);
}

Scene readScene(const char* path) {
  std::ifstream in(path);
  if (!in) die(std::string("cannot open ") + path);
  Scene s;
  std::string key;
  while (in >> key) {
    if (key == "size") {
      in >> s.width >> s.height;
    } else if (key == "frames") {
      in >> s.frames;
    } else if (key == "fbo") {
      in >> s.fbo;
    } else if (key == "churn") {
      in >> s.churn;
    } else if (key == "texturenames") {
      in >> s.texture_names[0] >> s.texture_names[1];
    } else if (key == "draw") {
      Draw d;
      size_t n = 0;
      in >> d.kind >> d.blend >> d.depth >> d.colour[0] >> d.colour[1] >> d.colour[2] >> d.colour[3] >> n;
      for (size_t plus = d.kind.rfind('+'); plus != std::string::npos; plus = d.kind.rfind('+')) {
        const std::string modifier = d.kind.substr(plus + 1);
        d.kind.resize(plus);
        if (modifier == "msaa") d.msaa = true;
        else if (modifier == "stencil") d.stencil = true;
        else if (modifier == "stencilalways") d.stencil_always = true;
        else if (modifier == "window") d.window = true;
        else die("unknown draw modifier '+" + modifier + "' in " + path);
      }
      d.clip.resize(4 * n);
      for (float& v : d.clip) in >> v;
      s.draws.push_back(std::move(d));
    } else {
      die("unknown key '" + key + "' in " + path);
    }
    if (!in) die(std::string("bad scene file ") + path);
  }
  if (s.width <= 0 || s.height <= 0) die("scene has no size");
  for (const Draw& d : s.draws)
    if (!s.fbo && (d.kind == "mrt" || d.stencil || d.stencil_always))
      die("draws of kind mrt or with +stencil need fbo 1 (the window has no second target or stencil)");
  return s;
}

template <typename F>
F proc(const char* name) {
  auto p = reinterpret_cast<F>(glXGetProcAddressARB(reinterpret_cast<const GLubyte*>(name)));
  if (!p) die(std::string("no ") + name);
  return p;
}

// The GL 2.0+ entry points, through glXGetProcAddress as applications do.
struct Gl {
  PFNGLCREATESHADERPROC CreateShader = proc<PFNGLCREATESHADERPROC>("glCreateShader");
  PFNGLSHADERSOURCEPROC ShaderSource = proc<PFNGLSHADERSOURCEPROC>("glShaderSource");
  PFNGLCOMPILESHADERPROC CompileShader = proc<PFNGLCOMPILESHADERPROC>("glCompileShader");
  PFNGLGETSHADERIVPROC GetShaderiv = proc<PFNGLGETSHADERIVPROC>("glGetShaderiv");
  PFNGLGETSHADERINFOLOGPROC GetShaderInfoLog = proc<PFNGLGETSHADERINFOLOGPROC>("glGetShaderInfoLog");
  PFNGLCREATEPROGRAMPROC CreateProgram = proc<PFNGLCREATEPROGRAMPROC>("glCreateProgram");
  PFNGLATTACHSHADERPROC AttachShader = proc<PFNGLATTACHSHADERPROC>("glAttachShader");
  PFNGLBINDATTRIBLOCATIONPROC BindAttribLocation = proc<PFNGLBINDATTRIBLOCATIONPROC>("glBindAttribLocation");
  PFNGLLINKPROGRAMPROC LinkProgram = proc<PFNGLLINKPROGRAMPROC>("glLinkProgram");
  PFNGLGETPROGRAMIVPROC GetProgramiv = proc<PFNGLGETPROGRAMIVPROC>("glGetProgramiv");
  PFNGLUSEPROGRAMPROC UseProgram = proc<PFNGLUSEPROGRAMPROC>("glUseProgram");
  PFNGLGETUNIFORMLOCATIONPROC GetUniformLocation = proc<PFNGLGETUNIFORMLOCATIONPROC>("glGetUniformLocation");
  PFNGLUNIFORM4FVPROC Uniform4fv = proc<PFNGLUNIFORM4FVPROC>("glUniform4fv");
  PFNGLUNIFORM1FPROC Uniform1f = proc<PFNGLUNIFORM1FPROC>("glUniform1f");
  PFNGLGENBUFFERSPROC GenBuffers = proc<PFNGLGENBUFFERSPROC>("glGenBuffers");
  PFNGLDELETEBUFFERSPROC DeleteBuffers = proc<PFNGLDELETEBUFFERSPROC>("glDeleteBuffers");
  PFNGLDELETEPROGRAMPROC DeleteProgram = proc<PFNGLDELETEPROGRAMPROC>("glDeleteProgram");
  PFNGLBINDBUFFERPROC BindBuffer = proc<PFNGLBINDBUFFERPROC>("glBindBuffer");
  PFNGLBUFFERDATAPROC BufferData = proc<PFNGLBUFFERDATAPROC>("glBufferData");
  PFNGLGENVERTEXARRAYSPROC GenVertexArrays = proc<PFNGLGENVERTEXARRAYSPROC>("glGenVertexArrays");
  PFNGLBINDVERTEXARRAYPROC BindVertexArray = proc<PFNGLBINDVERTEXARRAYPROC>("glBindVertexArray");
  PFNGLENABLEVERTEXATTRIBARRAYPROC EnableVertexAttribArray =
      proc<PFNGLENABLEVERTEXATTRIBARRAYPROC>("glEnableVertexAttribArray");
  PFNGLVERTEXATTRIBPOINTERPROC VertexAttribPointer = proc<PFNGLVERTEXATTRIBPOINTERPROC>("glVertexAttribPointer");
  PFNGLGENFRAMEBUFFERSPROC GenFramebuffers = proc<PFNGLGENFRAMEBUFFERSPROC>("glGenFramebuffers");
  PFNGLBINDFRAMEBUFFERPROC BindFramebuffer = proc<PFNGLBINDFRAMEBUFFERPROC>("glBindFramebuffer");
  PFNGLGENRENDERBUFFERSPROC GenRenderbuffers = proc<PFNGLGENRENDERBUFFERSPROC>("glGenRenderbuffers");
  PFNGLBINDRENDERBUFFERPROC BindRenderbuffer = proc<PFNGLBINDRENDERBUFFERPROC>("glBindRenderbuffer");
  PFNGLRENDERBUFFERSTORAGEPROC RenderbufferStorage = proc<PFNGLRENDERBUFFERSTORAGEPROC>("glRenderbufferStorage");
  PFNGLFRAMEBUFFERRENDERBUFFERPROC FramebufferRenderbuffer =
      proc<PFNGLFRAMEBUFFERRENDERBUFFERPROC>("glFramebufferRenderbuffer");
  PFNGLBLITFRAMEBUFFERPROC BlitFramebuffer = proc<PFNGLBLITFRAMEBUFFERPROC>("glBlitFramebuffer");
  PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC RenderbufferStorageMultisample =
      proc<PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC>("glRenderbufferStorageMultisample");
  PFNGLDRAWBUFFERSPROC DrawBuffers = proc<PFNGLDRAWBUFFERSPROC>("glDrawBuffers");
  PFNGLCHECKFRAMEBUFFERSTATUSPROC CheckFramebufferStatus =
      proc<PFNGLCHECKFRAMEBUFFERSTATUSPROC>("glCheckFramebufferStatus");
};

const char* kVs120 = "#version 120\nattribute vec4 a_clip;\nvoid main() { gl_Position = a_clip; }\n";
const char* kFs120 = "#version 120\nuniform vec4 u_colour;\nvoid main() { gl_FragColor = u_colour; }\n";
const char* kVs330 =
    "#version 330 core\nlayout(location = 0) in vec4 a_clip;\nvoid main() { gl_Position = a_clip; }\n";
const char* kFs330 =
    "#version 330 core\nuniform vec4 u_colour;\nout vec4 o_colour;\nvoid main() { o_colour = u_colour; }\n";
const char* kFsDiscard =
    "#version 330 core\nuniform vec4 u_colour;\nout vec4 o_colour;\n"
    "void main() {\n  if (((int(gl_FragCoord.x) + int(gl_FragCoord.y)) & 1) == 1) discard;\n"
    "  o_colour = u_colour;\n}\n";
// GLSL ES on desktop GL (ARB_ES3_compatibility, ARB_ES2_compatibility).
const char* kVsEs300 =
    "#version 300 es\nlayout(location = 0) in vec4 a_clip;\nvoid main() { gl_Position = a_clip; }\n";
const char* kFsEs300 =
    "#version 300 es\nprecision highp float;\nuniform vec4 u_colour;\nout vec4 o_colour;\n"
    "void main() { o_colour = u_colour; }\n";
const char* kVsEs100 = "#version 100\nattribute vec4 a_clip;\nvoid main() { gl_Position = a_clip; }\n";
const char* kFsEs100 =
    "#version 100\nprecision mediump float;\nuniform vec4 u_colour;\nvoid main() { gl_FragColor = u_colour; }\n";
// Two colour outputs (several render targets).
const char* kFsMrt =
    "#version 330 core\nuniform vec4 u_colour;\nlayout(location = 0) out vec4 o_colour;\n"
    "layout(location = 1) out vec4 o_second;\nvoid main() { o_colour = u_colour; o_second = u_colour.abgr; }\n";
// Links on its own; the capture's record code declares `uniform uint oitsim_mode`.
const char* kFsClash =
    "#version 330 core\nuniform vec4 u_colour;\nuniform float oitsim_mode;\nout vec4 o_colour;\n"
    "void main() { o_colour = u_colour * oitsim_mode; }\n";

GLuint compile(const Gl& gl, GLenum type, const char* src) {
  const GLuint s = gl.CreateShader(type);
  gl.ShaderSource(s, 1, &src, nullptr);
  gl.CompileShader(s);
  GLint ok = 0;
  gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[2048] = {};
    gl.GetShaderInfoLog(s, sizeof log, nullptr, log);
    die(std::string("shader does not compile: ") + log);
  }
  return s;
}

GLuint program(const Gl& gl, const std::string& kind) {
  const bool old = kind == "glsl120";
  const char* fs = old                 ? kFs120
                   : kind == "discard" ? kFsDiscard
                   : kind == "clash"   ? kFsClash
                   : kind == "es300"   ? kFsEs300
                   : kind == "es100"   ? kFsEs100
                   : kind == "mrt"     ? kFsMrt
                   : kind == "glsl330" ? kFs330
                                       : nullptr;
  if (!fs) die("unknown draw kind '" + kind + "'");
  const char* vs = old ? kVs120 : kind == "es300" ? kVsEs300 : kind == "es100" ? kVsEs100 : kVs330;
  const GLuint p = gl.CreateProgram();
  gl.AttachShader(p, compile(gl, GL_VERTEX_SHADER, vs));
  gl.AttachShader(p, compile(gl, GL_FRAGMENT_SHADER, fs));
  gl.BindAttribLocation(p, 0, "a_clip");
  gl.LinkProgram(p);
  GLint ok = 0;
  gl.GetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) die("program " + kind + " does not link");
  return p;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) die("usage: oitsim_gl_testapp SCENE_FILE");
  const Scene scene = readScene(argv[1]);
  Display* dpy = XOpenDisplay(nullptr);
  if (!dpy) die("cannot open the X display (run under Xvfb)");
  int attrs[] = {GLX_RGBA, GLX_DOUBLEBUFFER, GLX_RED_SIZE, 8, GLX_GREEN_SIZE, 8, GLX_BLUE_SIZE, 8,
                 GLX_ALPHA_SIZE, 8, GLX_DEPTH_SIZE, 24, None};
  XVisualInfo* vi = glXChooseVisual(dpy, DefaultScreen(dpy), attrs);
  if (!vi) die("no RGBA8 double-buffered visual with depth");
  XSetWindowAttributes swa{};
  swa.colormap = XCreateColormap(dpy, RootWindow(dpy, vi->screen), vi->visual, AllocNone);
  const Window win = XCreateWindow(dpy, RootWindow(dpy, vi->screen), 0, 0, scene.width, scene.height, 0, vi->depth,
                                   InputOutput, vi->visual, CWColormap, &swa);
  XMapWindow(dpy, win);
  GLXContext ctx = glXCreateContext(dpy, vi, nullptr, True);
  if (!ctx || !glXMakeCurrent(dpy, win, ctx)) die("cannot create a GLX context");

  const Gl gl;
  std::vector<GLuint> programs, vaos;
  for (const Draw& d : scene.draws) {
    GLuint p = 0, vao = 0;
    if (d.kind != "fixed") {
      p = program(gl, d.kind);
      GLuint vbo = 0;
      gl.GenVertexArrays(1, &vao);
      gl.BindVertexArray(vao);
      gl.GenBuffers(1, &vbo);
      gl.BindBuffer(GL_ARRAY_BUFFER, vbo);
      gl.BufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(d.clip.size() * sizeof(float)), d.clip.data(),
                    GL_STATIC_DRAW);
      gl.EnableVertexAttribArray(0);
      gl.VertexAttribPointer(0, 4, GL_FLOAT, GL_FALSE, 0, nullptr);
      gl.BindVertexArray(0);
      gl.BindBuffer(GL_ARRAY_BUFFER, 0);
    }
    programs.push_back(p);
    vaos.push_back(vao);
  }

  bool mrt = false, stencil = false, msaa = false;
  for (const Draw& d : scene.draws) {
    mrt = mrt || d.kind == "mrt";
    stencil = stencil || d.stencil || d.stencil_always;
    msaa = msaa || d.msaa;
  }
  GLuint fbo = 0;
  if (scene.fbo) {
    // The second colour attachment and the stencil only where a draw needs them,
    // so the other scenes' framebuffer stays RGBA8 + DEPTH24.
    GLuint rb[3] = {};
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl.GenRenderbuffers(3, rb);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, scene.width, scene.height);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, stencil ? GL_DEPTH24_STENCIL8 : GL_DEPTH_COMPONENT24, scene.width,
                           scene.height);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, stencil ? GL_DEPTH_STENCIL_ATTACHMENT : GL_DEPTH_ATTACHMENT,
                               GL_RENDERBUFFER, rb[1]);
    if (mrt) {
      gl.BindRenderbuffer(GL_RENDERBUFFER, rb[2]);
      gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, scene.width, scene.height);
      gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_RENDERBUFFER, rb[2]);
    }
    if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) die("incomplete framebuffer");
  }
  GLuint msaa_fbo = 0;
  if (msaa) {
    GLuint rb[2] = {};
    gl.GenFramebuffers(1, &msaa_fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, msaa_fbo);
    gl.GenRenderbuffers(2, rb);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, 4, GL_RGBA8, scene.width, scene.height);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    gl.RenderbufferStorageMultisample(GL_RENDERBUFFER, 4, GL_DEPTH_COMPONENT24, scene.width, scene.height);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    if (gl.CheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) die("incomplete multisample framebuffer");
  }
  glViewport(0, 0, scene.width, scene.height);
  bool window_draws = false;
  for (const Draw& d : scene.draws) window_draws = window_draws || d.window;
  for (int frame = 0; frame < scene.frames; ++frame) {
    if (scene.churn) {
      for (size_t i = 0; i < scene.draws.size(); ++i)
        if (programs[i]) {
          gl.DeleteProgram(programs[i]);
          programs[i] = program(gl, scene.draws[i].kind);
        }
      GLuint tex = 0, buf = 0;
      glGenTextures(1, &tex);
      glBindTexture(GL_TEXTURE_2D, tex);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, 4, 4, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
      glBindTexture(GL_TEXTURE_2D, 0);
      glDeleteTextures(1, &tex);
      gl.GenBuffers(1, &buf);
      gl.BindBuffer(GL_ARRAY_BUFFER, buf);
      gl.BufferData(GL_ARRAY_BUFFER, 64, nullptr, GL_STATIC_DRAW);
      gl.BindBuffer(GL_ARRAY_BUFFER, 0);
      gl.DeleteBuffers(1, &buf);
    }
    if (scene.texture_names[1]) {
      for (GLuint name = scene.texture_names[0]; name <= scene.texture_names[1]; ++name) glDeleteTextures(1, &name);
      GLuint tex = 0;
      glGenTextures(1, &tex);
      glBindTexture(GL_TEXTURE_2D, tex);
      glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA8, 4, 4, 0, GL_RGBA, GL_UNSIGNED_BYTE, nullptr);
      glBindTexture(GL_TEXTURE_2D, 0);
    }
    glClearColor(0, 0, 0, 0);
    glDepthMask(GL_TRUE);
    glClearDepth(1.0);
    glClearStencil(0);
    if (window_draws && fbo) {
      gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
      glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    }
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT | (stencil ? GL_STENCIL_BUFFER_BIT : 0));
    for (size_t i = 0; i < scene.draws.size(); ++i) {
      const Draw& d = scene.draws[i];
      if (d.depth == "off") {
        glDisable(GL_DEPTH_TEST);
      } else {
        glEnable(GL_DEPTH_TEST);
        glDepthFunc(GL_LESS);
      }
      glDepthMask(d.depth == "write" ? GL_TRUE : GL_FALSE);
      if (d.blend == "off") {
        glDisable(GL_BLEND);
      } else {
        glEnable(GL_BLEND);
        if (d.blend == "over") glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        else if (d.blend == "premul") glBlendFunc(GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
        else glBlendFunc(GL_ONE, GL_ONE);
      }
      const GLsizei n = static_cast<GLsizei>(d.clip.size() / 4);
      if (d.msaa) {
        gl.BindFramebuffer(GL_FRAMEBUFFER, msaa_fbo);
        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
      }
      if (d.stencil || d.stencil_always) {
        glEnable(GL_STENCIL_TEST);
        glStencilFunc(d.stencil ? GL_EQUAL : GL_ALWAYS, 0, 0xFF);
        glStencilOp(GL_KEEP, GL_KEEP, GL_KEEP);
      }
      const GLenum both[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
      if (d.kind == "mrt") gl.DrawBuffers(2, both);
      if (d.window) gl.BindFramebuffer(GL_FRAMEBUFFER, 0);
      if (d.kind == "fixed") {
        gl.UseProgram(0);
        glColor4fv(d.colour);
        glEnableClientState(GL_VERTEX_ARRAY);
        glVertexPointer(4, GL_FLOAT, 0, d.clip.data());
        glDrawArrays(GL_TRIANGLES, 0, n);
        glDisableClientState(GL_VERTEX_ARRAY);
      } else {
        gl.UseProgram(programs[i]);
        gl.Uniform4fv(gl.GetUniformLocation(programs[i], "u_colour"), 1, d.colour);
        if (d.kind == "clash") gl.Uniform1f(gl.GetUniformLocation(programs[i], "oitsim_mode"), 1.0f);
        gl.BindVertexArray(vaos[i]);
        glDrawArrays(GL_TRIANGLES, 0, n);
        gl.BindVertexArray(0);
      }
      if (d.kind == "mrt") gl.DrawBuffers(1, both);
      if (d.window) gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
      if (d.stencil || d.stencil_always) glDisable(GL_STENCIL_TEST);
      if (d.msaa) {  // resolve into the frame's target
        gl.BindFramebuffer(GL_READ_FRAMEBUFFER, msaa_fbo);
        gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, fbo);
        gl.BlitFramebuffer(0, 0, scene.width, scene.height, 0, 0, scene.width, scene.height, GL_COLOR_BUFFER_BIT,
                           GL_NEAREST);
        gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
      }
    }
    if (fbo) {
      gl.BindFramebuffer(GL_READ_FRAMEBUFFER, fbo);
      gl.BindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
      gl.BlitFramebuffer(0, 0, scene.width, scene.height, 0, 0, scene.width, scene.height, GL_COLOR_BUFFER_BIT,
                         GL_NEAREST);
    }
    glXSwapBuffers(dpy, win);
  }
  glXMakeCurrent(dpy, None, nullptr);
  glXDestroyContext(dpy, ctx);
  XDestroyWindow(dpy, win);
  XCloseDisplay(dpy);
  return 0;
}
