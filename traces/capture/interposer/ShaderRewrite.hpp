// Rewrites an application's fragment shader so that, after its own main, every
// fragment that reaches the end of the shader is appended to a storage buffer
// (x, y, depth, the colour of output 0, primitive id, draw id). Pure text work:
// no GL here, so it is tested on its own (tests/capture/test_shader_rewrite.cpp).
//
// Desktop GLSL (1.10 - 4.60, core or compatibility): the application's source
// keeps its version; its main is renamed with a #define, a new main calls it and
// then oitsim_record(colour, depth), which lives in a second fragment shader object
// of version 4.30 linked into the same program (desktop GL links shader objects
// of different versions of one stage together). GLSL ES allows one object per stage
// of one version, so ES sources become a single `#version 320 es` source (1.00's
// attribute/varying/texture2D/gl_FragColor mapped onto 3.20's names).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace oit::capture::glsl {

struct SourceInfo {
  int version = 110;        // #version number; 110 when the source has none
  bool es = false;          // "es" profile (or version 100)
  bool has_version_line = false;
  size_t after_version = 0; // offset just past the #version line (0 without one)
  bool defines_main = false;
  bool has_discard = false;
  bool writes_frag_depth = false;  // gl_FragDepth (or gl_FragDepthEXT) appears
  bool uses_frag_color = false;    // gl_FragColor appears
  bool uses_frag_data = false;     // gl_FragData appears
};

// Scans a source (comments and the insides of #if 0 are not skipped: a mention in
// dead code only makes the rewrite more careful, never wrong).
SourceInfo inspect(std::string_view source);

// The colour expression for a user output of the given GL type (GL_FLOAT_VEC4 ...)
// named as GL reports it ("frag", "outs[0]"); nullopt for integer or non-float types.
std::optional<std::string> outputExpression(const std::string& name, uint32_t gl_type);

// The built-in output a pre-1.30 (or compatibility) shader writes: gl_FragData[0] when
// the source mentions gl_FragData, gl_FragColor when it mentions gl_FragColor, else
// nullopt (the shader writes no colour).
std::optional<std::string> builtinColour(const SourceInfo& info);

struct Bindings {
  uint32_t records = 0;   // shader storage binding of the record buffer
  uint32_t counts = 0;    // shader storage binding of the per-pixel counters (verify)
};

// Desktop: the application's source with main renamed and a new main appended that
// calls oitsim_record(colour, depth).
std::string rewriteDesktopMain(std::string_view source, const SourceInfo& info, const std::string& colour);

// Desktop: the second fragment shader object that defines oitsim_record. With
// early_tests the program runs the depth test before the shader (only for shaders
// that neither discard nor write gl_FragDepth, where it changes nothing GL draws).
std::string desktopRecordUnit(const Bindings& b, bool early_tests);

// ES: one `#version 320 es` source with the record code inside. colour is the
// expression for a 3.00+ source's output 0; for 1.00 sources pass "" (the rewrite
// declares the output that replaces gl_FragColor / gl_FragData).
std::string rewriteEs(std::string_view source, const SourceInfo& info, const std::string& colour,
                      const Bindings& b, bool early_tests);

// GLSL ES links only shaders of one version, so the program's other ES stages
// (a vertex shader of 1.00, 3.00 or 3.10) are recompiled as `#version 320 es`
// beside the rewritten fragment shader: the version line replaced, 1.00's
// `attribute`/`varying` and texture functions named as 3.20 names them.
std::string esStageAt320(std::string_view source, const SourceInfo& info);

// Names of the uniforms the injected code declares (set with glProgramUniform*).
inline constexpr const char* kUniformMode = "oitsim_mode";       // bits: 1 record, 2 count per pixel
inline constexpr const char* kUniformDraw = "oitsim_draw";
inline constexpr const char* kUniformCapacity = "oitsim_capacity";
inline constexpr const char* kUniformWidth = "oitsim_width";

}  // namespace oit::capture::glsl
