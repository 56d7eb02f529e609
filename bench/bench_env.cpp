// Environment-map projection (docs/lighting.md), one thread:
//   BM_ProjectEquirect/N       project_equirect on a 4096 x 2048 RGB float image
//   BM_ProjectEquirectSetup/N  EquirectProjector::create alone (the per-size cost that
//                              project_equirect pays on every call)
//   BM_NaiveEquirect/N         the textbook loop: all N^2 SH at every texel centre
//   BM_ReadImageOnce           one pass over the same floats: the memory-bandwidth floor
//   BM_ProjectCubemap/N        project_cubemap on six 1024 x 1024 RGB faces (create included)
//   BM_ProjectCubemapReference/N  project_cubemap_reference on the same faces: the rule
//                              run texel by texel, for the ratio
// items_per_second is texels per second.
// Run: build/bench/bench_env --benchmark_min_time=0.1
// Figures and the machine they were measured on: docs/benchmarks.md.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include <benchmark/benchmark.h>

#include "shtool/env_projection.h"
#include "shtool/sh.h"

namespace {

constexpr int kEquirectWidth = 4096, kEquirectHeight = 2048;
constexpr int kFaceSize = 1024;
constexpr int kChannels = 3;

// Uniform in [0, 1): an image with no structure, so no texel is cheaper than another.
std::vector<float> random_texels(std::size_t count, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::vector<float> v(count);
  for (float& x : v) x = u(rng);
  return v;
}

// Made on first use and kept: 100 MB (equirect) and 75 MB (cube) would otherwise be
// generated for every benchmark, and a filtered run should not pay for the other.
const std::vector<float>& equirect_texels() {
  static const std::vector<float> texels =
      random_texels(static_cast<std::size_t>(kEquirectWidth) * kEquirectHeight * kChannels, 1);
  return texels;
}

shtool::FloatImageView equirect_view() {
  return {equirect_texels().data(), kEquirectWidth, kEquirectHeight, kChannels, 0};
}

const std::vector<float>& cube_texels() {
  static const std::vector<float> texels =
      random_texels(6 * static_cast<std::size_t>(kFaceSize) * kFaceSize * kChannels, 2);
  return texels;
}

const std::vector<double>& check(const shtool::Result<shtool::EnvCoefficients>& r) {
  if (!r) {
    std::fprintf(stderr, "bench_env: %s\n", r.error().message.c_str());
    std::abort();
  }
  return r.value().coefficients;
}

void set_texel_rates(benchmark::State& state, std::size_t texels) {
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * texels));
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations() * texels * kChannels * sizeof(float)));
}

void BM_ProjectEquirect(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const shtool::FloatImageView image = equirect_view();
  for (auto _ : state) {
    shtool::Result<shtool::EnvCoefficients> r = shtool::project_equirect(image, n);
    benchmark::DoNotOptimize(check(r).data());
  }
  set_texel_rates(state, static_cast<std::size_t>(kEquirectWidth) * kEquirectHeight);
}

void BM_ProjectEquirectSetup(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  for (auto _ : state) {
    shtool::Result<shtool::EquirectProjector> p = shtool::EquirectProjector::create(kEquirectWidth, kEquirectHeight, n);
    if (!p) std::abort();
    benchmark::DoNotOptimize(p.value().row_integrals(0).data());
  }
}

