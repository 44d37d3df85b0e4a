// Recorder::afterLink: the GL side of the fragment shader rewrite (the text side is
// ShaderRewrite.cpp). The program is first linked as the application asked; only a
// program that links is rewritten and linked again with the record code, then its
// shader attachments are put back as they were.
#include <string>
#include <vector>

#include "traces/capture/interposer/Recorder.hpp"
#include "traces/capture/interposer/ShaderRewrite.hpp"

namespace oit::capture::interposer {

using namespace stream;

namespace {

std::string shaderSource(GLuint shader) {
  RealGl& g = gl();
  GLint len = 0;
  g.glGetShaderiv(shader, GL_SHADER_SOURCE_LENGTH, &len);
  if (len <= 0) return {};
  std::string s(static_cast<size_t>(len), '\0');
  GLsizei got = 0;
  g.glGetShaderSource(shader, len, &got, s.data());
  s.resize(static_cast<size_t>(got));
  return s;
}

std::string firstLines(std::string log, size_t max_lines = 3) {
  size_t pos = 0;
  for (size_t i = 0; i < max_lines && pos != std::string::npos; ++i) {
    pos = log.find('\n', pos);
    if (pos != std::string::npos) ++pos;
  }
  if (pos != std::string::npos) log.resize(pos);
  while (!log.empty() && (log.back() == '\n' || log.back() == ' ')) log.pop_back();
  for (char& c : log)
    if (c == '\n') c = ' ';
  return log;
}

// Compiles a shader of `type`; returns 0 and fills log on failure.
GLuint compileShader(GLenum type, const std::string& src, std::string& log) {
  RealGl& g = gl();
  const GLuint s = g.glCreateShader(type);
  const char* text = src.c_str();
  g.glShaderSource(s, 1, &text, nullptr);
  g.glCompileShader(s);
  GLint ok = 0;
  g.glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (ok) return s;
  GLint len = 0;
  g.glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
  log.assign(static_cast<size_t>(std::max(len, 1)), '\0');
  g.glGetShaderInfoLog(s, len, nullptr, log.data());
  log.resize(log.find('\0') == std::string::npos ? log.size() : log.find('\0'));
  g.glDeleteShader(s);
  return 0;
}

// Output 0 of a linked program (location 0, index 0), as a vec4 expression; sets
// integer when it exists but is not a float type; nullopt when no user output has
// location 0 (the built-ins are then used).
std::optional<std::string> userOutput(GLuint program, bool es, bool& integer) {
  RealGl& g = gl();
  GLint count = 0;
  g.glGetProgramInterfaceiv(program, GL_PROGRAM_OUTPUT, GL_ACTIVE_RESOURCES, &count);
  for (GLint i = 0; i < count; ++i) {
    const GLenum props[3] = {GL_LOCATION, GL_TYPE, GL_LOCATION_INDEX};
    GLint values[3] = {-1, 0, 0};
    g.glGetProgramResourceiv(program, GL_PROGRAM_OUTPUT, static_cast<GLuint>(i), es ? 2 : 3, props, 3, nullptr,
                             values);
    if (values[0] != 0 || values[2] != 0) continue;
    char name[256] = {};
    g.glGetProgramResourceName(program, GL_PROGRAM_OUTPUT, static_cast<GLuint>(i), sizeof name, nullptr, name);
    const std::string n(name);
    if (n.rfind("gl_", 0) == 0) continue;
    // An array output is reported as "name[0]": element 0 is the one at location 0.
    auto expr = glsl::outputExpression(n, static_cast<uint32_t>(values[1]));
    if (!expr) integer = true;
    return expr;
  }
  return std::nullopt;
}

}  // namespace

void Recorder::afterLink(GLuint program) {
  if (!active_) return;
  ensureGl();
  RealGl& g = gl();
  programs_.erase(program);
  GLint linked = 0;
  g.glGetProgramiv(program, GL_LINK_STATUS, &linked);
  if (!linked) return;  // the application's own failure: nothing to rewrite
  // A program that is not rewritten is remembered with the reason its draws are
  // not captured.
  auto refuse = [&](uint32_t reason) {
    ProgramInfo refused;
    refused.reason = reason;
    programs_[program] = refused;
  };

  GLint attached = 0;
  g.glGetProgramiv(program, GL_ATTACHED_SHADERS, &attached);
  std::vector<GLuint> shaders(static_cast<size_t>(std::max(attached, 0)));
  if (attached > 0) g.glGetAttachedShaders(program, attached, nullptr, shaders.data());
  GLuint main_shader = 0;
  std::string source;
  glsl::SourceInfo si;
  for (GLuint s : shaders) {
    GLint type = 0;
    g.glGetShaderiv(s, GL_SHADER_TYPE, &type);
    if (type != GL_FRAGMENT_SHADER) continue;
    std::string src = shaderSource(s);
    if (const glsl::SourceInfo inspected = glsl::inspect(src); inspected.defines_main) {
      main_shader = s;
      source = std::move(src);
      si = inspected;
      break;
    }
  }
  if (!main_shader) return refuse(kNotRewritten);
  std::string colour;
  if (!(si.es && si.version < 300)) {
    bool integer = false;
    std::optional<std::string> out;
    if (si.es || si.version >= 130) out = userOutput(program, si.es, integer);
    if (integer) return refuse(kIntegerOutput);
    if (!out) out = glsl::builtinColour(si);
    if (!out) return refuse(kNoColourOutput);
    colour = *out;
  } else if (!si.uses_frag_color && !si.uses_frag_data) {
    return refuse(kNoColourOutput);
  }
  // Early depth tests record exactly the fragments that pass GL's depth test; a
  // shader that discards or writes depth needs the late test (see CAPTURE.md).
  const bool early = !si.has_discard && !si.writes_frag_depth;
  const glsl::Bindings bindings{record_binding_, count_binding_};
  const std::string version = std::to_string(si.version) + (si.es ? " es" : "");
  auto failure = [&](const std::string& what, const std::string& log) {
    fail("program " + std::to_string(program) + " (fragment shader GLSL " + version + ") " + what +
         " after rewriting: " + firstLines(log));
  };

  std::vector<GLuint> added, replaced;  // shaders attached for the link; the application's taken off
  std::string log;
  if (si.es) {
    const GLuint s = compileShader(GL_FRAGMENT_SHADER, glsl::rewriteEs(source, si, colour, bindings, early), log);
    if (!s) failure("does not compile", log);
    added.push_back(s);
    // GLSL ES links only shaders of one version: the other stages go to 3.20 too.
    for (GLuint other : shaders) {
      if (other == main_shader) continue;
      const std::string other_source = shaderSource(other);
      const glsl::SourceInfo oi = glsl::inspect(other_source);
      if (!oi.es || oi.version == 320) continue;
      GLint type = 0;
      g.glGetShaderiv(other, GL_SHADER_TYPE, &type);
      const GLuint o = compileShader(static_cast<GLenum>(type), glsl::esStageAt320(other_source, oi), log);
      if (!o) failure("does not compile (another stage at GLSL ES 3.20)", log);
      g.glDetachShader(program, other);
      replaced.push_back(other);
      added.push_back(o);
    }
  } else {
    const GLuint a = compileShader(GL_FRAGMENT_SHADER, glsl::rewriteDesktopMain(source, si, colour), log);
    if (!a) failure("does not compile", log);
    const GLuint b = compileShader(GL_FRAGMENT_SHADER, glsl::desktopRecordUnit(bindings, early), log);
    if (!b) failure("does not compile (record unit)", log);
    added = {a, b};
  }
  g.glDetachShader(program, main_shader);
  for (GLuint s : added) g.glAttachShader(program, s);
  g.glLinkProgram(program);
  g.glGetProgramiv(program, GL_LINK_STATUS, &linked);
  if (!linked) {
    GLint len = 0;
    g.glGetProgramiv(program, GL_INFO_LOG_LENGTH, &len);
    log.assign(static_cast<size_t>(std::max(len, 1)), '\0');
    g.glGetProgramInfoLog(program, len, nullptr, log.data());
    log.resize(log.find('\0') == std::string::npos ? log.size() : log.find('\0'));
    failure("fails to link", log);
  }
  // The application sees the shaders it attached; the linked code stays.
  for (GLuint s : added) {
    g.glDetachShader(program, s);
    g.glDeleteShader(s);
  }
  g.glAttachShader(program, main_shader);
  for (GLuint s : replaced) g.glAttachShader(program, s);
  ProgramInfo info;
  info.rewritten = true;
  info.reason = kCaptured;
  info.early_tests = early;
  info.loc_mode = g.glGetUniformLocation(program, glsl::kUniformMode);
  info.loc_draw = g.glGetUniformLocation(program, glsl::kUniformDraw);
  info.loc_capacity = g.glGetUniformLocation(program, glsl::kUniformCapacity);
  info.loc_width = g.glGetUniformLocation(program, glsl::kUniformWidth);
  programs_[program] = info;
}

}  // namespace oit::capture::interposer
