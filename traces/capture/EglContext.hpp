// The headless capture's GL context (one EGL display and an OpenGL 4.5 core
// context without a surface, on Mesa's surfaceless platform; rendering goes to
// framebuffer objects) and its error checks, each failure a GlError naming the
// call, the error and what to install. Used by GlCapture.cpp.
#pragma once

#include "traces/capture/GlCapture.hpp"
#include "traces/capture/GlEntryPoints.hpp"

namespace oit::capture {

// What to install when EGL or GL is missing or too old.
inline constexpr const char* kGlInstallHint =
    "headless capture needs Mesa's EGL and software GL (llvmpipe): "
    "apt-get install libegl1 libegl-mesa0 libgl1-mesa-dri (scripts/setup.sh installs them)";

// One EGL display + OpenGL 4.5 core context with no surface, current from
// construction (the entry points are loaded first) to destruction.
struct EglContext {
  EGLDisplay display = EGL_NO_DISPLAY;
  EGLContext context = EGL_NO_CONTEXT;

  EglContext();
  ~EglContext();
  EglContext(const EglContext&) = delete;
  EglContext& operator=(const EglContext&) = delete;
};

// GL reports errors lazily: check after each group of calls, naming the group.
void checkGl(const char* what);

// Compiles one shader stage; a GlError with GL's log when it does not compile.
GLuint compileShader(GLenum type, const char* src, const char* what);

}  // namespace oit::capture
