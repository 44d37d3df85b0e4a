// The EGL and OpenGL entry points of the headless capture, loaded at run time
// (dlopen of GLVND's libEGL.so.1 and libOpenGL.so.0) the first time a capture
// starts, so that the oitsim executable does not link GL: `run`, `sweep` and
// every other command start on machines (e.g. cluster compute nodes) that have
// no GL libraries at all. Only traces/capture/GlCapture.cpp and EglContext.cpp include this.
#pragma once

#include <string>

#define EGL_NO_PROTOTYPES 1  // the entry points are the pointers below
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GL/glcorearb.h>  // without GL_GLEXT_PROTOTYPES: the PFN... types only

namespace oit::capture::gl {

// X(type, name) for every entry point the capture calls.
#define OITSIM_EGL_ENTRY_POINTS(X) \
  X(PFNEGLBINDAPIPROC, eglBindAPI) \
  X(PFNEGLCREATECONTEXTPROC, eglCreateContext) \
  X(PFNEGLDESTROYCONTEXTPROC, eglDestroyContext) \
  X(PFNEGLGETERRORPROC, eglGetError) \
  X(PFNEGLGETPROCADDRESSPROC, eglGetProcAddress) \
  X(PFNEGLINITIALIZEPROC, eglInitialize) \
  X(PFNEGLMAKECURRENTPROC, eglMakeCurrent) \
  X(PFNEGLQUERYSTRINGPROC, eglQueryString)

#define OITSIM_GL_ENTRY_POINTS(X) \
  X(PFNGLATTACHSHADERPROC, glAttachShader) \
  X(PFNGLBINDBUFFERBASEPROC, glBindBufferBase) \
  X(PFNGLBINDFRAMEBUFFERPROC, glBindFramebuffer) \
  X(PFNGLBINDVERTEXARRAYPROC, glBindVertexArray) \
  X(PFNGLBLENDFUNCPROC, glBlendFunc) \
  X(PFNGLCHECKNAMEDFRAMEBUFFERSTATUSPROC, glCheckNamedFramebufferStatus) \
  X(PFNGLCLEARNAMEDFRAMEBUFFERFVPROC, glClearNamedFramebufferfv) \
  X(PFNGLCOLORMASKPROC, glColorMask) \
  X(PFNGLCOMPILESHADERPROC, glCompileShader) \
  X(PFNGLCREATEBUFFERSPROC, glCreateBuffers) \
  X(PFNGLCREATEFRAMEBUFFERSPROC, glCreateFramebuffers) \
  X(PFNGLCREATEPROGRAMPROC, glCreateProgram) \
  X(PFNGLCREATERENDERBUFFERSPROC, glCreateRenderbuffers) \
  X(PFNGLCREATESHADERPROC, glCreateShader) \
  X(PFNGLCREATETEXTURESPROC, glCreateTextures) \
  X(PFNGLCREATEVERTEXARRAYSPROC, glCreateVertexArrays) \
  X(PFNGLCULLFACEPROC, glCullFace) \
  X(PFNGLDELETEBUFFERSPROC, glDeleteBuffers) \
  X(PFNGLDELETEFRAMEBUFFERSPROC, glDeleteFramebuffers) \
  X(PFNGLDELETEPROGRAMPROC, glDeleteProgram) \
  X(PFNGLDELETERENDERBUFFERSPROC, glDeleteRenderbuffers) \
  X(PFNGLDELETESHADERPROC, glDeleteShader) \
  X(PFNGLDELETETEXTURESPROC, glDeleteTextures) \
  X(PFNGLDELETEVERTEXARRAYSPROC, glDeleteVertexArrays) \
  X(PFNGLDEPTHFUNCPROC, glDepthFunc) \
  X(PFNGLDEPTHMASKPROC, glDepthMask) \
  X(PFNGLDISABLEPROC, glDisable) \
  X(PFNGLDRAWARRAYSPROC, glDrawArrays) \
  X(PFNGLENABLEPROC, glEnable) \
  X(PFNGLENABLEVERTEXARRAYATTRIBPROC, glEnableVertexArrayAttrib) \
  X(PFNGLFRONTFACEPROC, glFrontFace) \
  X(PFNGLGETERRORPROC, glGetError) \
  X(PFNGLGETINTEGER64VPROC, glGetInteger64v) \
  X(PFNGLGETINTEGERVPROC, glGetIntegerv) \
  X(PFNGLGETNAMEDBUFFERSUBDATAPROC, glGetNamedBufferSubData) \
  X(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog) \
  X(PFNGLGETPROGRAMIVPROC, glGetProgramiv) \
  X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog) \
  X(PFNGLGETSHADERIVPROC, glGetShaderiv) \
  X(PFNGLGETSTRINGPROC, glGetString) \
  X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation) \
  X(PFNGLLINKPROGRAMPROC, glLinkProgram) \
  X(PFNGLMEMORYBARRIERPROC, glMemoryBarrier) \
  X(PFNGLNAMEDBUFFERDATAPROC, glNamedBufferData) \
  X(PFNGLNAMEDBUFFERSTORAGEPROC, glNamedBufferStorage) \
  X(PFNGLNAMEDBUFFERSUBDATAPROC, glNamedBufferSubData) \
  X(PFNGLNAMEDFRAMEBUFFERRENDERBUFFERPROC, glNamedFramebufferRenderbuffer) \
  X(PFNGLNAMEDFRAMEBUFFERTEXTUREPROC, glNamedFramebufferTexture) \
  X(PFNGLNAMEDRENDERBUFFERSTORAGEPROC, glNamedRenderbufferStorage) \
  X(PFNGLREADPIXELSPROC, glReadPixels) \
  X(PFNGLSHADERSOURCEPROC, glShaderSource) \
  X(PFNGLTEXTURESTORAGE2DPROC, glTextureStorage2D) \
  X(PFNGLUNIFORM1FPROC, glUniform1f) \
  X(PFNGLUNIFORM1IPROC, glUniform1i) \
  X(PFNGLUNIFORM1UIPROC, glUniform1ui) \
  X(PFNGLUNIFORM3FPROC, glUniform3f) \
  X(PFNGLUSEPROGRAMPROC, glUseProgram) \
  X(PFNGLVERTEXARRAYATTRIBBINDINGPROC, glVertexArrayAttribBinding) \
  X(PFNGLVERTEXARRAYATTRIBFORMATPROC, glVertexArrayAttribFormat) \
  X(PFNGLVERTEXARRAYVERTEXBUFFERPROC, glVertexArrayVertexBuffer) \
  X(PFNGLVIEWPORTPROC, glViewport)

#define OITSIM_DECLARE_ENTRY_POINT(type, name) extern type name;
OITSIM_EGL_ENTRY_POINTS(OITSIM_DECLARE_ENTRY_POINT)
OITSIM_GL_ENTRY_POINTS(OITSIM_DECLARE_ENTRY_POINT)
#undef OITSIM_DECLARE_ENTRY_POINT

// Loads the libraries and every entry point once per process. Returns an empty
// string on success, else one line saying which library or entry point is
// missing and what to install (the same message on every later call).
const std::string& loadEntryPoints();

}  // namespace oit::capture::gl
