// The entry points liboitsim_interposer.so puts in front of the GL library. apitrace's
// glretrace opens "libGL.so.1" with dlopen and looks every entry point up in it with
// dlsym; `oitsim capture --apitrace` puts a folder first on the retracer's
// LD_LIBRARY_PATH where libGL.so.1 is this library. dlsym on it finds the wrappers
// below, and every other name in its dependencies, GLVND's libOpenGL.so.0 (GL) and
// libGLX.so.0 (GLX), which dispatch to Mesa as libGL.so.1 itself does.
// glXGetProcAddress(ARB) is wrapped too, for the names below. Each wrapper forwards
// to the real function and tells the Recorder.
#include <dlfcn.h>

#include <cstring>

#include "traces/capture/interposer/Recorder.hpp"

#define OITSIM_EXPORT extern "C" __attribute__((visibility("default")))

using oit::capture::interposer::Recorder;
using oit::capture::interposer::realProc;
namespace stream = oit::capture::stream;

namespace {

template <typename F>
F real(const char* name) {
  return reinterpret_cast<F>(realProc(name));
}

}  // namespace

// Draw calls: X(name, multi, (parameters), (arguments)). `multi` marks calls whose
// primitive ids restart (instances, several sub-draws).
#define OITSIM_DRAWS(X)                                                                                              \
  X(glDrawArrays, false, (GLenum mode, GLint first, GLsizei count), (mode, first, count))                            \
  X(glDrawArraysEXT, false, (GLenum mode, GLint first, GLsizei count), (mode, first, count))                         \
  X(glDrawElements, false, (GLenum mode, GLsizei count, GLenum type, const void* indices),                          \
    (mode, count, type, indices))                                                                                    \
  X(glDrawRangeElements, false,                                                                                      \
    (GLenum mode, GLuint start, GLuint end, GLsizei count, GLenum type, const void* indices),                       \
    (mode, start, end, count, type, indices))                                                                        \
  X(glDrawRangeElementsEXT, false,                                                                                   \
    (GLenum mode, GLuint start, GLuint end, GLsizei count, GLenum type, const void* indices),                       \
    (mode, start, end, count, type, indices))                                                                        \
  X(glDrawElementsBaseVertex, false,                                                                                 \
    (GLenum mode, GLsizei count, GLenum type, const void* indices, GLint basevertex),                               \
    (mode, count, type, indices, basevertex))                                                                        \
  X(glDrawRangeElementsBaseVertex, false,                                                                            \
    (GLenum mode, GLuint start, GLuint end, GLsizei count, GLenum type, const void* indices, GLint basevertex),     \
    (mode, start, end, count, type, indices, basevertex))                                                            \
  X(glDrawArraysInstanced, true, (GLenum mode, GLint first, GLsizei count, GLsizei n), (mode, first, count, n))      \
  X(glDrawArraysInstancedARB, true, (GLenum mode, GLint first, GLsizei count, GLsizei n), (mode, first, count, n))   \
  X(glDrawArraysInstancedEXT, true, (GLenum mode, GLint first, GLsizei count, GLsizei n), (mode, first, count, n))   \
  X(glDrawElementsInstanced, true, (GLenum mode, GLsizei count, GLenum type, const void* indices, GLsizei n),       \
    (mode, count, type, indices, n))                                                                                 \
  X(glDrawElementsInstancedARB, true, (GLenum mode, GLsizei count, GLenum type, const void* indices, GLsizei n),    \
    (mode, count, type, indices, n))                                                                                 \
  X(glDrawElementsInstancedEXT, true, (GLenum mode, GLsizei count, GLenum type, const void* indices, GLsizei n),    \
    (mode, count, type, indices, n))                                                                                 \
  X(glDrawElementsInstancedBaseVertex, true,                                                                         \
    (GLenum mode, GLsizei count, GLenum type, const void* indices, GLsizei n, GLint basevertex),                    \
    (mode, count, type, indices, n, basevertex))                                                                     \
  X(glDrawArraysInstancedBaseInstance, true,                                                                         \
    (GLenum mode, GLint first, GLsizei count, GLsizei n, GLuint baseinstance), (mode, first, count, n, baseinstance)) \
  X(glDrawElementsInstancedBaseInstance, true,                                                                       \
    (GLenum mode, GLsizei count, GLenum type, const void* indices, GLsizei n, GLuint baseinstance),                 \
    (mode, count, type, indices, n, baseinstance))                                                                   \
  X(glDrawElementsInstancedBaseVertexBaseInstance, true,                                                             \
    (GLenum mode, GLsizei count, GLenum type, const void* indices, GLsizei n, GLint basevertex, GLuint baseinstance), \
    (mode, count, type, indices, n, basevertex, baseinstance))                                                       \
  X(glMultiDrawArrays, true, (GLenum mode, const GLint* first, const GLsizei* count, GLsizei drawcount),            \
    (mode, first, count, drawcount))                                                                                 \
  X(glMultiDrawArraysEXT, true, (GLenum mode, const GLint* first, const GLsizei* count, GLsizei drawcount),         \
    (mode, first, count, drawcount))                                                                                 \
  X(glMultiDrawElements, true,                                                                                       \
    (GLenum mode, const GLsizei* count, GLenum type, const void* const* indices, GLsizei drawcount),                \
    (mode, count, type, indices, drawcount))                                                                         \
  X(glMultiDrawElementsEXT, true,                                                                                    \
    (GLenum mode, const GLsizei* count, GLenum type, const void* const* indices, GLsizei drawcount),                \
    (mode, count, type, indices, drawcount))                                                                         \
  X(glMultiDrawElementsBaseVertex, true,                                                                             \
    (GLenum mode, const GLsizei* count, GLenum type, const void* const* indices, GLsizei drawcount,                 \
     const GLint* basevertex),                                                                                       \
    (mode, count, type, indices, drawcount, basevertex))                                                             \
  X(glDrawArraysIndirect, true, (GLenum mode, const void* indirect), (mode, indirect))                               \
  X(glDrawElementsIndirect, true, (GLenum mode, GLenum type, const void* indirect), (mode, type, indirect))          \
  X(glMultiDrawArraysIndirect, true, (GLenum mode, const void* indirect, GLsizei drawcount, GLsizei stride),        \
    (mode, indirect, drawcount, stride))                                                                             \
  X(glMultiDrawElementsIndirect, true,                                                                               \
    (GLenum mode, GLenum type, const void* indirect, GLsizei drawcount, GLsizei stride),                            \
    (mode, type, indirect, drawcount, stride))                                                                       \
  X(glDrawTransformFeedback, false, (GLenum mode, GLuint id), (mode, id))                                            \
  X(glDrawTransformFeedbackStream, false, (GLenum mode, GLuint id, GLuint stream), (mode, id, stream))               \
  X(glDrawTransformFeedbackInstanced, true, (GLenum mode, GLuint id, GLsizei n), (mode, id, n))                      \
  X(glDrawTransformFeedbackStreamInstanced, true, (GLenum mode, GLuint id, GLuint stream, GLsizei n),                \
    (mode, id, stream, n))

