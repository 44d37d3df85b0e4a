#include "traces/capture/interposer/RealGl.hpp"

#include <dlfcn.h>

#include <initializer_list>

namespace oit::capture::interposer {

void* realProc(const char* name) {
  // The interposer is loaded as the retracer's libGL.so.1 (ApitraceCapture puts it
  // first on LD_LIBRARY_PATH) and depends on GLVND's libOpenGL.so.0 (every GL entry
  // point) and libGLX.so.0 (GLX): the real functions are there, past the wrappers.
  static void* opengl = dlopen("libOpenGL.so.0", RTLD_LAZY | RTLD_LOCAL);
  static void* glx = dlopen("libGLX.so.0", RTLD_LAZY | RTLD_LOCAL);
  for (void* lib : {opengl, glx})
    if (lib)
      if (void* p = dlsym(lib, name)) return p;
  // Entry points no library exports: ask the window system's loader.
  using GetProc = void* (*)(const char*);
  static GetProc glx_get = glx ? reinterpret_cast<GetProc>(dlsym(glx, "glXGetProcAddressARB")) : nullptr;
  static GetProc egl_get = [] {
    void* egl = dlopen("libEGL.so.1", RTLD_LAZY | RTLD_NOLOAD);
    return egl ? reinterpret_cast<GetProc>(dlsym(egl, "eglGetProcAddress")) : nullptr;
  }();
  if (glx_get)
    if (void* p = glx_get(name)) return p;
  if (egl_get)
    if (void* p = egl_get(name)) return p;
  return nullptr;
}

const char* RealGl::load() {
#define OITSIM_LOAD(type, name)                                  \
  if (!name) name = reinterpret_cast<type>(realProc(#name));     \
  if (!name) return #name;
  OITSIM_REAL_GL(OITSIM_LOAD)
#undef OITSIM_LOAD
#define OITSIM_LOAD_OPTIONAL(type, name) \
  if (!name) name = reinterpret_cast<type>(realProc(#name));
  OITSIM_REAL_GL_OPTIONAL(OITSIM_LOAD_OPTIONAL)
#undef OITSIM_LOAD_OPTIONAL
  return "";
}

RealGl& gl() {
  static RealGl g;
  return g;
}

}  // namespace oit::capture::interposer
