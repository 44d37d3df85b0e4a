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
//   draw KIND BLEND DEPTH R G B A VERTICES      then VERTICES lines "x y z w"
// KIND: glsl120 (gl_FragColor), glsl330 (core `out`), discard (3.30 core, discards
// the pixels with odd x + y), fixed (no program: fixed function, client arrays),
// clash (3.30 core declaring a uniform named like the capture's own: links as
// written, fails to link after the capture's rewrite).
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
  float colour[4] = {};
  std::vector<float> clip;  // x y z w per vertex
};

struct Scene {
  int width = 0, height = 0, frames = 1, fbo = 0;
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
    } else if (key == "draw") {
      Draw d;
      size_t n = 0;
      in >> d.kind >> d.blend >> d.depth >> d.colour[0] >> d.colour[1] >> d.colour[2] >> d.colour[3] >> n;
      d.clip.resize(4 * n);
      for (float& v : d.clip) in >> v;
      s.draws.push_back(std::move(d));
    } else {
      die("unknown key '" + key + "' in " + path);
    }
    if (!in) die(std::string("bad scene file ") + path);
  }
  if (s.width <= 0 || s.height <= 0) die("scene has no size");
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
  const char* fs = old ? kFs120 : kind == "discard" ? kFsDiscard : kind == "clash" ? kFsClash : kFs330;
  const GLuint p = gl.CreateProgram();
  gl.AttachShader(p, compile(gl, GL_VERTEX_SHADER, old ? kVs120 : kVs330));
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

  GLuint fbo = 0;
  if (scene.fbo) {
    GLuint rb[2] = {};
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl.GenRenderbuffers(1, &rb[0]);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, scene.width, scene.height);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    gl.GenRenderbuffers(1, &rb[1]);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT24, scene.width, scene.height);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
  }
  glViewport(0, 0, scene.width, scene.height);
  for (int frame = 0; frame < scene.frames; ++frame) {
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    glClearColor(0, 0, 0, 0);
    glDepthMask(GL_TRUE);
    glClearDepth(1.0);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
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
