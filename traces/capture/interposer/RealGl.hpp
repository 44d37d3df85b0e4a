// The real GL entry points the interposer calls for its own work, resolved past
// itself (in GLVND's libOpenGL.so.0 and libGLX.so.0, then glXGetProcAddressARB /
// eglGetProcAddress), so that none of its own calls goes through its own wrappers.
#pragma once

#include <GL/glcorearb.h>

namespace oit::capture::interposer {

// Resolves `name` past the interposer; nullptr when no library has it.
void* realProc(const char* name);

// X(type, name): every entry point the interposer uses for itself.
#define OITSIM_REAL_GL(X)                                                        \
  X(PFNGLATTACHSHADERPROC, glAttachShader)                                       \
  X(PFNGLBINDBUFFERPROC, glBindBuffer)                                           \
  X(PFNGLBINDBUFFERBASEPROC, glBindBufferBase)                                   \
  X(PFNGLBINDBUFFERRANGEPROC, glBindBufferRange)                                 \
  X(PFNGLBINDFRAMEBUFFERPROC, glBindFramebuffer)                                 \
  X(PFNGLBINDRENDERBUFFERPROC, glBindRenderbuffer)                               \
  X(PFNGLBINDTEXTUREPROC, glBindTexture)                                         \
  X(PFNGLBLITFRAMEBUFFERPROC, glBlitFramebuffer)                                 \
  X(PFNGLBUFFERDATAPROC, glBufferData)                                           \
  X(PFNGLBUFFERSUBDATAPROC, glBufferSubData)                                     \
  X(PFNGLCLEARBUFFERFVPROC, glClearBufferfv)                                     \
  X(PFNGLCOLORMASKPROC, glColorMask)                                             \
  X(PFNGLCOMPILESHADERPROC, glCompileShader)                                     \
  X(PFNGLCREATESHADERPROC, glCreateShader)                                       \
  X(PFNGLDELETERENDERBUFFERSPROC, glDeleteRenderbuffers)                         \
  X(PFNGLDELETESHADERPROC, glDeleteShader)                                       \
  X(PFNGLDELETETEXTURESPROC, glDeleteTextures)                                   \
  X(PFNGLDETACHSHADERPROC, glDetachShader)                                       \
  X(PFNGLDISABLEPROC, glDisable)                                                 \
  X(PFNGLENABLEPROC, glEnable)                                                   \
  X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, glFramebufferRenderbuffer)                 \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, glFramebufferTexture2D)                       \
  X(PFNGLGENBUFFERSPROC, glGenBuffers)                                           \
  X(PFNGLGENFRAMEBUFFERSPROC, glGenFramebuffers)                                 \
  X(PFNGLGENRENDERBUFFERSPROC, glGenRenderbuffers)                               \
  X(PFNGLGENTEXTURESPROC, glGenTextures)                                         \
  X(PFNGLGETATTACHEDSHADERSPROC, glGetAttachedShaders)                           \
  X(PFNGLGETBOOLEANI_VPROC, glGetBooleani_v)                                     \
  X(PFNGLGETERRORPROC, glGetError)                                               \
  X(PFNGLGETFRAMEBUFFERATTACHMENTPARAMETERIVPROC, glGetFramebufferAttachmentParameteriv) \
  X(PFNGLGETINTEGER64VPROC, glGetInteger64v)                                     \
  X(PFNGLGETINTEGERI_VPROC, glGetIntegeri_v)                                     \
  X(PFNGLGETINTEGER64I_VPROC, glGetInteger64i_v)                                 \
  X(PFNGLGETINTEGERVPROC, glGetIntegerv)                                         \
  X(PFNGLGETPROGRAMINFOLOGPROC, glGetProgramInfoLog)                             \
  X(PFNGLGETPROGRAMINTERFACEIVPROC, glGetProgramInterfaceiv)                     \
  X(PFNGLGETPROGRAMIVPROC, glGetProgramiv)                                       \
  X(PFNGLGETPROGRAMRESOURCEIVPROC, glGetProgramResourceiv)                       \
  X(PFNGLGETPROGRAMRESOURCENAMEPROC, glGetProgramResourceName)                   \
  X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog)                               \
  X(PFNGLGETSHADERIVPROC, glGetShaderiv)                                         \
  X(PFNGLGETSHADERSOURCEPROC, glGetShaderSource)                                 \
  X(PFNGLGETSTRINGPROC, glGetString)                                             \
  X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation)                           \
  X(PFNGLISENABLEDPROC, glIsEnabled)                                             \
  X(PFNGLISTEXTUREPROC, glIsTexture)                                             \
  X(PFNGLLINKPROGRAMPROC, glLinkProgram)                                         \
  X(PFNGLMAPBUFFERRANGEPROC, glMapBufferRange)                                   \
  X(PFNGLMEMORYBARRIERPROC, glMemoryBarrier)                                     \
  X(PFNGLPIXELSTOREIPROC, glPixelStorei)                                         \
  X(PFNGLPROGRAMUNIFORM1UIPROC, glProgramUniform1ui)                             \
  X(PFNGLREADPIXELSPROC, glReadPixels)                                           \
  X(PFNGLRENDERBUFFERSTORAGEPROC, glRenderbufferStorage)                         \
  X(PFNGLSHADERSOURCEPROC, glShaderSource)                                       \
  X(PFNGLTEXSTORAGE2DPROC, glTexStorage2D)                                       \
  X(PFNGLUNMAPBUFFERPROC, glUnmapBuffer)

// Optional (desktop GL 4.5 direct state access): nullptr on ES.
#define OITSIM_REAL_GL_OPTIONAL(X)                                               \
  X(PFNGLGETTEXTURELEVELPARAMETERIVPROC, glGetTextureLevelParameteriv)           \
  X(PFNGLGETNAMEDRENDERBUFFERPARAMETERIVPROC, glGetNamedRenderbufferParameteriv)  \
  X(PFNGLCLAMPCOLORPROC, glClampColor)

struct RealGl {
#define OITSIM_REAL_MEMBER(type, name) type name = nullptr;
  OITSIM_REAL_GL(OITSIM_REAL_MEMBER)
  OITSIM_REAL_GL_OPTIONAL(OITSIM_REAL_MEMBER)
#undef OITSIM_REAL_MEMBER
  // Resolves every entry point (a context must be current for GetProcAddress);
  // returns "" or the name of the first missing one.
  const char* load();
};

RealGl& gl();

}  // namespace oit::capture::interposer
