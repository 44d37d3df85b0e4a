#include "traces/capture/GlEntryPoints.hpp"

#include <dlfcn.h>

#include <fmt/format.h>

namespace oit::capture::gl {

#define OITSIM_DEFINE_ENTRY_POINT(type, name) type name = nullptr;
OITSIM_EGL_ENTRY_POINTS(OITSIM_DEFINE_ENTRY_POINT)
OITSIM_GL_ENTRY_POINTS(OITSIM_DEFINE_ENTRY_POINT)
#undef OITSIM_DEFINE_ENTRY_POINT

namespace {

constexpr const char* kInstall =
    "headless capture needs Mesa's EGL and OpenGL through GLVND: apt-get install libegl1 libopengl0 "
    "libegl-mesa0 libgl1-mesa-dri (scripts/setup.sh installs them); every other oitsim command works without them";

std::string load() {
  // RTLD_LOCAL: the symbols stay out of the global namespace; kept open for
  // the life of the process (the context may be used until exit).
  void* egl = dlopen("libEGL.so.1", RTLD_NOW | RTLD_LOCAL);
  if (!egl) return fmt::format("cannot load libEGL.so.1 ({}); {}", dlerror(), kInstall);
  void* opengl = dlopen("libOpenGL.so.0", RTLD_NOW | RTLD_LOCAL);
  if (!opengl) return fmt::format("cannot load libOpenGL.so.0 ({}); {}", dlerror(), kInstall);
#define OITSIM_LOAD_EGL(type, name)                                                              \
  name = reinterpret_cast<type>(dlsym(egl, #name));                                              \
  if (!name) return fmt::format("libEGL.so.1 has no {} (EGL 1.5 needed); {}", #name, kInstall);
  OITSIM_EGL_ENTRY_POINTS(OITSIM_LOAD_EGL)
#undef OITSIM_LOAD_EGL
  // GLVND's libOpenGL exports every core entry point; eglGetProcAddress (EGL
  // 1.5: core functions too) covers an implementation that does not.
#define OITSIM_LOAD_GL(type, name)                                                               \
  name = reinterpret_cast<type>(dlsym(opengl, #name));                                           \
  if (!name) name = reinterpret_cast<type>(eglGetProcAddress(#name));                            \
  if (!name) return fmt::format("no OpenGL entry point {} (OpenGL 4.5 core needed); {}", #name, kInstall);
  OITSIM_GL_ENTRY_POINTS(OITSIM_LOAD_GL)
#undef OITSIM_LOAD_GL
  return "";
}

}  // namespace

const std::string& loadEntryPoints() {
  static const std::string why = load();  // once; thread-safe
  return why;
}

}  // namespace oit::capture::gl
