#include "traces/capture/EglContext.hpp"

#include <cstring>
#include <optional>
#include <string>

#include <fmt/format.h>

namespace oit::capture {

using namespace gl;  // the entry points, loaded at run time (GlEntryPoints.hpp)

namespace {

const char* eglErrorName(EGLint e) {
  switch (e) {
    case EGL_SUCCESS: return "EGL_SUCCESS";
    case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
    case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
    case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
    case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
    case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
    case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
    case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
    case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
    case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
    case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
    default: return "unknown EGL error";
  }
}

[[noreturn]] void eglFail(const char* call, const std::string& extra = {}) {
  const EGLint e = eglGetError();
  throw GlError(fmt::format("{} failed: {} (0x{:04X}){}; {}", call, eglErrorName(e), e,
                            extra.empty() ? "" : " - " + extra, kGlInstallHint));
}

const char* glErrorName(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    default: return "unknown GL error";
  }
}

}  // namespace

void checkGl(const char* what) {
  const GLenum e = glGetError();
  if (e != GL_NO_ERROR)
    throw GlError(fmt::format("{} failed: {} (0x{:04X})", what, glErrorName(e), e));
}

EglContext::EglContext() {
  if (const std::string& why = loadEntryPoints(); !why.empty()) throw GlError(why);
  const char* client_ext = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
  if (!client_ext) eglFail("eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS)", "no EGL client extensions");
  if (!std::strstr(client_ext, "EGL_MESA_platform_surfaceless"))
    throw GlError(fmt::format("eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS): no "
                              "EGL_MESA_platform_surfaceless among the client extensions ({}); {}",
                              *client_ext ? client_ext : "none: no EGL vendor library found", kGlInstallHint));
  auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (!getPlatformDisplay) eglFail("eglGetProcAddress(eglGetPlatformDisplayEXT)");
  display = getPlatformDisplay(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, nullptr);
  if (display == EGL_NO_DISPLAY) eglFail("eglGetPlatformDisplayEXT(EGL_PLATFORM_SURFACELESS_MESA)");
  EGLint major = 0, minor = 0;
  if (!eglInitialize(display, &major, &minor)) eglFail("eglInitialize(surfaceless display)");
  if (!eglBindAPI(EGL_OPENGL_API)) eglFail("eglBindAPI(EGL_OPENGL_API)");
  const EGLint attribs[] = {EGL_CONTEXT_MAJOR_VERSION, 4, EGL_CONTEXT_MINOR_VERSION, 5,
                            EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT,
                            EGL_NONE};
  // EGL_KHR_no_config_context: no surface, so no config is needed.
  context = eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, attribs);
  if (context == EGL_NO_CONTEXT) eglFail("eglCreateContext(OpenGL 4.5 core, no config)");
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    eglDestroyContext(display, context);
    eglFail("eglMakeCurrent(no surface)");
  }
}

EglContext::~EglContext() {
  // The display is shared by every context of the process: not terminated here.
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, context);
}

GLuint compileShader(GLenum type, const char* src, const char* what) {
  GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096] = {};
    glGetShaderInfoLog(s, sizeof log, nullptr, log);
    glDeleteShader(s);
    throw GlError(fmt::format("glCompileShader({}) failed: {}", what, log));
  }
  return s;
}

std::optional<std::string> glUnavailableReason() {
  try {
    EglContext ctx;
    GLint major = 0, minor = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);
    glGetIntegerv(GL_MINOR_VERSION, &minor);
    if (major * 10 + minor < 45) return fmt::format("OpenGL {}.{} < 4.5", major, minor);
    return std::nullopt;
  } catch (const GlError& e) {
    return std::string(e.what());
  }
}

}  // namespace oit::capture
