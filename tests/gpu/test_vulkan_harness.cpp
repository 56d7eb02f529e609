// Smoke tests of the Vulkan compute harness itself: GLSL and HLSL shaders run on the
// device and checked bit for bit against the CPU, buffer order, bounds of the dispatch,
// the validator, and the errors a wrong shader or wrong arguments must produce.
#include <gtest/gtest.h>

#include <bit>
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

// `precise` keeps the device from fusing a * b + i into one rounding, which the CPU
// reference (below) does not do either.
const char* const kGlslMultiplyAdd = R"(#version 450
layout(local_size_x = 64) in;
layout(push_constant) uniform Push { uint count; } pc;
layout(std430, set = 0, binding = 0) readonly buffer A { float a[]; };
layout(std430, set = 0, binding = 1) readonly buffer B { float b[]; };
layout(std430, set = 0, binding = 2) writeonly buffer Out { float o[]; };
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= pc.count) return;
  precise float r = a[i] * b[i] + float(i);
  o[i] = r;
}
)";

const char* const kHlslMultiplyAdd = R"(struct Push { uint count; };
[[vk::push_constant]] ConstantBuffer<Push> pc;
RWStructuredBuffer<float> a : register(u0);
RWStructuredBuffer<float> b : register(u1);
RWStructuredBuffer<float> o : register(u2);
[numthreads(64, 1, 1)]
void main(uint3 id : SV_DispatchThreadID) {
  uint i = id.x;
  if (i >= pc.count) return;
  precise float r = a[i] * b[i] + float(i);
  o[i] = r;
}
)";

// Asymmetric in every buffer, so a harness that bound buffers in another order (or
// read-only HLSL t registers elsewhere than u registers) gives different numbers.
const char* const kGlslFourBuffers = R"(#version 450
layout(local_size_x = 64) in;
layout(push_constant) uniform Push { uint count; } pc;
layout(std430, set = 0, binding = 0) readonly buffer A { float a[]; };
layout(std430, set = 0, binding = 1) readonly buffer B { float b[]; };
layout(std430, set = 0, binding = 2) buffer C { float c[]; };
layout(std430, set = 0, binding = 3) buffer D { float d[]; };
void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= pc.count) return;
  c[i] = a[i] - 2.0 * b[i] + c[i];
  d[i] = 3.0 * a[i] + b[i] - d[i];
}
)";

const char* const kHlslFourBuffers = R"([[vk::push_constant]] cbuffer Push { uint count; };
StructuredBuffer<float> a : register(t0);
StructuredBuffer<float> b : register(t1);
RWStructuredBuffer<float> c : register(u2);
RWStructuredBuffer<float> d : register(u3);
[numthreads(64, 1, 1)]
void main(uint3 id : SV_DispatchThreadID) {
  uint i = id.x;
  if (i >= count) return;
  c[i] = a[i] - 2.0 * b[i] + c[i];
  d[i] = 3.0 * a[i] + b[i] - d[i];
}
)";

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

void check_multiply_add(const char* source, ShaderLanguage lang) {
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

}  // namespace
}  // namespace shtool::gpu
