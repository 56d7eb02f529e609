// The compute shaders that wrap a generated shader include for the Vulkan harness: one
// invocation's float inputs and outputs and the call of the generated function, the
// band textures of a coefficient vector as docs/shaders.md defines them, and the request
// of each operation. Shared by tests/gpu/test_shaders.cpp and bench/bench_shaders.cpp.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "shaders/shader_source.h"
#include "shtool/sh.h"
#include "shtool/zhf_rotation.h"
#include "vulkan_compute.h"

namespace shtool::gpu {

// One invocation's inputs and outputs, as float arrays of fixed strides, and the
// statements of main() that call the generated function on them.
struct Wrapper {
  int in_stride = 0, out_stride = 0;
  std::string body;  // uses ib, ob (first input and output float of this invocation)
};

inline std::string vec3_of(shtool::ShaderLanguage lang, const std::string& at) {
  return std::string(lang == shtool::ShaderLanguage::glsl ? "vec3" : "float3") + "(inp[" + at + "], inp[" + at +
         " + 1], inp[" + at + " + 2])";
}

inline std::string load_array(const std::string& type, const std::string& name, int size, const std::string& from) {
  return "  " + type + " " + name + "[" + std::to_string(size) + "];\n  for (int k = 0; k < " + std::to_string(size) +
         "; ++k) " + name + "[k] = inp[" + from + " + k];\n";
}

// The rotation matrix of an invocation, stored row-major at inp[ib..ib+8], as the
// language's 3x3 constructor: GLSL's takes columns, HLSL's rows.
inline std::string matrix_argument(shtool::ShaderLanguage lang) {
  const bool glsl = lang == shtool::ShaderLanguage::glsl;
  std::string m = glsl ? "mat3(" : "float3x3(";
  for (int k = 0; k < 9; ++k) {
    const int i = glsl ? k % 3 : k / 3, j = glsl ? k / 3 : k % 3;
    m += (k ? ", " : "") + std::string("inp[ib + ") + std::to_string(3 * i + j) + "]";
  }
  return m + ")";
}

inline std::string texture_arguments(shtool::ShaderLanguage lang, int count);
inline std::string texture_declarations(shtool::ShaderLanguage lang, int count);

inline Wrapper wrapper(shtool::ShaderLanguage lang, shtool::ShaderOperation op, int n, int lobes) {
  const int nn = n * n;
  const bool glsl = lang == shtool::ShaderLanguage::glsl;
  const std::string v3 = glsl ? "vec3" : "float3";
  Wrapper w;
  switch (op) {
    case shtool::ShaderOperation::sh_eval:
      w.in_stride = 3;
      w.out_stride = nn;
      w.body = "  float y[SHTOOL_ORDER * SHTOOL_ORDER];\n  shtool_sh_eval(" + vec3_of(lang, "ib") +
               ", y);\n  for (int k = 0; k < " + std::to_string(nn) + "; ++k) outp[ob + k] = y[k];\n";
      break;
    case shtool::ShaderOperation::sh_irradiance:
      // n, L (scalar), then L as RGB (interleaved)
      w.in_stride = 3 + nn + 3 * nn;
      w.out_stride = 4;
      w.body = load_array("float", "L", nn, "ib + 3") + "  " + v3 + " Lc[" + std::to_string(nn) +
               "];\n  for (int k = 0; k < " + std::to_string(nn) + "; ++k) Lc[k] = " +
               vec3_of(lang, "ib + 3 + " + std::to_string(nn) + " + 3 * k") +
               ";\n  outp[ob] = shtool_sh_irradiance(" + vec3_of(lang, "ib") + ", L);\n  " + v3 +
               " e = shtool_sh_irradiance_rgb(" + vec3_of(lang, "ib") +
               ", Lc);\n  outp[ob + 1] = e.x;\n  outp[ob + 2] = e.y;\n  outp[ob + 3] = e.z;\n";
      break;
    case shtool::ShaderOperation::zxzxz_rotate:
    case shtool::ShaderOperation::zhf_rotate:
    case shtool::ShaderOperation::zhf_tailored_rotate: {
      // R row-major, then f
      w.in_stride = 9 + nn;
      w.out_stride = nn;
      const std::string m = matrix_argument(lang);
      w.body = load_array("float", "f", nn, "ib + 9") + "  float g[" + std::to_string(nn) + "];\n  " +
               (op == shtool::ShaderOperation::zhf_rotate            ? "shtool_zhf_rotate("
                : op == shtool::ShaderOperation::zhf_tailored_rotate ? "shtool_zhf_tailored_rotate_arithmetic("
                                                             : "shtool_rotate(") +
               m + ", f, g);\n  for (int k = 0; k < " + std::to_string(nn) + "; ++k) outp[ob + k] = g[k];\n";
      break;
    }
    case shtool::ShaderOperation::triple_product:
      w.in_stride = 2 * nn;
      w.out_stride = nn;
      w.body = load_array("float", "a", nn, "ib") + load_array("float", "b", nn, "ib + " + std::to_string(nn)) +
               "  float c[" + std::to_string(nn) + "];\n  shtool_triple_product(a, b, c);\n  for (int k = 0; k < " +
               std::to_string(nn) + "; ++k) outp[ob + k] = c[k];\n";
      break;
    case shtool::ShaderOperation::zh_shade:
      // axes (3 per lobe), g (N per lobe), e
      w.in_stride = 3 * lobes + lobes * n + nn;
      w.out_stride = 1;
      w.body = "  " + v3 + " axes[" + std::to_string(lobes) + "];\n  for (int k = 0; k < " + std::to_string(lobes) +
               "; ++k) axes[k] = " + vec3_of(lang, "ib + 3 * k") + ";\n" +
               load_array("float", "g", lobes * n, "ib + " + std::to_string(3 * lobes)) +
               load_array("float", "e", nn, "ib + " + std::to_string(3 * lobes + lobes * n)) +
               "  outp[ob] = shtool_zh_shade(axes, g, e);\n";
      break;
    case shtool::ShaderOperation::l1_irradiance:
    case shtool::ShaderOperation::zh3_irradiance: {
      // n, L[4] as RGB, then (zh3) the zonal RGB coefficients. Outputs: l1 E (RGB); zh3 E
      // (RGB) of stored zonal coefficients on the luminance axis, on per-channel axes, then
      // hallucinated on the luminance axis and on per-channel axes.
      const bool zh3 = op == shtool::ShaderOperation::zh3_irradiance;
      w.in_stride = 3 + 12 + (zh3 ? 3 : 0);
      w.out_stride = zh3 ? 12 : 3;
      std::string b = "  " + v3 + " n = " + vec3_of(lang, "ib") + ";\n  " + v3 + " L[4];\n" +
                      "  for (int k = 0; k < 4; ++k) L[k] = " + vec3_of(lang, "ib + 3 + 3 * k") + ";\n";
      auto put = [&](int at, const std::string& call) {
        b += "  { " + v3 + " e = " + call + ";\n    outp[ob + " + std::to_string(at) + "] = e.x; outp[ob + " +
             std::to_string(at + 1) + "] = e.y; outp[ob + " + std::to_string(at + 2) + "] = e.z; }\n";
      };
      if (!zh3) put(0, "shtool_l1_irradiance(n, L)");
      else {
        b += "  " + v3 + " zonal = " + vec3_of(lang, "ib + 15") + ";\n";
        put(0, "shtool_zh3_irradiance(n, L, zonal)");
        put(3, "shtool_zh3_irradiance_per_channel(n, L, zonal)");
        put(6, "shtool_zh3_hallucinate_irradiance(n, L)");
        put(9, "shtool_zh3_hallucinate_irradiance_per_channel(n, L)");
      }
      w.body = b;
      break;
    }
  }
  return w;
}

// The wrappers' push constants: the number of invocations, and the number of input and
// output slots they cycle through (invocation id uses slot id % period: a benchmark runs
// many invocations on a small buffer; the tests give period = count).
struct WrapperPush {
  uint32_t count;
  uint32_t period;
};

inline std::string compute_shader(shtool::ShaderLanguage lang, const std::string& generated, const Wrapper& w) {
  const std::string index = "  uint slot = id % params.period;\n  uint ib = slot * " + std::to_string(w.in_stride) +
                            "u;\n  uint ob = slot * " + std::to_string(w.out_stride) + "u;\n";
  if (lang == shtool::ShaderLanguage::glsl)
    return "#version 450\nlayout(local_size_x = 64) in;\n"
           "layout(std430, set = 0, binding = 0) readonly buffer Inputs { float inp[]; };\n"
           "layout(std430, set = 0, binding = 1) writeonly buffer Outputs { float outp[]; };\n"
           "layout(push_constant) uniform Params { uint count; uint period; } params;\n\n" +
           generated +
           "\nvoid main() {\n  uint id = gl_GlobalInvocationID.x;\n  if (id >= params.count) return;\n" + index +
           w.body + "}\n";
  return "[[vk::binding(0, 0)]] RWStructuredBuffer<float> inp : register(u0);\n"
         "[[vk::binding(1, 0)]] RWStructuredBuffer<float> outp : register(u1);\n"
         "struct Params { uint count; uint period; };\n[[vk::push_constant]] ConstantBuffer<Params> params;\n\n" +
         generated + "\n[numthreads(64, 1, 1)]\nvoid main(uint3 tid : SV_DispatchThreadID) {\n  uint id = tid.x;\n"
         "  if (id >= params.count) return;\n" + index + w.body + "}\n";
}

// The texture forms: zh-shade's shtool_zh_shade_table (inputs: the lobe axes, then g) and
// zhf-tailored-rotate's shtool_zhf_tailored_rotate (input: R), reading the band textures.
inline Wrapper textured_wrapper(shtool::ShaderLanguage lang, shtool::ShaderOperation op, int n, int lobes) {
  const int textures = (n + 3) / 4, nn = n * n;
  const std::string v3 = lang == shtool::ShaderLanguage::glsl ? "vec3" : "float3";
  Wrapper w;
  if (op == shtool::ShaderOperation::zh_shade) {
    w.in_stride = 3 * lobes + lobes * n;
    w.out_stride = 1;
    w.body = "  " + v3 + " axes[" + std::to_string(lobes) + "];\n  for (int k = 0; k < " + std::to_string(lobes) +
             "; ++k) axes[k] = " + vec3_of(lang, "ib + 3 * k") + ";\n" +
             load_array("float", "g", lobes * n, "ib + " + std::to_string(3 * lobes)) +
             "  outp[ob] = shtool_zh_shade_table(axes, g" + texture_arguments(lang, textures) + ");\n";
  } else {
    w.in_stride = 9;
    w.out_stride = nn;
    w.body = "  float g[" + std::to_string(nn) + "];\n  shtool_zhf_tailored_rotate(" + matrix_argument(lang) +
             texture_arguments(lang, textures) + ", g);\n  for (int k = 0; k < " + std::to_string(nn) +
             "; ++k) outp[ob + k] = g[k];\n";
  }
  return w;
}

// The compute shader of a generated include (with `textures` band textures declared after
// the two buffers), compiled to SPIR-V and accepted by spirv-val; throws otherwise.
inline std::vector<uint32_t> compiled_wrapper(shtool::ShaderLanguage lang, const std::string& generated,
                                              const Wrapper& w, int textures = 0) {
  const std::vector<uint32_t> spirv =
      compile_compute(compute_shader(lang, texture_declarations(lang, textures) + generated, w),
                      lang == shtool::ShaderLanguage::glsl ? ShaderLanguage::glsl : ShaderLanguage::hlsl);
  validate_spirv(spirv);
  return spirv;
}

// The request of one case; zhf-rotate takes the shipped shared-lobe table of its order.
inline shtool::ShaderRequest request_for(shtool::ShaderLanguage language, shtool::ShaderOperation op, int order, int lobes,
                                  shtool::ShaderPrecision precision = shtool::ShaderPrecision::float32) {
  shtool::ShaderRequest request{
      .language = language, .operation = op, .order = order, .precision = precision, .zh_lobes = lobes, .command = "test"};
  if (op == shtool::ShaderOperation::zhf_rotate || op == shtool::ShaderOperation::zhf_tailored_rotate) {
    auto loaded = shtool::ZhfLobes::load(shtool::default_zhf_lobes_path(order));
    if (loaded) loaded = loaded.value().bands_below(order);
    if (!loaded) throw std::runtime_error(loaded.error().message);
    request.lobes = std::make_shared<const shtool::ZhfLobes>(std::move(loaded).value());
  }
  return request;
}

// The unit direction of node (column i, row j) of face `face` of a band texture with
// size x size texels: face coordinates sc = 2i / (size-1) - 1, tc = 2j / (size-1) - 1 (edges
// included), placed by the Vulkan face selection rule inverted (+X: sc = -z, tc = -y;
// -X: sc = z, tc = -y; +Y: sc = x, tc = z; -Y: sc = x, tc = -z; +Z: sc = x, tc = -y;
// -Z: sc = -x, tc = -y).
inline Eigen::Vector3d node_direction(int face, int i, int j, int size) {
  const double sc = 2.0 * i / (size - 1) - 1.0, tc = 2.0 * j / (size - 1) - 1.0;
  Eigen::Vector3d d;
  switch (face) {
    case 0: d = {1, -tc, -sc}; break;
    case 1: d = {-1, -tc, sc}; break;
    case 2: d = {sc, 1, tc}; break;
    case 3: d = {sc, -1, -tc}; break;
    case 4: d = {sc, -tc, 1}; break;
    default: d = {-sc, -tc, -1}; break;
  }
  return d.normalized();
}

// The band textures of coefficients c as the docs describe them: texture k holds the band
// sums of bands 4k..4k+3 at each node (in double, stored as float). size >= 2.
inline std::vector<CubeTexture> band_textures(int n, const std::vector<double>& c, int size) {
  const int count = (n + 3) / 4;
  std::vector<CubeTexture> cubes(count);
  for (auto& cube : cubes) {
    cube.size = size;
    cube.texels.assign(std::size_t(6) * size * size * 4, 0.0f);
  }
  std::vector<double> y(n * n);
  for (int face = 0; face < 6; ++face)
    for (int j = 0; j < size; ++j)
      for (int i = 0; i < size; ++i) {
        shtool::eval_sh<double>(n, node_direction(face, i, j, size), y);
        for (int l = 0; l < n; ++l) {
          double sum = 0;
          for (int m = -l; m <= l; ++m) sum += c[l * (l + 1) + m] * y[l * (l + 1) + m];
          cubes[l / 4].texels[((std::size_t(face) * size + j) * size + i) * 4 + l % 4] = static_cast<float>(sum);
        }
      }
  return cubes;
}

// Declarations of the band textures after the two storage buffers, and the arguments
// that pass them on.
inline std::string texture_declarations(shtool::ShaderLanguage lang, int count) {
  std::string d;
  for (int k = 0; k < count; ++k)
    d += lang == shtool::ShaderLanguage::glsl
             ? "layout(set = 0, binding = " + std::to_string(2 + k) + ") uniform samplerCube bands" +
                   std::to_string(k) + ";\n"
             : "[[vk::binding(" + std::to_string(2 + k) + ", 0)]] TextureCube<float4> bands" + std::to_string(k) +
                   ";\n";
  if (lang == shtool::ShaderLanguage::hlsl)
    d += "[[vk::binding(" + std::to_string(2 + count) + ", 0)]] SamplerState bands_sampler;\n";
  return d;
}

inline std::string texture_arguments(shtool::ShaderLanguage lang, int count) {
  std::string a;
  for (int k = 0; k < count; ++k) a += ", bands" + std::to_string(k);
  if (lang == shtool::ShaderLanguage::hlsl) a += ", bands_sampler";
  return a;
}


}  // namespace shtool::gpu
