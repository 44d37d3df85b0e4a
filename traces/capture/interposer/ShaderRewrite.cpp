#include "traces/capture/interposer/ShaderRewrite.hpp"

#include <cctype>
#include <cstdlib>
#include <string>

namespace oit::capture::glsl {

namespace {

// GL type enums of float outputs (glcorearb.h values; no GL header needed here).
constexpr uint32_t kFloat = 0x1406, kVec2 = 0x8B50, kVec3 = 0x8B51, kVec4 = 0x8B52;

bool identChar(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

// The source with comments replaced by blanks (newlines kept), so offsets and
// line structure stay those of the original.
std::string withoutComments(std::string_view s) {
  std::string out(s);
  for (size_t i = 0; i < out.size(); ++i) {
    if (out[i] == '/' && i + 1 < out.size() && out[i + 1] == '/') {
      while (i < out.size() && out[i] != '\n') out[i++] = ' ';
    } else if (out[i] == '/' && i + 1 < out.size() && out[i + 1] == '*') {
      out[i] = out[i + 1] = ' ';
      for (i += 2; i < out.size() && !(out[i] == '*' && i + 1 < out.size() && out[i + 1] == '/'); ++i)
        if (out[i] != '\n') out[i] = ' ';
      if (i < out.size()) out[i] = out[i + 1] = ' ', ++i;
    }
  }
  return out;
}

// Offset of the first occurrence of identifier `token` as a whole token, or npos.
size_t findToken(std::string_view s, std::string_view token, size_t from = 0) {
  for (size_t p = s.find(token, from); p != std::string_view::npos; p = s.find(token, p + 1)) {
    const bool left = p == 0 || !identChar(s[p - 1]);
    const bool right = p + token.size() >= s.size() || !identChar(s[p + token.size()]);
    if (left && right) return p;
  }
  return std::string_view::npos;
}

bool hasToken(std::string_view s, std::string_view token) { return findToken(s, token) != std::string_view::npos; }

// Start offsets of the lines of s that are preprocessor directives named `name`.
template <typename F>
void forEachDirective(std::string_view s, std::string_view name, F&& f) {
  size_t line = 0;
  while (line < s.size()) {
    size_t end = s.find('\n', line);
    if (end == std::string_view::npos) end = s.size();
    size_t i = line;
    while (i < end && (s[i] == ' ' || s[i] == '\t' || s[i] == '\r')) ++i;
    if (i < end && s[i] == '#') {
      ++i;
      while (i < end && (s[i] == ' ' || s[i] == '\t')) ++i;
      if (s.substr(i, name.size()) == name && (i + name.size() == end || !identChar(s[i + name.size()])))
        f(line, i + name.size(), end);
    }
    line = end + 1;
  }
}

// Where declarations may go: after the #version line and after every #extension
// directive (which must precede all other tokens).
size_t declarationPoint(std::string_view clean, const SourceInfo& info) {
  size_t at = info.after_version;
  forEachDirective(clean, "extension", [&](size_t, size_t, size_t end) {
    at = std::max(at, end < clean.size() ? end + 1 : clean.size());
  });
  return at;
}

// Text spliced in at `at`, on its own lines.
std::string insertAt(std::string_view s, size_t at, const std::string& text) {
  std::string out(s.substr(0, at));
  if (!out.empty() && out.back() != '\n') out += '\n';
  out += text;
  out.append(s.substr(at));
  return out;
}

std::string recordFunction(const Bindings& b, const char* hp) {
  // hp: "highp " for ES (every declaration needs a precision there), "" for desktop.
  std::string s;
  s += std::string("struct OitsimRecord { ") + hp + "uint xy; " + hp + "float z; " + hp + "uint prim; " + hp +
       "uint draw; " + hp + "vec4 rgba; };\n";
  s += "layout(std430, binding = " + std::to_string(b.records) +
       ") restrict buffer OitsimRecords { " + hp + "uint oitsim_count; " + hp + "uint oitsim_pad0; " + hp +
       "uint oitsim_pad1; " + hp + "uint oitsim_pad2; OitsimRecord oitsim_records[]; };\n";
  s += "layout(std430, binding = " + std::to_string(b.counts) + ") restrict buffer OitsimCounts { " + hp +
       "uint oitsim_pixel_counts[]; };\n";
  for (const char* u : {kUniformMode, kUniformDraw, kUniformCapacity, kUniformWidth})
    s += std::string("uniform ") + hp + "uint " + u + ";\n";
  s += std::string("void oitsim_record(") + hp + "vec4 oitsim_colour, " + hp + "float oitsim_depth) {\n";
  s += "  " + std::string(hp) + "uvec2 oitsim_xy = uvec2(gl_FragCoord.xy);\n";
  s += "  if ((oitsim_mode & 1u) != 0u) {\n";
  s += "    " + std::string(hp) + "uint oitsim_i = atomicAdd(oitsim_count, 1u);\n";
  s += "    if (oitsim_i < oitsim_capacity)\n";
  s += "      oitsim_records[oitsim_i] = OitsimRecord(oitsim_xy.x | (oitsim_xy.y << 16), oitsim_depth, "
       "uint(gl_PrimitiveID), oitsim_draw, oitsim_colour);\n";
  s += "  }\n  if ((oitsim_mode & 2u) != 0u) {\n";
  s += "    atomicAdd(oitsim_pixel_counts[oitsim_xy.y * oitsim_width + oitsim_xy.x], 1u);\n";
  s += "  }\n}\n";
  return s;
}

std::string newMain(const SourceInfo& info, const std::string& colour) {
  const char* depth = info.writes_frag_depth ? "gl_FragDepth" : "gl_FragCoord.z";
  return "void main() {\n  oitsim_app_main();\n  oitsim_record(" + colour + ", " + depth + ");\n}\n";
}

}  // namespace

SourceInfo inspect(std::string_view source) {
  SourceInfo info;
  const std::string clean = withoutComments(source);
  // #version must come first; take the first directive of that name.
  bool found = false;
  forEachDirective(clean, "version", [&](size_t, size_t args, size_t end) {
    if (found) return;
    found = true;
    info.has_version_line = true;
    info.after_version = end < clean.size() ? end + 1 : clean.size();
    const std::string rest(clean.substr(args, end - args));
    info.version = std::atoi(rest.c_str());
    info.es = rest.find("es") != std::string::npos && hasToken(rest, "es");
  });
  if (info.version == 100) info.es = true;
  // A definition of main: `main` followed by '(' ... ')' and then '{'.
  for (size_t p = findToken(clean, "main"); p != std::string::npos; p = findToken(clean, "main", p + 1)) {
    size_t i = p + 4;
    while (i < clean.size() && std::isspace(static_cast<unsigned char>(clean[i]))) ++i;
    if (i >= clean.size() || clean[i] != '(') continue;
    const size_t close = clean.find(')', i);
    if (close == std::string::npos) continue;
    size_t j = close + 1;
    while (j < clean.size() && std::isspace(static_cast<unsigned char>(clean[j]))) ++j;
    if (j < clean.size() && clean[j] == '{') {
      info.defines_main = true;
      break;
    }
  }
  info.has_discard = hasToken(clean, "discard");
  info.writes_frag_depth = hasToken(clean, "gl_FragDepth") || hasToken(clean, "gl_FragDepthEXT");
  info.uses_frag_color = hasToken(clean, "gl_FragColor");
  info.uses_frag_data = hasToken(clean, "gl_FragData");
  return info;
}

std::optional<std::string> outputExpression(const std::string& name, uint32_t gl_type) {
  switch (gl_type) {
    case kVec4: return name;
    case kVec3: return "vec4(" + name + ", 1.0)";
    case kVec2: return "vec4(" + name + ", 0.0, 1.0)";
    case kFloat: return "vec4(" + name + ", 0.0, 0.0, 1.0)";
    default: return std::nullopt;
  }
}

std::optional<std::string> builtinColour(const SourceInfo& info) {
  if (info.uses_frag_data) return std::string("gl_FragData[0]");
  if (info.uses_frag_color) return std::string("gl_FragColor");
  return std::nullopt;
}

std::string rewriteDesktopMain(std::string_view source, const SourceInfo& info, const std::string& colour) {
  std::string out = insertAt(source, info.after_version, "#define main oitsim_app_main\n");
  if (!out.empty() && out.back() != '\n') out += '\n';
  out += "#undef main\nvoid oitsim_record(vec4 oitsim_colour, float oitsim_depth);\n";
  out += newMain(info, colour);
  return out;
}

std::string desktopRecordUnit(const Bindings& b, bool early_tests) {
  std::string s = "#version 430\n";
  if (early_tests) s += "layout(early_fragment_tests) in;\n";
  return s + recordFunction(b, "");
}

namespace {

// GLSL ES 1.00 texture functions under their 3.20 names.
const char* kEs100TextureNames =
    "#define texture2D texture\n#define texture2DProj textureProj\n"
    "#define texture2DLod textureLod\n#define texture2DProjLod textureProjLod\n"
    "#define textureCube texture\n#define textureCubeLod textureLod\n"
    "#define texture2DLodEXT textureLod\n#define textureCubeLodEXT textureLod\n"
    "#define texture2DGradEXT textureGrad\n";

}  // namespace

std::string esStageAt320(std::string_view source, const SourceInfo& info) {
  std::string out = "#version 320 es\n";
  if (info.version < 300) out += std::string("#define attribute in\n#define varying out\n") + kEs100TextureNames;
  out.append(source.substr(info.after_version));
  return out;
}

std::string rewriteEs(std::string_view source, const SourceInfo& info, const std::string& colour,
                      const Bindings& b, bool early_tests) {
  const std::string clean = withoutComments(source);
  std::string head = "#version 320 es\n#define main oitsim_app_main\n";
  std::string decl;
  std::string colour_expr = colour;
  if (info.version < 300) {
    // 1.00 names on 3.20 ones.
    head += std::string("#define varying in\n") + kEs100TextureNames + "#define gl_FragDepthEXT gl_FragDepth\n";
    if (info.uses_frag_data) {
      head += "#define gl_FragData oitsim_frag_data\n";
      decl += "layout(location = 0) out highp vec4 oitsim_frag_data[4];\n";
    } else {
      head += "#define gl_FragColor oitsim_frag_data[0]\n";
      decl += "layout(location = 0) out highp vec4 oitsim_frag_data[1];\n";
    }
    colour_expr = "oitsim_frag_data[0]";
  }
  if (early_tests) decl += "layout(early_fragment_tests) in;\n";
  // The #version line is replaced; everything else is kept, declarations go after
  // the last #extension.
  const size_t at = declarationPoint(clean, info);
  std::string out = head;
  out.append(source.substr(info.after_version, at - info.after_version));
  if (!out.empty() && out.back() != '\n') out += '\n';
  out += decl;
  out.append(source.substr(at));
  if (!out.empty() && out.back() != '\n') out += '\n';
  out += "#undef main\n";
  out += recordFunction(b, "highp ");
  out += newMain(info, colour_expr);
  return out;
}

}  // namespace oit::capture::glsl
