// fit-glossy's BRDF matrix ([4] Eq. 14), the per-ring fast path beside its row-by-row
// reference, and the runtime's view-dependent shading (Eq. 16).
//
//   BM_BrdfMatrix/<model>/<path>   B at the defaults (order 4, a 32 x 32 view map, the
//                                  128 x 256 rule), ONE thread; model cook-torrance or
//                                  phong (m = 0.3), path rings (brdf_matrix) or direct
//                                  (brdf_matrix_direct).
//   BM_GlossyShade/<type>          GlossyFit::shade of one point: n_b = 3 rows of 3 lobes,
//                                  order 4, view-factor look-up included; 4096 points with
//                                  random axes, coefficients and views per iteration.
//
// Command: build/bench/bench_glossy --benchmark_repetitions=3
//          --benchmark_enable_random_interleaving=true --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "glossy/brdf.h"
#include "shtool/glossy.h"

namespace {

using namespace shtool;

void BM_BrdfMatrix(benchmark::State& state, glossy::BrdfModel model, bool rings) {
  const glossy::Brdf brdf{model, 0.3, 1.0};
  for (auto _ : state) {
    Eigen::MatrixXd b = rings ? glossy::brdf_matrix(brdf, 4, 32, 1) : glossy::brdf_matrix_direct(brdf, 4, 32, 1);
    benchmark::DoNotOptimize(b.data());
  }
}
BENCHMARK_CAPTURE(BM_BrdfMatrix, cook-torrance/rings, glossy::BrdfModel::cook_torrance, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BrdfMatrix, cook-torrance/direct, glossy::BrdfModel::cook_torrance, false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BrdfMatrix, phong/rings, glossy::BrdfModel::phong, true)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BrdfMatrix, phong/direct, glossy::BrdfModel::phong, false)->Unit(benchmark::kMillisecond);

template <class T>
void BM_GlossyShade(benchmark::State& state) {
  constexpr int kPoints = 4096, kTerms = 3, kLobes = 3, kOrder = 4, kG = 32;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  GlossyFit<T> fit;
  fit.vertices = kPoints;
  fit.terms = kTerms;
  fit.view_resolution = kG;
  fit.rows.order = kOrder;
  fit.rows.lobes = kLobes;
  fit.rows.vertices = std::size_t(kPoints) * kTerms;
  fit.rows.direct_count = 4;
  for (std::size_t r = 0; r < fit.rows.vertices; ++r) {
    for (int k = 0; k < kLobes; ++k) {
      fit.rows.axes.push_back(Vec3<double>(gauss(rng), gauss(rng), gauss(rng)).normalized().cast<T>());
      for (int l = 0; l < kOrder; ++l) fit.rows.coeffs.push_back(static_cast<T>(l < 2 ? 0.0 : gauss(rng)));
    }
    for (int i = 0; i < 4; ++i) fit.rows.direct.push_back(static_cast<T>(gauss(rng)));
  }
  for (int i = 0; i < kG * kG * kTerms; ++i) fit.view_factors.push_back(static_cast<T>(gauss(rng) / kG));
  std::vector<Vec3<T>> views;
  for (int p = 0; p < kPoints; ++p)
    views.push_back(Vec3<double>(gauss(rng), gauss(rng), std::abs(gauss(rng))).normalized().cast<T>());
  std::vector<T> light(kOrder * kOrder);
  for (T& e : light) e = static_cast<T>(gauss(rng));
  for (auto _ : state) {
    T sum = 0;
    for (int p = 0; p < kPoints; ++p) sum += fit.shade(light, p, views[p]);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * kPoints);
}
BENCHMARK_TEMPLATE(BM_GlossyShade, float);
BENCHMARK_TEMPLATE(BM_GlossyShade, double);

}  // namespace

BENCHMARK_MAIN();
