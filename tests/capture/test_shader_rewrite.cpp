// The text side of the apitrace capture's fragment shader rewrite and the blend
// classification: pure functions, no GL (the GL side is test_apitrace_capture.cpp).
#include <gtest/gtest.h>

#include "traces/capture/interposer/BlendClass.hpp"
#include "traces/capture/interposer/ShaderRewrite.hpp"

namespace oit::capture {
namespace {

TEST(ShaderRewrite, InspectFindsVersionOutputsDiscardAndMain) {
  const glsl::SourceInfo a = glsl::inspect(
      "// discard in a comment does not count\n#version 120\nuniform vec4 c;\n"
      "void main ( ) { gl_FragColor = c; }\n");
  EXPECT_EQ(a.version, 120);
  EXPECT_FALSE(a.es);
  EXPECT_TRUE(a.defines_main);
  EXPECT_FALSE(a.has_discard);
  EXPECT_TRUE(a.uses_frag_color);
  EXPECT_FALSE(a.writes_frag_depth);
  const glsl::SourceInfo b = glsl::inspect(
      "#version 300 es\nprecision mediump float;\nout vec4 o;\nvoid main() { if (o.a < 0.5) discard; "
      "gl_FragDepth = 0.5; o = vec4(1); }\n");
  EXPECT_EQ(b.version, 300);
  EXPECT_TRUE(b.es);
  EXPECT_TRUE(b.has_discard);
  EXPECT_TRUE(b.writes_frag_depth);
  const glsl::SourceInfo c = glsl::inspect("void helper() {}\n");  // no version: 1.10, no main
  EXPECT_EQ(c.version, 110);
  EXPECT_FALSE(c.has_version_line);
  EXPECT_FALSE(c.defines_main);
}

TEST(ShaderRewrite, DesktopKeepsTheVersionAndCallsTheRecordAfterMain) {
  const std::string src = "#version 330 core\nout vec4 o;\nvoid main() { o = vec4(1); }\n";
  const glsl::SourceInfo info = glsl::inspect(src);
  const std::string out = glsl::rewriteDesktopMain(src, info, "o");
  EXPECT_EQ(out.rfind("#version 330 core\n#define main oitsim_app_main\n", 0), 0u) << out;
  EXPECT_NE(out.find("#undef main\nvoid oitsim_record(vec4 oitsim_colour, float oitsim_depth);\n"
                     "void main() {\n  oitsim_app_main();\n  oitsim_record(o, gl_FragCoord.z);\n}\n"),
            std::string::npos)
      << out;
  const std::string unit = glsl::desktopRecordUnit({7, 6}, true);
  EXPECT_EQ(unit.rfind("#version 430\nlayout(early_fragment_tests) in;\n", 0), 0u) << unit;
  EXPECT_NE(unit.find("layout(std430, binding = 7)"), std::string::npos) << unit;
  EXPECT_EQ(glsl::desktopRecordUnit({7, 6}, false).find("early_fragment_tests"), std::string::npos);
  // A shader writing gl_FragDepth records the depth it wrote.
  const std::string d = "#version 130\nvoid main() { gl_FragDepth = 0.25; gl_FragColor = vec4(1); }\n";
  EXPECT_NE(glsl::rewriteDesktopMain(d, glsl::inspect(d), "gl_FragColor").find("oitsim_record(gl_FragColor, gl_FragDepth)"),
            std::string::npos);
}

TEST(ShaderRewrite, Es100BecomesOne320Source) {
  const std::string src =
      "#version 100\n#extension GL_OES_standard_derivatives : enable\nprecision mediump float;\n"
      "varying vec2 uv;\nuniform sampler2D t;\nvoid main() { gl_FragColor = texture2D(t, uv); }\n";
  const glsl::SourceInfo info = glsl::inspect(src);
  ASSERT_TRUE(info.es);
  const std::string out = glsl::rewriteEs(src, info, "", {3, 2}, true);
  EXPECT_EQ(out.rfind("#version 320 es\n#define main oitsim_app_main\n", 0), 0u) << out;
  EXPECT_NE(out.find("#define gl_FragColor oitsim_frag_data[0]"), std::string::npos) << out;
  EXPECT_NE(out.find("#define texture2D texture"), std::string::npos) << out;
  // Declarations come after the #extension line.
  EXPECT_LT(out.find("#extension GL_OES_standard_derivatives"), out.find("out highp vec4 oitsim_frag_data[1]"));
  EXPECT_NE(out.find("oitsim_record(oitsim_frag_data[0], gl_FragCoord.z)"), std::string::npos) << out;
}

// GLSL ES links only shaders of one version: the vertex shader beside a rewritten
// ES fragment shader goes to 3.20 as well (the GL side: GlslEsShadersMatchTheMeshCapture).
TEST(ShaderRewrite, EsVertexStagesGoTo320) {
  const std::string v100 = "#version 100\nattribute vec4 a;\nvarying vec2 uv;\nvoid main() { uv = a.xy; gl_Position = a; }\n";
  const std::string out100 = glsl::esStageAt320(v100, glsl::inspect(v100));
  EXPECT_EQ(out100.rfind("#version 320 es\n#define attribute in\n#define varying out\n#define texture2D texture\n", 0), 0u)
      << out100;
  EXPECT_NE(out100.find("attribute vec4 a;\nvarying vec2 uv;\nvoid main() { uv = a.xy; gl_Position = a; }\n"),
            std::string::npos)
      << out100;
  EXPECT_EQ(out100.find("#version 100"), std::string::npos) << out100;
  const std::string v300 = "#version 300 es\nin vec4 a;\nvoid main() { gl_Position = a; }\n";
  EXPECT_EQ(glsl::esStageAt320(v300, glsl::inspect(v300)), "#version 320 es\nin vec4 a;\nvoid main() { gl_Position = a; }\n");
}

TEST(ShaderRewrite, OutputExpressions) {
  EXPECT_EQ(glsl::outputExpression("o", 0x8B52), "o");                          // vec4
  EXPECT_EQ(glsl::outputExpression("c", 0x8B51), "vec4(c, 1.0)");               // vec3
  EXPECT_EQ(glsl::outputExpression("v", 0x1406), "vec4(v, 0.0, 0.0, 1.0)");     // float
  EXPECT_FALSE(glsl::outputExpression("i", 0x8D8C));                            // ivec4: not a colour
}

TEST(BlendClass, ModesFromTheGlEnums) {
  using namespace stream;
  constexpr uint32_t kAdd = 0x8006, kMin = 0x8007;
  EXPECT_EQ(classifyBlend(false, kAdd, 0x0302, 0x0303), kBlendOff);
  EXPECT_EQ(classifyBlend(true, kAdd, 0x0302, 0x0303), kBlendOver);
  EXPECT_EQ(classifyBlend(true, kAdd, 1, 0x0303), kBlendPremulOver);
  EXPECT_EQ(classifyBlend(true, kAdd, 1, 1), kBlendAdditive);
  EXPECT_EQ(classifyBlend(true, kAdd, 0x0302, 1), kBlendAdditive);
  EXPECT_EQ(classifyBlend(true, kAdd, 0x0306, 0), kBlendMultiply);
  EXPECT_EQ(classifyBlend(true, kAdd, 0, 0x0300), kBlendMultiply);
  EXPECT_EQ(classifyBlend(true, kAdd, 1, 0), kBlendOff);  // ONE, ZERO writes the source
  EXPECT_EQ(classifyBlend(true, kMin, 0x0302, 0x0303), kBlendOther);
  EXPECT_EQ(classifyBlend(true, kAdd, 0x8001, 0x0303), kBlendOther);  // constant colour
}

}  // namespace
}  // namespace oit::capture