// The midpoint rule in the polar angle with the row's exact solid angle: what a
// projection without the separable integrals costs. The counter max_diff is its
// largest difference from project_equirect, over the coefficients (the midpoint rule's
// error, not a failure).
void BM_NaiveEquirect(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int count = shtool::sh_count(n);
  const std::vector<float>& texels = equirect_texels();
  std::vector<double> coeffs(static_cast<std::size_t>(count) * kChannels);
  std::vector<double> y(count);
  constexpr double kPi = std::numbers::pi;
  for (auto _ : state) {
    std::fill(coeffs.begin(), coeffs.end(), 0.0);
    for (int row = 0; row < kEquirectHeight; ++row) {
      const double t0 = kPi * row / kEquirectHeight, t1 = kPi * (row + 1) / kEquirectHeight;
      const double solid_angle = (2 * kPi / kEquirectWidth) * (std::cos(t0) - std::cos(t1));
      const double t = (t0 + t1) / 2;
      const float* line = &texels[static_cast<std::size_t>(row) * kEquirectWidth * kChannels];
      for (int x = 0; x < kEquirectWidth; ++x) {
        const double p = kPi - 2 * kPi * (x + 0.5) / kEquirectWidth;
        shtool::eval_sh<double>(n, shtool::direction_from_angles(t, p), y);
        const float* v = line + static_cast<std::size_t>(x) * kChannels;
        for (int i = 0; i < count; ++i) {
          const double w = y[i] * solid_angle;
          for (int c = 0; c < kChannels; ++c) coeffs[static_cast<std::size_t>(i) * kChannels + c] += w * v[c];
        }
      }
    }
    benchmark::DoNotOptimize(coeffs.data());
    benchmark::ClobberMemory();
  }
  set_texel_rates(state, static_cast<std::size_t>(kEquirectWidth) * kEquirectHeight);
  const std::vector<double> exact = check(shtool::project_equirect(equirect_view(), n));
  double diff = 0;
  for (std::size_t i = 0; i < exact.size(); ++i) diff = std::max(diff, std::abs(exact[i] - coeffs[i]));
  state.counters["max_diff"] = diff;
}

// Summed in double like the projections, in four chains so the additions' latency
// does not hide the memory bandwidth.
void BM_ReadImageOnce(benchmark::State& state) {
  const std::vector<float>& texels = equirect_texels();
  for (auto _ : state) {
    double s[4] = {0, 0, 0, 0};
    const std::size_t size = texels.size();
    std::size_t i = 0;
    for (; i + 4 <= size; i += 4)
      for (int k = 0; k < 4; ++k) s[k] += texels[i + k];
    for (; i < size; ++i) s[0] += texels[i];
    double sum = (s[0] + s[1]) + (s[2] + s[3]);
    benchmark::DoNotOptimize(sum);
  }
  set_texel_rates(state, static_cast<std::size_t>(kEquirectWidth) * kEquirectHeight);
}

std::array<shtool::FloatImageView, 6> cube_views() {
  const std::vector<float>& texels = cube_texels();
  const std::size_t face = static_cast<std::size_t>(kFaceSize) * kFaceSize * kChannels;
  std::array<shtool::FloatImageView, 6> faces;
  for (int f = 0; f < 6; ++f) faces[f] = {texels.data() + f * face, kFaceSize, kFaceSize, kChannels, 0};
  return faces;
}

void BM_ProjectCubemap(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const std::array<shtool::FloatImageView, 6> faces = cube_views();
  for (auto _ : state) {
    shtool::Result<shtool::EnvCoefficients> r = shtool::project_cubemap(std::span<const shtool::FloatImageView, 6>(faces), n);
    benchmark::DoNotOptimize(check(r).data());
  }
  set_texel_rates(state, 6 * static_cast<std::size_t>(kFaceSize) * kFaceSize);
  state.counters["nodes"] = shtool::cubemap_nodes_per_side(kFaceSize, n);
}

void BM_ProjectCubemapReference(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const std::array<shtool::FloatImageView, 6> faces = cube_views();
  for (auto _ : state) {
    shtool::Result<shtool::EnvCoefficients> r =
        shtool::project_cubemap_reference(std::span<const shtool::FloatImageView, 6>(faces), n);
    benchmark::DoNotOptimize(check(r).data());
  }
  set_texel_rates(state, 6 * static_cast<std::size_t>(kFaceSize) * kFaceSize);
}

}  // namespace

BENCHMARK(BM_ReadImageOnce)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProjectEquirect)->Arg(3)->Arg(6)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProjectEquirectSetup)->Arg(3)->Arg(6)->Arg(10)->Arg(20)->Unit(benchmark::kMicrosecond);
// Seconds per call: one iteration is already far above any min_time worth asking for.
BENCHMARK(BM_NaiveEquirect)->Arg(3)->Arg(6)->Arg(10)->Arg(20)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProjectCubemap)->Arg(3)->Arg(6)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_ProjectCubemapReference)->Arg(3)->Iterations(1)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
