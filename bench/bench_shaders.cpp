// The generated shaders on the Vulkan device the tests use (lavapipe: a CPU device, so
// these figures say little about a GPU; docs/shaders.md gives the operation counts, the
// figure that carries over). One dispatch per iteration, each invocation one operation on
// one of 65,536 input slots; items/s = operations per second. Each case runs with 0
// invocations too: the harness builds the pipeline (lavapipe compiles the shader) on
// every run, and that fixed cost is what the 0 case times; subtract it for the rate of
// the shader itself. Side by side: the three rotations (zxzxz, standard ZHF,
// signal-tailored ZHF from coefficients and from band textures), the basis, the triple
// product.
//   SHTOOL_TABLES=tables build/bench/bench_shaders [--benchmark_filter=...]
#include <benchmark/benchmark.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "shader_wrappers.h"

namespace {

using shtool::ShaderLanguage;
using shtool::ShaderOperation;
namespace gpu = shtool::gpu;

constexpr uint32_t kSlots = 65536;

// form: 0 the plain function, 1 the texture form (band textures of 65 x 65 nodes per face).
void BM_Shader(benchmark::State& state, ShaderOperation op, int form) {
  const int n = static_cast<int>(state.range(0));
  const uint32_t invocations = static_cast<uint32_t>(state.range(1));
  std::string why_not;
  gpu::VulkanCompute* device = gpu::shared_device(&why_not);
  if (!device) {
    state.SkipWithError(("no Vulkan device: " + why_not).c_str());
    return;
  }
  const shtool::ShaderRequest request = gpu::request_for(ShaderLanguage::glsl, op, n, 4);
  const std::string generated = shtool::shader_source(request).text;
  const gpu::Wrapper w = form ? gpu::textured_wrapper(ShaderLanguage::glsl, op, n, 4)
                              : gpu::wrapper(ShaderLanguage::glsl, op, n, 4);
  const int textures = form ? (n + 3) / 4 : 0;
  const std::vector<uint32_t> spirv = gpu::compiled_wrapper(ShaderLanguage::glsl, generated, w, textures);
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<float> u(-1, 1);
  std::vector<float> in(std::size_t(kSlots) * w.in_stride);
  for (float& v : in) v = u(rng);
  const bool rotation = op == ShaderOperation::zxzxz_rotate || op == ShaderOperation::zhf_rotate ||
                        op == ShaderOperation::zhf_tailored_rotate;
  if (rotation)
    for (uint32_t i = 0; i < kSlots; ++i) {
      const Eigen::Matrix3f r =
          Eigen::Quaternionf(u(rng), u(rng), u(rng), u(rng)).normalized().toRotationMatrix();
      for (int k = 0; k < 9; ++k) in[std::size_t(i) * w.in_stride + k] = r(k / 3, k % 3);
    }
  std::vector<gpu::CubeTexture> cubes;
  if (form) {
    std::vector<double> c(n * n);
    for (double& v : c) v = u(rng);
    cubes = gpu::band_textures(n, c, 65);
  }
  std::vector<std::vector<float>> buffers = {in, std::vector<float>(std::size_t(kSlots) * w.out_stride)};
  const gpu::WrapperPush push{invocations, kSlots};
  for (auto _ : state) device->run(spirv, buffers, invocations, &push, sizeof push, cubes);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * invocations);
}

BENCHMARK_CAPTURE(BM_Shader, zxzxz_rotate, ShaderOperation::zxzxz_rotate, 0)->Args({4, 0})->Args({4, 1 << 20})->Args({6, 0})->Args({6, 1 << 20})->Args({8, 0})->Args({8, 1 << 20})->UseRealTime();
BENCHMARK_CAPTURE(BM_Shader, zhf_rotate, ShaderOperation::zhf_rotate, 0)->Args({4, 0})->Args({4, 1 << 20})->Args({6, 0})->Args({6, 1 << 20})->Args({8, 0})->Args({8, 1 << 20})->UseRealTime();
BENCHMARK_CAPTURE(BM_Shader, zhf_tailored_arithmetic, ShaderOperation::zhf_tailored_rotate, 0)
    ->Args({4, 0})->Args({4, 1 << 20})->Args({6, 0})->Args({6, 1 << 20})->Args({8, 0})->Args({8, 1 << 20})->UseRealTime();
BENCHMARK_CAPTURE(BM_Shader, zhf_tailored_textures, ShaderOperation::zhf_tailored_rotate, 1)
    ->Args({4, 0})->Args({4, 1 << 20})->Args({6, 0})->Args({6, 1 << 20})->Args({8, 0})->Args({8, 1 << 20})->UseRealTime();
BENCHMARK_CAPTURE(BM_Shader, sh_eval, ShaderOperation::sh_eval, 0)->Args({3, 0})->Args({3, 1 << 20})->Args({6, 0})->Args({6, 1 << 20})->Args({10, 0})->Args({10, 1 << 20})->UseRealTime();
BENCHMARK_CAPTURE(BM_Shader, triple_product, ShaderOperation::triple_product, 0)->Args({3, 0})->Args({3, 1 << 20})->Args({6, 0})->Args({6, 1 << 20})->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