#define OITSIM_DEFINE_DRAW(name, multi, params, args)                   \
  OITSIM_EXPORT void name params {                                      \
    static auto next = real<void(*) params>(#name);                    \
    Recorder::get().draw(#name, multi, [&] { next args; });            \
  }
OITSIM_DRAWS(OITSIM_DEFINE_DRAW)
#undef OITSIM_DEFINE_DRAW

// Draws the trace cannot take apart: listed, never recorded.
OITSIM_EXPORT void glBegin(GLenum mode) {
  static auto next = real<void (*)(GLenum)>("glBegin");
  Recorder::get().uncapturable("glBegin", stream::kImmediateMode, stream::kFixedFunction);
  next(mode);
}
OITSIM_EXPORT void glCallList(GLuint list) {
  static auto next = real<void (*)(GLuint)>("glCallList");
  Recorder::get().uncapturable("glCallList", stream::kDisplayList, stream::kDisplayList);
  next(list);
}
OITSIM_EXPORT void glCallLists(GLsizei n, GLenum type, const void* lists) {
  static auto next = real<void (*)(GLsizei, GLenum, const void*)>("glCallLists");
  Recorder::get().uncapturable("glCallLists", stream::kDisplayList, stream::kDisplayList);
  next(n, type, lists);
}

// Programs.
OITSIM_EXPORT void glLinkProgram(GLuint program) {
  static auto next = real<void (*)(GLuint)>("glLinkProgram");
  next(program);
  Recorder::get().afterLink(program);
}
OITSIM_EXPORT void glLinkProgramARB(GLuint program) {
  static auto next = real<void (*)(GLuint)>("glLinkProgramARB");
  next(program);
  Recorder::get().afterLink(program);
}
OITSIM_EXPORT void glDeleteProgram(GLuint program) {
  static auto next = real<void (*)(GLuint)>("glDeleteProgram");
  Recorder::get().forgetProgram(program);
  next(program);
}
OITSIM_EXPORT void glDeleteObjectARB(GLuint object) {
  static auto next = real<void (*)(GLuint)>("glDeleteObjectARB");
  Recorder::get().forgetProgram(object);
  next(object);
}

// Frame boundaries: glretrace presents with GLX.
OITSIM_EXPORT void glXSwapBuffers(void* display, unsigned long drawable) {
  static auto next = real<void (*)(void*, unsigned long)>("glXSwapBuffers");
  Recorder::get().swap();
  next(display, drawable);
}

// GetProcAddress: hand out the wrappers above for their names.
namespace {

void* ownProc(const char* name) {
  if (std::strncmp(name, "gl", 2) != 0) return nullptr;
  // This library's own handle: dlsym on it searches it first, then its dependencies.
  static Dl_info mine = [] {
    Dl_info d{};
    dladdr(reinterpret_cast<void*>(&ownProc), &d);
    return d;
  }();
  static void* self = mine.dli_fname ? dlopen(mine.dli_fname, RTLD_LAZY | RTLD_NOLOAD) : nullptr;
  void* p = self ? dlsym(self, name) : nullptr;
  Dl_info info{};
  if (p && dladdr(p, &info) && info.dli_fbase == mine.dli_fbase) return p;
  return nullptr;
}

}  // namespace

OITSIM_EXPORT void* glXGetProcAddressARB(const unsigned char* name) {
  static auto next = real<void* (*)(const unsigned char*)>("glXGetProcAddressARB");
  if (void* p = ownProc(reinterpret_cast<const char*>(name))) return p;
  return next ? next(name) : nullptr;
}
OITSIM_EXPORT void* glXGetProcAddress(const unsigned char* name) { return glXGetProcAddressARB(name); }
__attribute__((destructor)) static void oitsimInterposerExit() { Recorder::get().atExit(); }
