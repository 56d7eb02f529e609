// Smoke tests of the Vulkan compute harness itself: GLSL and HLSL shaders run on the
// device and checked bit for bit against the CPU, buffer order, bounds of the dispatch,
// cube textures (face order, orientation, filtering, bindings), the validator, and the
// errors a wrong shader or wrong arguments must produce.
#include <gtest/gtest.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <random>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "vulkan_compute.h"

namespace shtool::gpu {
namespace {

constexpr uint32_t kCount = 10000;  // not a multiple of 64: the last work group is partial
constexpr uint32_t kPad = 300;      // sentinel elements after kCount, more than a work group
constexpr float kSentinel = -1234.5f;

// A compute kernel over the elements i < count, 64 invocations a work group, in GLSL: the
// buffers' declarations, then main's body.
std::string glsl_kernel(const std::string& buffers, const std::string& body) {
  return "#version 450\n"
         "layout(local_size_x = 64) in;\n"
         "layout(push_constant) uniform Push { uint count; } pc;\n" +
         buffers +
         "void main() {\n"
         "  uint i = gl_GlobalInvocationID.x;\n"
         "  if (i >= pc.count) return;\n" +
         body + "}\n";
}

// The same in HLSL: the push constant's and the buffers' declarations, `count` the
// expression of the push constant's count, then main's body.
std::string hlsl_kernel(const std::string& declarations, const std::string& count, const std::string& body) {
  return declarations +
         "[numthreads(64, 1, 1)]\n"
         "void main(uint3 id : SV_DispatchThreadID) {\n"
         "  uint i = id.x;\n"
         "  if (i >= " + count + ") return;\n" +
         body + "}\n";
}

// Each kernel's body is written once, for both languages. `precise` keeps the device from
// fusing a * b + i into one rounding, which the CPU reference (below) does not do either.
const std::string kMultiplyAdd = R"(  precise float r = a[i] * b[i] + float(i);
  o[i] = r;
)";

const std::string kGlslMultiplyAdd = glsl_kernel(R"(layout(std430, set = 0, binding = 0) readonly buffer A { float a[]; };
layout(std430, set = 0, binding = 1) readonly buffer B { float b[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Out { float o[]; };
)", kMultiplyAdd);

const std::string kHlslMultiplyAdd = hlsl_kernel(R"(struct Push { uint count; };
[[vk::push_constant]] ConstantBuffer<Push> pc;
RWStructuredBuffer<float> a : register(u0);
RWStructuredBuffer<float> b : register(u1);
RWStructuredBuffer<float> o : register(u2);
)", "pc.count", kMultiplyAdd);

// Asymmetric in every buffer, so a harness that bound buffers in another order (or
// read-only HLSL t registers elsewhere than u registers) gives different numbers.
const std::string kFourBuffers = R"(  c[i] = a[i] - 2.0 * b[i] + c[i];
  d[i] = 3.0 * a[i] + b[i] - d[i];
)";

const std::string kGlslFourBuffers = glsl_kernel(R"(layout(std430, set = 0, binding = 0) readonly buffer A { float a[]; };
layout(std430, set = 0, binding = 1) readonly buffer B { float b[]; };
layout(std430, set = 0, binding = 2) buffer C { float c[]; };
layout(std430, set = 0, binding = 3) buffer D { float d[]; };
)", kFourBuffers);

const std::string kHlslFourBuffers = hlsl_kernel(R"([[vk::push_constant]] cbuffer Push { uint count; };
StructuredBuffer<float> a : register(t0);
StructuredBuffer<float> b : register(t1);
RWStructuredBuffer<float> c : register(u2);
RWStructuredBuffer<float> d : register(u3);
)", "count", kFourBuffers);

// Bit for bit, so -0 against +0 or a different rounding counts; reports the first few.
void expect_bits_equal(const std::vector<float>& got, const std::vector<float>& want, const std::string& what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  size_t wrong = 0;
  for (size_t i = 0; i < got.size(); ++i) {
    if (std::bit_cast<uint32_t>(got[i]) != std::bit_cast<uint32_t>(want[i]) && ++wrong <= 5) {
      ADD_FAILURE() << what << "[" << i << "] = " << got[i] << ", expected " << want[i];
    }
  }
  EXPECT_EQ(wrong, 0u) << what << ": elements differing";
}

// a, b with full mantissas (so a fused multiply-add would show), out padded by sentinels.
std::vector<std::vector<float>> multiply_add_buffers() {
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<float> dist(-4.0f, 4.0f);
  std::vector<float> a(kCount), b(kCount);
  for (uint32_t i = 0; i < kCount; ++i) {
    a[i] = dist(rng);
    b[i] = dist(rng);
  }
  return {a, b, std::vector<float>(kCount + kPad, kSentinel)};
}

std::vector<float> multiply_add_expected(const std::vector<float>& a, const std::vector<float>& b) {
  std::vector<float> out(kCount + kPad, kSentinel);
  for (uint32_t i = 0; i < kCount; ++i) {
    volatile float product = a[i] * b[i];  // volatile: no contraction into an fma on the CPU either
    out[i] = product + static_cast<float>(i);
  }
  return out;
}

void check_multiply_add(const std::string& source, ShaderLanguage lang) {
  VulkanCompute& gpu = *shared_device();
  const std::vector<uint32_t> spirv = compile_compute(source, lang);
  const std::vector<std::vector<float>> inputs = multiply_add_buffers();
  const std::vector<float> want = multiply_add_expected(inputs[0], inputs[1]);

  // Exactly kCount invocations (a partial last group), then enough that whole groups run
  // past the count and over the sentinels: only the shader's bound may stop them.
  for (uint32_t invocations : {kCount, kCount + kPad}) {
    SCOPED_TRACE("invocations = " + std::to_string(invocations));
    std::vector<std::vector<float>> buffers = inputs;
    const uint32_t push = kCount;
    gpu.run(spirv, buffers, invocations, &push, sizeof(push));
    expect_bits_equal(buffers[2], want, "out");
    expect_bits_equal(buffers[0], inputs[0], "a (input)");
    expect_bits_equal(buffers[1], inputs[1], "b (input)");
  }
}

TEST(VulkanHarness, Device) {
  SHTOOL_REQUIRE_VULKAN();
  const std::string name = shared_device()->device_name();
  EXPECT_FALSE(name.empty());
  RecordProperty("vulkan_device", name);
  std::cout << "Vulkan device: " << name << "\n";
}

TEST(VulkanHarness, GlslMultiplyAdd) {
  SHTOOL_REQUIRE_VULKAN();
  check_multiply_add(kGlslMultiplyAdd, ShaderLanguage::glsl);
}

TEST(VulkanHarness, HlslMultiplyAdd) {
  SHTOOL_REQUIRE_VULKAN();
  check_multiply_add(kHlslMultiplyAdd, ShaderLanguage::hlsl);
}

TEST(VulkanHarness, BufferKIsBindingK) {
  SHTOOL_REQUIRE_VULKAN();
  constexpr uint32_t n = 1000;
  std::vector<float> a(n), b(n), c(n), d(n), want_c(n), want_d(n);
  for (uint32_t i = 0; i < n; ++i) {
    // Small integers: every result is exact, whatever the evaluation order.
    a[i] = static_cast<float>(i % 17) + 1.0f;
    b[i] = static_cast<float>(i % 5) + 20.0f;
    c[i] = 100.0f * static_cast<float>(i % 3);
    d[i] = 1000.0f + static_cast<float>(i % 7);
    want_c[i] = a[i] - 2.0f * b[i] + c[i];
    want_d[i] = 3.0f * a[i] + b[i] - d[i];
  }
  for (auto [source, lang] :
       {std::pair{kGlslFourBuffers, ShaderLanguage::glsl}, std::pair{kHlslFourBuffers, ShaderLanguage::hlsl}}) {
    SCOPED_TRACE(lang == ShaderLanguage::glsl ? "GLSL" : "HLSL");
    std::vector<std::vector<float>> buffers = {a, b, c, d};
    const uint32_t push = n;
    shared_device()->run(compile_compute(source, lang), buffers, n, &push, sizeof(push));
    expect_bits_equal(buffers[0], a, "a");
    expect_bits_equal(buffers[1], b, "b");
    expect_bits_equal(buffers[2], want_c, "c");
    expect_bits_equal(buffers[3], want_d, "d");
  }
}

// Every run creates and destroys its pipeline objects; many in a row must keep working.
TEST(VulkanHarness, RepeatedRuns) {
  SHTOOL_REQUIRE_VULKAN();
  const std::vector<uint32_t> spirv = compile_compute(kGlslMultiplyAdd, ShaderLanguage::glsl);
  for (uint32_t run = 0; run < 50; ++run) {
    const uint32_t count = 1 + run * 37;
    std::vector<std::vector<float>> buffers = {std::vector<float>(count, 2.0f), std::vector<float>(count, 0.5f),
                                               std::vector<float>(count + 1, kSentinel)};
    shared_device()->run(spirv, buffers, count, &count, sizeof(count));
    for (uint32_t i = 0; i < count; ++i) ASSERT_EQ(buffers[2][i], 1.0f + static_cast<float>(i)) << "run " << run;
    ASSERT_EQ(buffers[2][count], kSentinel) << "run " << run;
  }
}

// An empty vector still gets a (4-byte) buffer, and no invocations is a valid dispatch.
TEST(VulkanHarness, EmptyBuffersAndNoInvocations) {
  SHTOOL_REQUIRE_VULKAN();
  std::vector<std::vector<float>> buffers = {{}, {}, {kSentinel}};
  const uint32_t count = 0;
  shared_device()->run(compile_compute(kGlslMultiplyAdd, ShaderLanguage::glsl), buffers, 0, &count, sizeof(count));
  EXPECT_TRUE(buffers[0].empty());
  EXPECT_EQ(buffers[2][0], kSentinel);
}

TEST(VulkanHarness, SpirvValAcceptsBothModules) {
  EXPECT_NO_THROW(validate_spirv(compile_compute(kGlslMultiplyAdd, ShaderLanguage::glsl)));
  EXPECT_NO_THROW(validate_spirv(compile_compute(kHlslMultiplyAdd, ShaderLanguage::hlsl)));
  EXPECT_NO_THROW(validate_spirv(compile_compute(kGlslFourBuffers, ShaderLanguage::glsl)));
  EXPECT_NO_THROW(validate_spirv(compile_compute(kHlslFourBuffers, ShaderLanguage::hlsl)));
}

TEST(VulkanHarness, SpirvValRejectsABrokenModule) {
  std::vector<uint32_t> spirv = compile_compute(kGlslMultiplyAdd, ShaderLanguage::glsl);
  spirv.resize(spirv.size() / 2);  // cut mid-function
  try {
    validate_spirv(spirv);
    FAIL() << "validate_spirv accepted a truncated module";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("spirv-val"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("error"), std::string::npos) << e.what();
  }
}

// The exception must carry glslang's message and the numbered source, so a failing test
// of a generated shader shows what went wrong.
TEST(VulkanHarness, SyntaxErrorThrowsWithCompilerOutput) {
  const std::string glsl =
      std::string(kGlslMultiplyAdd).replace(std::string(kGlslMultiplyAdd).find("o[i] = r;"), 9, "o[i] = r +;");
  const std::string hlsl = std::string(kHlslMultiplyAdd)
                               .replace(std::string(kHlslMultiplyAdd).find("o[i] = r;"), 9, "o[i] = undeclared_name;");
  for (auto [source, lang] : {std::pair{glsl, ShaderLanguage::glsl}, std::pair{hlsl, ShaderLanguage::hlsl}}) {
    SCOPED_TRACE(lang == ShaderLanguage::glsl ? "GLSL" : "HLSL");
    std::string log;
    try {
      compile_compute(source, lang, &log);
      FAIL() << "compile_compute accepted a broken shader";
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("ERROR:"), std::string::npos) << what;
      EXPECT_NE(what.find(lang == ShaderLanguage::glsl ? "syntax error" : "undeclared_name"), std::string::npos)
          << what;
      EXPECT_NE(what.find(log), std::string::npos) << "the full compiler output is in the message";
      EXPECT_NE(what.find("  11 |   o[i] = "), std::string::npos) << "numbered source in the message:\n" << what;
    }
  }
}

// A module that does not match run()'s arguments is refused with a reason instead of
// running into undefined behaviour.
TEST(VulkanHarness, MismatchedInterfaceIsRefused) {
  SHTOOL_REQUIRE_VULKAN();
  auto refusal = [](const std::string& source, ShaderLanguage lang, size_t buffer_count, uint32_t push_size) {
    std::vector<std::vector<float>> buffers(buffer_count, std::vector<float>(64));
    const uint32_t push[64] = {64};
    try {
      shared_device()->run(compile_compute(source, lang), buffers, 64, push_size ? push : nullptr, push_size);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  EXPECT_NE(refusal(kGlslMultiplyAdd, ShaderLanguage::glsl, 2, 4).find("beyond the 2 buffers"), std::string::npos);
  EXPECT_NE(refusal(kGlslMultiplyAdd, ShaderLanguage::glsl, 3, 0).find("push constants"), std::string::npos);
  EXPECT_NE(refusal(kGlslMultiplyAdd, ShaderLanguage::glsl, 3, 132).find("push_size 132"), std::string::npos);

  std::string local32 = kGlslMultiplyAdd;
  local32.replace(local32.find("local_size_x = 64"), 17, "local_size_x = 32");
  EXPECT_NE(refusal(local32, ShaderLanguage::glsl, 3, 4).find("local size is (32, 1, 1)"), std::string::npos);

  // HLSL's implicit $Global uniform buffer, and a buffer left without a register.
  std::string global = kHlslMultiplyAdd;
  global.replace(global.find("[[vk::push_constant]] ConstantBuffer<Push> pc;"), 46, "[[vk::push_constant]] Push pc;");
  EXPECT_NE(refusal(global, ShaderLanguage::hlsl, 3, 4).find("$Global"), std::string::npos);
  std::string unregistered = kHlslMultiplyAdd;
  unregistered.replace(unregistered.find(" : register(u1)"), 15, "");
  EXPECT_NE(refusal(unregistered, ShaderLanguage::hlsl, 3, 4).find("two buffers at binding 0"), std::string::npos);
}

// ---------------------------------------------------------------------------------------
// Cube textures

using Dir = std::array<float, 3>;
using Texel = std::array<float, 4>;

// A shader after two storage buffers (directions in, texels out) taking `cubes` cube
// textures in the language's usual form: invocation i samples cube k at direction
// dirs[3 (C i + k) ..] and writes o[C i + k], C = cubes. `separate_glsl` writes the GLSL
// with separate textureCube and sampler variables, the form HLSL compiles to.
std::string cube_shader(ShaderLanguage lang, int cubes, bool separate_glsl = false) {
  const std::string c = std::to_string(cubes);
  std::string decls, body;
  for (int k = 0; k < cubes; ++k) {
    const std::string name = "bands" + std::to_string(k), binding = std::to_string(2 + k);
    const std::string at = c + " * i + " + std::to_string(k);
    if (lang == ShaderLanguage::hlsl) {
      decls += "[[vk::binding(" + binding + ", 0)]] TextureCube<float4> " + name + ";\n";
      body += "  o[" + at + "] = " + name + ".SampleLevel(bands_sampler, dir_of(" + at + "), 0);\n";
    } else if (separate_glsl) {
      decls += "layout(set = 0, binding = " + binding + ") uniform textureCube " + name + ";\n";
      body += "  o[" + at + "] = textureLod(samplerCube(" + name + ", bands_sampler), dir_of(" + at + "), 0.0);\n";
    } else {
      decls += "layout(set = 0, binding = " + binding + ") uniform samplerCube " + name + ";\n";
      body += "  o[" + at + "] = textureLod(" + name + ", dir_of(" + at + "), 0.0);\n";
    }
  }
  const std::string sampler_binding = std::to_string(2 + cubes);
  if (lang == ShaderLanguage::hlsl) {
    decls += "[[vk::binding(" + sampler_binding + ", 0)]] SamplerState bands_sampler;\n";
    return "struct Push { uint count; };\n"
           "[[vk::push_constant]] ConstantBuffer<Push> pc;\n"
           "StructuredBuffer<float> dirs : register(t0);\n"
           "RWStructuredBuffer<float4> o : register(u1);\n" +
           decls +
           "float3 dir_of(uint k) { return float3(dirs[3 * k], dirs[3 * k + 1], dirs[3 * k + 2]); }\n"
           "[numthreads(64, 1, 1)]\n"
           "void main(uint3 id : SV_DispatchThreadID) {\n"
           "  uint i = id.x;\n"
           "  if (i >= pc.count) return;\n" +
           body + "}\n";
  }
  if (separate_glsl) decls += "layout(set = 0, binding = " + sampler_binding + ") uniform sampler bands_sampler;\n";
  return "#version 450\n"
         "layout(local_size_x = 64) in;\n"
         "layout(push_constant) uniform Push { uint count; } pc;\n"
         "layout(std430, set = 0, binding = 0) readonly buffer Dirs { float dirs[]; };\n"
         "layout(std430, set = 0, binding = 1) writeonly buffer Out { vec4 o[]; };\n" +
         decls +
         "vec3 dir_of(uint k) { return vec3(dirs[3u * k], dirs[3u * k + 1u], dirs[3u * k + 2u]); }\n"
         "void main() {\n"
         "  uint i = gl_GlobalInvocationID.x;\n"
         "  if (i >= pc.count) return;\n" +
         body + "}\n";
}

// The direction whose major axis selects `face` (Vulkan layer order +X, -X, +Y, -Y, +Z,
// -Z) with |ma| = 1 and face coordinates (s, t), by the cube face selection table
// inverted: +X: sc = -z, tc = -y; -X: sc = +z, tc = -y; +Y: sc = +x, tc = +z;
// -Y: sc = +x, tc = -z; +Z: sc = +x, tc = -y; -Z: sc = -x, tc = -y; s = (sc + 1) / 2,
// t = (tc + 1) / 2. Written out from the table, not from the harness, so a harness that
// uploaded faces in another order or transposed would fail against it. Exact in float
// when s and t are multiples of a power of two (texel centres of power-of-two sizes).
Dir face_direction(int face, double s, double t) {
  const double sc = 2.0 * s - 1.0, tc = 2.0 * t - 1.0;
  auto f = [](double v) { return static_cast<float>(v); };
  switch (face) {
    case 0:
      return {1.0f, f(-tc), f(-sc)};
    case 1:
      return {-1.0f, f(-tc), f(sc)};
    case 2:
      return {f(sc), 1.0f, f(tc)};
    case 3:
      return {f(sc), -1.0f, f(-tc)};
    case 4:
      return {f(sc), f(-tc), 1.0f};
    default:
      return {f(-sc), f(-tc), -1.0f};
  }
}

// The centre of texel (column i, row j) of a size x size face.
Dir texel_centre(int face, int i, int j, int size) { return face_direction(face, (i + 0.5) / size, (j + 0.5) / size); }

// A cube whose texel (column i, row j) of face f holds value(f, i, j).
template <typename F>
CubeTexture make_cube(int size, F value) {
  CubeTexture cube;
  cube.size = size;
  cube.texels.resize(std::size_t(6) * size * size * 4);
  for (int f = 0; f < 6; ++f)
    for (int j = 0; j < size; ++j)
      for (int i = 0; i < size; ++i) {
        const Texel v = value(f, i, j);
        for (int c = 0; c < 4; ++c) cube.texels[((std::size_t(f) * size + j) * size + i) * 4 + c] = v[c];
      }
  return cube;
}

// Texel (f, i, j) of face f, column i, row j holds (f, i, j, 1) (+ offset in x, y, z).
CubeTexture coordinate_cube(int size, float offset = 0.0f) {
  return make_cube(size, [&](int f, int i, int j) {
    return Texel{float(f) + offset, float(i) + offset, float(j) + offset, 1.0f};
  });
}

// Runs cube_shader(lang, cubes.size()) on the GPU: result[k][n] is cube k sampled at dirs[k][n].
std::vector<std::vector<Texel>> sample_cubes(const std::string& source, ShaderLanguage lang,
                                             const std::vector<CubeTexture>& cubes,
                                             const std::vector<std::vector<Dir>>& dirs) {
  const size_t c = cubes.size(), n = dirs.at(0).size();
  std::vector<float> in(3 * c * n);
  for (size_t k = 0; k < c; ++k) {
    EXPECT_EQ(dirs[k].size(), n);
    for (size_t p = 0; p < n; ++p)
      for (int d = 0; d < 3; ++d) in[3 * (c * p + k) + d] = dirs[k][p][d];
  }
  std::vector<std::vector<float>> buffers = {in, std::vector<float>(4 * c * n, kSentinel)};
  const auto count = static_cast<uint32_t>(n);
  const std::vector<uint32_t> spirv = compile_compute(source, lang);
  validate_spirv(spirv);
  shared_device()->run(spirv, buffers, count, &count, sizeof(count), cubes);
  std::vector<std::vector<Texel>> out(c, std::vector<Texel>(n));
  for (size_t k = 0; k < c; ++k)
    for (size_t p = 0; p < n; ++p)
      for (int d = 0; d < 4; ++d) out[k][p][d] = buffers[1][4 * (c * p + k) + d];
  return out;
}

std::string texel_string(const Texel& t) {
  return "(" + std::to_string(t[0]) + ", " + std::to_string(t[1]) + ", " + std::to_string(t[2]) + ", " +
         std::to_string(t[3]) + ")";
}

struct LanguageCase {
  const char* name;
  ShaderLanguage lang;
  bool separate_glsl;
};
const LanguageCase kCubeLanguages[] = {
    {"GLSL samplerCube", ShaderLanguage::glsl, false},
    {"HLSL TextureCube + SamplerState", ShaderLanguage::hlsl, false},
    {"GLSL textureCube + sampler", ShaderLanguage::glsl, true},
};

// Every texel of every face sampled at its centre returns exactly (face, column, row, 1):
// linear filtering at a texel centre weighs that texel alone. Sizes 4 (coordinates exact
// in float) and 3 (not a power of two: a row stride or face offset of another size would
// show; centres not exact in float, so within 1e-5).
TEST(VulkanHarness, CubeFaceOrderAndOrientation) {
  SHTOOL_REQUIRE_VULKAN();
  for (const LanguageCase& lc : kCubeLanguages) {
    for (int size : {4, 3}) {
      SCOPED_TRACE(std::string(lc.name) + ", size " + std::to_string(size));
      std::vector<Dir> dirs;
      std::vector<Texel> want;
      for (int f = 0; f < 6; ++f)
        for (int j = 0; j < size; ++j)
          for (int i = 0; i < size; ++i) {
            dirs.push_back(texel_centre(f, i, j, size));
            want.push_back({float(f), float(i), float(j), 1.0f});
          }
      const auto got =
          sample_cubes(cube_shader(lc.lang, 1, lc.separate_glsl), lc.lang, {coordinate_cube(size)}, {dirs})[0];
      const float tolerance = size == 4 ? 0.0f : 1e-5f;
      int wrong = 0;
      for (size_t p = 0; p < dirs.size(); ++p) {
        bool ok = true;
        for (int c = 0; c < 4; ++c) ok = ok && std::abs(got[p][c] - want[p][c]) <= tolerance;
        if (!ok && ++wrong <= 8) {
          ADD_FAILURE() << "direction (" << dirs[p][0] << ", " << dirs[p][1] << ", " << dirs[p][2]
                        << "): got (face, column, row, 1) = " << texel_string(got[p]) << ", expected "
                        << texel_string(want[p]);
        }
      }
      EXPECT_EQ(wrong, 0);
    }
  }
}

// Two cubes of different sizes and contents at once, after two storage buffers: each
// binding gets its own cube, with its own extent.
TEST(VulkanHarness, TwoCubesAndTwoBuffers) {
  SHTOOL_REQUIRE_VULKAN();
  const std::vector<CubeTexture> cubes = {coordinate_cube(4), coordinate_cube(2, 100.0f)};
  const int sizes[] = {4, 2};
  for (const LanguageCase& lc : kCubeLanguages) {
    SCOPED_TRACE(lc.name);
    std::vector<std::vector<Dir>> dirs(2);
    std::vector<std::vector<Texel>> want(2);
    // The same number of samples from each: every texel of the 2 x 2 cube, and as many
    // texels of the 4 x 4 one (a diagonal-ish walk over its faces).
    for (int f = 0; f < 6; ++f)
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          dirs[1].push_back(texel_centre(f, i, j, sizes[1]));
          want[1].push_back({100.0f + f, 100.0f + i, 100.0f + j, 1.0f});
          const int i4 = (i * 2 + j + f) % 4, j4 = (j * 2 + i + 3 * f) % 4;
          dirs[0].push_back(texel_centre(f, i4, j4, sizes[0]));
          want[0].push_back({float(f), float(i4), float(j4), 1.0f});
        }
    const auto got = sample_cubes(cube_shader(lc.lang, 2, lc.separate_glsl), lc.lang, cubes, dirs);
    for (int k = 0; k < 2; ++k)
      for (size_t p = 0; p < dirs[k].size(); ++p)
        EXPECT_EQ(got[k][p], want[k][p]) << "cube " << k << " at (" << dirs[k][p][0] << ", " << dirs[k][p][1] << ", "
                                         << dirs[k][p][2] << "): got " << texel_string(got[k][p]) << ", expected "
                                         << texel_string(want[k][p]);
  }
}

// Linear filtering: half-way between two texel centres of a face returns their average,
// at the corner of four texels the average of the four; and across a face edge (seamless
// cube filtering) the average of the two texels that meet there.
TEST(VulkanHarness, CubeLinearFiltering) {
  SHTOOL_REQUIRE_VULKAN();
  constexpr int size = 4;
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> dist(-1.0f, 1.0f);
  std::vector<Texel> values(6 * size * size);
  for (Texel& t : values)
    for (float& v : t) v = dist(rng);
  auto texel = [&](int f, int i, int j) { return values[(f * size + j) * size + i]; };
  const CubeTexture cube = make_cube(size, texel);

  std::vector<Dir> dirs;
  std::vector<std::array<double, 4>> want;
  std::vector<std::string> what;
  auto average = [&](std::initializer_list<Texel> ts, Dir dir, std::string label) {
    std::array<double, 4> a{};
    for (const Texel& t : ts)
      for (int c = 0; c < 4; ++c) a[c] += double(t[c]) / double(ts.size());
    dirs.push_back(dir);
    want.push_back(a);
    what.push_back(std::move(label));
  };
  for (int f = 0; f < 6; ++f) {
    const std::string face = "face " + std::to_string(f);
    for (int a = 0; a + 1 < size; ++a) {
      for (int b = 0; b < size; ++b) {
        // Between columns a and a + 1 of row b, and between rows a and a + 1 of column b.
        average({texel(f, a, b), texel(f, a + 1, b)}, face_direction(f, double(a + 1) / size, (b + 0.5) / size),
                face + " columns " + std::to_string(a) + ".." + std::to_string(a + 1) + " of row " + std::to_string(b));
        average({texel(f, b, a), texel(f, b, a + 1)}, face_direction(f, (b + 0.5) / size, double(a + 1) / size),
                face + " rows " + std::to_string(a) + ".." + std::to_string(a + 1) + " of column " + std::to_string(b));
      }
      average({texel(f, a, a), texel(f, a + 1, a), texel(f, a, a + 1), texel(f, a + 1, a + 1)},
              face_direction(f, double(a + 1) / size, double(a + 1) / size),
              face + " corner of texels " + std::to_string(a) + ".." + std::to_string(a + 1));
    }
  }
  // The edge where +Z (s = 1, x = +1) meets +X (s = 0, z = +1), at the centre of row j
  // of both (tc = -y on both faces): |x| = |z|, and either face gives the same pair.
  for (int j = 0; j < size; ++j) {
    const float y = -static_cast<float>(2.0 * (j + 0.5) / size - 1.0);
    average({texel(4, size - 1, j), texel(0, 0, j)}, Dir{1.0f, y, 1.0f}, "edge +Z/+X at row " + std::to_string(j));
  }

  for (const LanguageCase& lc : kCubeLanguages) {
    SCOPED_TRACE(lc.name);
    const auto got = sample_cubes(cube_shader(lc.lang, 1, lc.separate_glsl), lc.lang, {cube}, {dirs})[0];
    for (size_t p = 0; p < dirs.size(); ++p)
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(got[p][c], want[p][c], 1e-6) << what[p] << ", channel " << c;
  }
}

// A cube shader run with the wrong textures, bindings or sampler is refused with a reason.
TEST(VulkanHarness, MismatchedTexturesAreRefused) {
  SHTOOL_REQUIRE_VULKAN();
  auto refusal = [](const std::string& source, ShaderLanguage lang, size_t buffer_count,
                    const std::vector<CubeTexture>& cubes) {
    std::vector<std::vector<float>> buffers(buffer_count, std::vector<float>(256));
    const uint32_t count = 1;
    try {
      shared_device()->run(compile_compute(source, lang), buffers, 1, &count, sizeof(count), cubes);
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string("(accepted)");
  };
  auto expect_refused = [&](const std::string& source, ShaderLanguage lang, size_t buffer_count,
                            const std::vector<CubeTexture>& cubes, const std::string& reason) {
    const std::string what = refusal(source, lang, buffer_count, cubes);
    EXPECT_NE(what.find(reason), std::string::npos) << "expected \"" << reason << "\" in: " << what;
  };
  const std::string glsl1 = cube_shader(ShaderLanguage::glsl, 1), glsl2 = cube_shader(ShaderLanguage::glsl, 2);
  const std::string hlsl1 = cube_shader(ShaderLanguage::hlsl, 1), hlsl2 = cube_shader(ShaderLanguage::hlsl, 2);
  const CubeTexture cube = coordinate_cube(2);

  // Sanity: the shaders below are refused for what is changed, not for anything else.
  EXPECT_EQ(refusal(glsl1, ShaderLanguage::glsl, 2, {cube}), "(accepted)");
  EXPECT_EQ(refusal(hlsl2, ShaderLanguage::hlsl, 2, {cube, cube}), "(accepted)");

  // A texture the arguments do not have: no cubes (either overload), one cube too few.
  for (const std::string* source : {&glsl1, &hlsl1}) {
    const ShaderLanguage lang = source == &glsl1 ? ShaderLanguage::glsl : ShaderLanguage::hlsl;
    expect_refused(*source, lang, 2, {}, "(binding 2) is a cube texture but run() was given no cube textures");
    std::vector<std::vector<float>> buffers(2, std::vector<float>(16));
    const uint32_t count = 1;
    try {
      shared_device()->run(compile_compute(*source, lang), buffers, 1, &count, sizeof(count));
      ADD_FAILURE() << "the overload without cubes accepted a cube shader";
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find("run() was given no cube textures"), std::string::npos) << e.what();
    }
  }
  expect_refused(glsl2, ShaderLanguage::glsl, 2, {cube},
                 "(binding 3) is a cube texture beyond the 1 cube texture (binding 2) given to run()");
  expect_refused(hlsl2, ShaderLanguage::hlsl, 2, {cube}, "beyond the 1 cube texture (binding 2) given to run()");
  // Cubes the shader does not declare.
  expect_refused(glsl1, ShaderLanguage::glsl, 2, {cube, cube},
                 "run() was given 2 cube textures (bindings 2..3) but the module declares 1: no cube texture at "
                 "binding 3");
  expect_refused(cube_shader(ShaderLanguage::glsl, 0), ShaderLanguage::glsl, 2, {cube},
                 "but the module declares none: no cube texture at binding 2");
  // Wrong bindings: one buffer more than the shader expects moves the cubes to binding 3;
  // a cube declared at the buffers' binding.
  expect_refused(glsl1, ShaderLanguage::glsl, 3, {cube}, "is a cube texture at a storage buffer's binding");
  std::string at_buffer = glsl1;
  at_buffer.replace(at_buffer.find("binding = 2) uniform samplerCube"), 11, "binding = 1");
  expect_refused(at_buffer, ShaderLanguage::glsl, 2, {cube}, "(binding 1) is a cube texture at a storage buffer");

  // The HLSL form without its sampler: a texture only queried needs none, and glslang
  // drops a declared but unused one too.
  const std::string query_only =
      "[[vk::push_constant]] cbuffer Push { uint count; };\n"
      "RWStructuredBuffer<float> o : register(u0);\n"
      "[[vk::binding(1, 0)]] TextureCube<float4> bands0;\n"
      "[[vk::binding(2, 0)]] SamplerState bands_sampler;\n"
      "[numthreads(64, 1, 1)]\n"
      "void main(uint3 id : SV_DispatchThreadID) {\n"
      "  uint w, h;\n"
      "  bands0.GetDimensions(w, h);\n"
      "  if (id.x < count) o[id.x] = float(w);\n"
      "}\n";
  expect_refused(query_only, ShaderLanguage::hlsl, 1, {cube},
                 "are separate images (HLSL TextureCube) but it has no sampler: declare one SamplerState at binding 2");
  // The sampler at the wrong binding, and the sampler where run() binds a cube.
  std::string sampler_at_5 = hlsl1;
  sampler_at_5.replace(sampler_at_5.find("[[vk::binding(3, 0)]] SamplerState"), 21, "[[vk::binding(5, 0)]]");
  expect_refused(sampler_at_5, ShaderLanguage::hlsl, 2, {cube},
                 "(binding 5) is the sampler, but with 2 buffers and 1 cube run() binds it at binding 3");
  expect_refused(hlsl1, ShaderLanguage::hlsl, 2, {cube, cube}, "no cube texture at binding 3; the sampler (variable %");

  // Textures run() does not provide: a 2D texture, a cube array, integer texels, and the
  // two forms mixed.
  std::string two_d = glsl1;
  two_d.replace(two_d.find("samplerCube"), 11, "sampler2D");
  two_d.replace(two_d.find("dir_of(1 * i + 0)"), 17, "dir_of(1 * i + 0).xy");
  expect_refused(two_d, ShaderLanguage::glsl, 2, {cube}, "is a 2D combined image sampler; run() binds cube textures");
  std::string cube_array = hlsl1;
  cube_array.replace(cube_array.find("TextureCube<float4>"), 19, "TextureCubeArray<float4>");
  cube_array.replace(cube_array.find("dir_of(1 * i + 0)"), 17, "float4(dir_of(1 * i + 0), 0)");
  expect_refused(cube_array, ShaderLanguage::hlsl, 2, {cube}, "is a cube array image");
  std::string integer = glsl1;
  integer.replace(integer.find("samplerCube"), 11, "isamplerCube");
  integer.replace(integer.find("= textureLod"), 12, "= vec4(textureLod");
  integer.replace(integer.find(", 0.0);"), 7, ", 0.0));");
  expect_refused(integer, ShaderLanguage::glsl, 2, {cube}, "of non-float texels");
  std::string mixed = cube_shader(ShaderLanguage::glsl, 2, true);
  mixed.replace(mixed.find("uniform textureCube bands1"), 26, "uniform samplerCube bands1");
  mixed.replace(mixed.find("samplerCube(bands1, bands_sampler)"), 34, "bands1");
  expect_refused(mixed, ShaderLanguage::glsl, 2, {cube, cube}, "mixes combined image samplers");

  // Bad cube arguments.
  CubeTexture empty;
  expect_refused(glsl1, ShaderLanguage::glsl, 2, {empty}, "cube 0 has size 0; at least 1");
  CubeTexture short_cube = coordinate_cube(2);
  short_cube.texels.pop_back();
  expect_refused(glsl2, ShaderLanguage::glsl, 2, {cube, short_cube},
                 "cube 1 of size 2 has 95 floats; 6 faces x 2 x 2 texels x 4 channels = 96");
}

}  // namespace
}  // namespace shtool::gpu
