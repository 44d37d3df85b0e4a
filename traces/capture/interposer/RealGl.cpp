#include "traces/capture/interposer/RealGl.hpp"

#include <dlfcn.h>

namespace oit::capture::interposer {

void* realProc(const char* name) {
  if (void* p = dlsym(RTLD_NEXT, name)) return p;
  // Entry points GLVND's libGL does not export: ask the window system's loader.
  using GetProc = void* (*)(const char*);
  static GetProc egl_get = [] {
    void* egl = dlopen("libEGL.so.1", RTLD_LAZY | RTLD_NOLOAD);
    return egl ? reinterpret_cast<GetProc>(dlsym(egl, "eglGetProcAddress")) : nullptr;
  }();
  static GetProc glx_get = reinterpret_cast<GetProc>(dlsym(RTLD_NEXT, "glXGetProcAddressARB"));
  if (egl_get)
    if (void* p = egl_get(name)) return p;
  if (glx_get)
    if (void* p = glx_get(name)) return p;
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
