// shtool gen-shader end to end: the include-file contract that engines and outside
// checks rely on (no #version, no main, no bindings; SHTOOL_ORDER; the documented
// signatures), constants at full float precision, the same bytes on every run, and
// bad requests refused by name with nothing written. That the code computes the right
// values is tests/gpu/test_shaders.cpp, on a Vulkan device.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "cli_test.h"

namespace {

using namespace shtool::test;

const Scratch scratch("gen_shader");

shtool::test::CommandResult gen(const std::vector<std::string>& args) {
  std::vector<std::string> argv = {"gen-shader"};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_shtool(argv);
}

const char* kOperations[] = {"sh-eval",        "sh-irradiance", "zxzxz-rotate", "zhf-rotate", "zhf-tailored-rotate",
                             "triple-product", "zh-shade",      "l1-irradiance", "zh3-irradiance"};

TEST(GenShader, EveryOperationIsAnIncludeWithTheContract) {
  for (const char* lang : {"glsl", "hlsl"})
    for (const char* what : kOperations) {
      const fs::path out = scratch(std::string(what) + "." + lang);
      const auto r = gen({"--lang", lang, "--what", what, "--order", "3", "--out", out.string()});
      ASSERT_EQ(r.exit_code, 0) << r.err;
      EXPECT_NE(r.err.find("multiplications"), std::string::npos) << r.err;
      const std::string text = read_file(out);
      SCOPED_TRACE(std::string(lang) + " " + what);
      EXPECT_EQ(text.find("#version"), std::string::npos);
      EXPECT_EQ(text.find("main("), std::string::npos);
      EXPECT_EQ(text.find("binding"), std::string::npos);
      EXPECT_EQ(text.find("register("), std::string::npos);
      EXPECT_EQ(text.find("#include"), std::string::npos);
      EXPECT_NE(text.find("\n#define SHTOOL_ORDER 3\n"), std::string::npos);
      // The provenance header records the command.
      EXPECT_NE(text.find(std::string("shtool gen-shader --lang ") + lang + " --what " + what + " --order 3"),
                std::string::npos);
    }
}

TEST(GenShader, SignaturesAsDocumented) {
  struct Expect {
    const char *lang, *what, *signature;
  } expects[] = {
      {"glsl", "sh-eval", "void shtool_sh_eval(vec3 dir, out float y[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"hlsl", "sh-eval", "void shtool_sh_eval(float3 dir, out float y[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"glsl", "zxzxz-rotate",
       "void shtool_rotate(mat3 R, float f[SHTOOL_ORDER * SHTOOL_ORDER], out float g[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"hlsl", "zxzxz-rotate",
       "void shtool_rotate(float3x3 R, float f[SHTOOL_ORDER * SHTOOL_ORDER], out float g[SHTOOL_ORDER * "
       "SHTOOL_ORDER])"},
      {"glsl", "sh-irradiance", "float shtool_sh_irradiance(vec3 n, float L[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"hlsl", "sh-irradiance",
       "float3 shtool_sh_irradiance_rgb(float3 n, float3 L[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"glsl", "triple-product",
       "void shtool_triple_product(float a[SHTOOL_ORDER * SHTOOL_ORDER], float b[SHTOOL_ORDER * SHTOOL_ORDER], out "
       "float c[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"glsl", "zhf-rotate",
       "void shtool_zhf_rotate(mat3 R, float f[SHTOOL_ORDER * SHTOOL_ORDER], out float g[SHTOOL_ORDER * "
       "SHTOOL_ORDER])"},
      {"glsl", "zhf-tailored-rotate",
       "void shtool_zhf_tailored_rotate(mat3 R, highp samplerCube bands0, out float g[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"hlsl", "zhf-tailored-rotate",
       "void shtool_zhf_tailored_rotate(float3x3 R, TextureCube<float4> bands0, SamplerState bands_sampler, out "
       "float g[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"glsl", "zhf-tailored-rotate",
       "void shtool_zhf_tailored_rotate_arithmetic(mat3 R, float f[SHTOOL_ORDER * SHTOOL_ORDER], out float "
       "g[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"glsl", "zhf-tailored-rotate",
       "void shtool_sh_band_sums(vec3 dir, float c[SHTOOL_ORDER * SHTOOL_ORDER], out float bands[SHTOOL_ORDER])"},
      {"glsl", "zh-shade",
       "float shtool_zh_shade_table(vec3 axes[SHTOOL_ZH_LOBES], float g[SHTOOL_ZH_LOBES * SHTOOL_ORDER], "
       "highp samplerCube bands0)"},
      {"glsl", "zh-shade",
       "float shtool_zh_shade(vec3 axes[SHTOOL_ZH_LOBES], float g[SHTOOL_ZH_LOBES * SHTOOL_ORDER], float "
       "e[SHTOOL_ORDER * SHTOOL_ORDER])"},
      {"glsl", "l1-irradiance", "vec3 shtool_l1_irradiance(vec3 n, vec3 L[4])"},
      {"hlsl", "l1-irradiance", "float shtool_l1_irradiance_channel(float3 n, float c00, float3 d)"},
      {"glsl", "zh3-irradiance", "vec3 shtool_zh3_irradiance(vec3 n, vec3 L[4], vec3 zonal)"},
      {"hlsl", "zh3-irradiance", "float3 shtool_zh3_hallucinate_irradiance(float3 n, float3 L[4])"},
      {"glsl", "zh3-irradiance", "vec3 shtool_zh3_irradiance_per_channel(vec3 n, vec3 L[4], vec3 zonal)"},
  };
  for (const Expect& e : expects) {
    const fs::path out = scratch("sig.txt");
    const auto r = gen({"--lang", e.lang, "--what", e.what, "--order", "4", "--out", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(read_file(out).find(e.signature), std::string::npos) << e.lang << " " << e.what;
  }
}

// Every literal is written at full float precision: it is exactly the 9-significant-digit
// rendering of its own float (a constant cut to 6 digits is not: "0.488603" reads as the
// float 0.488602996), and y_0^0 is the float of 1 / (2 sqrt(pi)).
TEST(GenShader, ConstantsAtFullFloatPrecision) {
  for (const char* what : {"sh-eval", "zxzxz-rotate", "triple-product", "sh-irradiance"}) {
    const fs::path out = scratch("constants.glsl");
    ASSERT_EQ(gen({"--lang", "glsl", "--what", what, "--order", std::string(what) == std::string("sh-eval") ? "10" : "6",
                   "--out", out.string()})
                  .exit_code,
              0);
    // The code without its comments (the header names the tool's version).
    std::string text;
    {
      std::istringstream lines(read_file(out));
      for (std::string line; std::getline(lines, line);) text += line.substr(0, line.find("//")) + "\n";
    }
    if (std::string(what) == "sh-eval") EXPECT_NE(text.find("y[0] = 0.282094806;"), std::string::npos);
    const std::regex number(R"(\b(\d+\.\d+(e[-+]?\d+)?|\d+e[-+]?\d+)\b)");
    int checked = 0;
    for (auto it = std::sregex_iterator(text.begin(), text.end(), number); it != std::sregex_iterator(); ++it) {
      const std::string s = it->str();
      char canonical[32];
      std::snprintf(canonical, sizeof canonical, "%.9g", static_cast<double>(std::strtof(s.c_str(), nullptr)));
      std::string expected = canonical;
      if (expected.find_first_of(".e") == std::string::npos) expected += ".0";
      EXPECT_EQ(s, expected) << what;
      ++checked;
    }
    EXPECT_GT(checked, 20) << what;
  }
}

TEST(GenShader, SameBytesOnEveryRun) {
  for (const char* what : kOperations) {
    const fs::path a = scratch("a.hlsl"), b = scratch("sub/a.hlsl");
    fs::create_directories(b.parent_path());
    ASSERT_EQ(gen({"--lang", "hlsl", "--what", what, "--order", "5", "--out", a.string()}).exit_code, 0);
    ASSERT_EQ(gen({"--lang", "hlsl", "--what", what, "--order", "5", "--out", b.string()}).exit_code, 0);
    EXPECT_EQ(read_file(a), read_file(b)) << what;
  }
}

TEST(GenShader, BadRequestsAreRefusedByName) {
  struct Bad {
    std::vector<std::string> args;
    const char* message;
  } bad[] = {
      {{"--lang", "glsl", "--what", "sh-eval", "--order", "11"}, "--order 11"},
      {{"--lang", "glsl", "--what", "sh-eval", "--order", "0"}, "--order 0"},
      {{"--lang", "glsl", "--what", "zxzxz-rotate", "--order", "9"}, "--order 9"},
      {{"--lang", "glsl", "--what", "zxzxz-rotate", "--order", "1"}, "--order 1"},
      {{"--lang", "glsl", "--what", "triple-product", "--order", "7"}, "--order 7"},
      {{"--lang", "glsl", "--what", "l1-irradiance", "--order", "1"}, "--order 1"},
      {{"--lang", "glsl", "--what", "zh3-irradiance", "--order", "11"}, "--order 11"},
      {{"--lang", "glsl", "--what", "sh-eval", "--order", "3", "--zh-lobes", "2"}, "--zh-lobes"},
      {{"--lang", "glsl", "--what", "zh-shade", "--order", "3", "--zh-lobes", "0"}, "--zh-lobes"},
      {{"--lang", "glsl", "--what", "zh-shade", "--order", "3", "--zh-lobes", "17"}, "--zh-lobes"},
      {{"--lang", "glsl", "--what", "zhf-nothing", "--order", "3"}, "--what"},
      {{"--lang", "msl", "--what", "sh-eval", "--order", "3"}, "--lang"},
      {{"--lang", "glsl", "--what", "sh-eval", "--order", "3", "--precision", "double"}, "--precision"},
      {{"--what", "sh-eval", "--order", "3"}, "--lang"},
      {{"--lang", "glsl", "--what", "zhf-rotate", "--order", "11"}, "--order 11"},
      {{"--lang", "glsl", "--what", "zxzxz-rotate", "--order", "3", "--lobes", "x.shtb"}, "--lobes"},
      {{"--lang", "glsl", "--what", "zhf-rotate", "--order", "3", "--lobes", SHTOOL_SOURCE_DIR "/data/sky.hdr"},
       "--lobes"},
      {{"--lang", "glsl", "--what", "zhf-rotate", "--order", "5", "--lobes",
        SHTOOL_SOURCE_DIR "/tables/zhf-shared-N4.shtb"},
       "--lobes"},
      {{"--lang", "glsl", "--what", "zhf-rotate", "--order", "3", "--lobes",
        SHTOOL_SOURCE_DIR "/tables/tripling-tensor.shtb"},
       "--lobes"},
  };
  for (const Bad& b : bad) {
    const fs::path out = scratch("bad.glsl");
    fs::remove(out);
    std::vector<std::string> args = b.args;
    args.insert(args.end(), {"--out", out.string()});
    const auto r = gen(args);
    EXPECT_EQ(r.exit_code, 1) << b.message;
    EXPECT_NE(r.err.find(b.message), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << b.message;
  }
  const auto r = gen({"--lang", "glsl", "--what", "sh-eval", "--order", "3", "--out", scratch("").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("is a folder"), std::string::npos) << r.err;
}

}  // namespace
