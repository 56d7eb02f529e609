// SH triple and k-multiple products, side by side ([3] Sec. 5.1):
//   BM_Triple/<method>/<type>/N         g = f1 (x) f2 by the tripling tensor, the Fourier
//                                       method, the grid (quadrature) and auto (default)
//   BM_Multiple/<method>/<type>/k/N     k - 1 inputs: accurate (grid; Fourier with divide
//                                       and conquer) vs recursive (Eq. 11, tripling / auto)
//   BM_GridAzimuth/<direct|fft>/<type>/k/N  the grid product's two azimuthal transforms
//   BM_TriplingBuild/N                  runtime construction of the tripling tensor
// Run: build-*/bench/bench_products --benchmark_min_time=0.2
// Figures and the machine they were measured on: docs/products.md.
#include <span>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "shtool/fourier_product.h"
#include "shtool/grid_product.h"
#include "shtool/product.h"
#include "shtool/sh.h"
#include "shtool/tripling_product.h"
#include "bench_util.h"

namespace {

using shtool::sh_count;

// Times multiply(f, h, g) of two random order-n vectors, the same for every method.
template <class T, class Multiply>
void time_pair_products(benchmark::State& state, int n, Multiply multiply) {
  const auto f = shtool::bench::random_sh_vectors<T>(n, 2);
  std::vector<T> g(sh_count(n));
  for (auto _ : state) {
    multiply(f[0], f[1], g);
    benchmark::DoNotOptimize(g.data());
    benchmark::ClobberMemory();
  }
}

template <class T>
void BM_TripleTripling(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const shtool::TriplingProduct<T> product(shtool::TriplingTensor::compute(n));
  time_pair_products<T>(state, n, [&](const auto& a, const auto& b, auto& g) { product.multiply(a, b, g); });
  state.counters["pairs"] = static_cast<double>(product.pair_count());
}

// Fourier ([3]) and grid products share the interface and the grid counter
// (theta points * 1000 + phi points).
template <class T, template <class> class Product>
void BM_TripleOnGrid(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  Product<T> product(n, 2);
  time_pair_products<T>(state, n, [&](const auto& a, const auto& b, auto& g) { product.multiply(a, b, g); });
  state.counters["grid"] = product.grid_theta() * 1000.0 + product.grid_phi();
}

// The grid product's two azimuthal methods at equal (order, inputs): the crossover that
// kDirectAzimuthMaxPoints (grid_product.cpp) encodes. Args: k (inputs + 1), N.
template <class T, shtool::GridAzimuth azimuth>
void BM_GridAzimuth(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  const int n = static_cast<int>(state.range(1));
  shtool::GridProduct<T> product(n, k - 1, azimuth);
  const auto f = shtool::bench::random_sh_vectors<T>(n, k - 1);
  const std::vector<std::span<const T>> spans(f.begin(), f.end());
  std::vector<T> g(sh_count(n));
  for (auto _ : state) {
    product.multiply(spans, g);
    benchmark::DoNotOptimize(g.data());
    benchmark::ClobberMemory();
  }
  state.counters["points"] = product.grid_theta() * product.grid_phi();
}

template <class T>
void BM_TripleAuto(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  shtool::ShProduct<T> product(n);
  product.prepare(2);
  time_pair_products<T>(state, n, [&](const auto& a, const auto& b, auto& g) { product.triple(a, b, g); });
}

enum Mode { kAccurateGrid, kAccurateFourier, kRecursiveTripling, kRecursiveAuto };

template <class T, Mode mode>
void BM_Multiple(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  const int n = static_cast<int>(state.range(1));
  const int inputs = k - 1;
  const auto f = shtool::bench::random_sh_vectors<T>(n, inputs);
  std::vector<std::span<const T>> spans(f.begin(), f.end());
  std::vector<T> g(sh_count(n));
  const shtool::ProductMethod method = mode == kRecursiveTripling ? shtool::ProductMethod::tripling
                                       : mode == kAccurateFourier ? shtool::ProductMethod::fourier
                                       : mode == kAccurateGrid    ? shtool::ProductMethod::grid
                                                                  : shtool::ProductMethod::automatic;
  shtool::ShProduct<T> product(n, method);
  const bool accurate = mode == kAccurateGrid || mode == kAccurateFourier;
  product.prepare(accurate ? inputs : 2);
  for (auto _ : state) {
    if (accurate)
      product.multiple(spans, g);
    else
      product.recursive(spans, g);
    benchmark::DoNotOptimize(g.data());
    benchmark::ClobberMemory();
  }
}

void BM_TriplingBuild(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  for (auto _ : state) {
    shtool::TriplingTensor t = shtool::TriplingTensor::compute(n);
    benchmark::DoNotOptimize(t.value.data());
    state.counters["nonzeros"] = static_cast<double>(t.size());
  }
}

void triple_orders(benchmark::internal::Benchmark* b) {
  for (int n = 3; n <= 20; ++n) b->Arg(n);
}
void azimuth_args(benchmark::internal::Benchmark* b) {
  for (int n = 3; n <= 20; ++n) b->Args({3, n});
  for (int k : {4, 6, 8})
    for (int n : {3, 4, 5, 6, 8, 10, 15, 20}) b->Args({k, n});
}
void multiple_args(benchmark::internal::Benchmark* b) {
  for (int k : {4, 6, 8})
    for (int n : {3, 5, 8, 10, 15, 20}) b->Args({k, n});
}

}  // namespace

BENCHMARK(BM_TripleTripling<float>)->Name("BM_Triple/tripling/float")->Apply(triple_orders);
BENCHMARK(BM_TripleOnGrid<float, shtool::FourierProduct>)->Name("BM_Triple/fourier/float")->Apply(triple_orders);
BENCHMARK(BM_TripleOnGrid<float, shtool::GridProduct>)->Name("BM_Triple/grid/float")->Apply(triple_orders);
BENCHMARK(BM_GridAzimuth<float, shtool::GridAzimuth::direct>)->Name("BM_GridAzimuth/direct/float")->Apply(azimuth_args);
BENCHMARK(BM_GridAzimuth<float, shtool::GridAzimuth::fft>)->Name("BM_GridAzimuth/fft/float")->Apply(azimuth_args);
BENCHMARK(BM_GridAzimuth<double, shtool::GridAzimuth::direct>)->Name("BM_GridAzimuth/direct/double")->Apply(azimuth_args);
BENCHMARK(BM_GridAzimuth<double, shtool::GridAzimuth::fft>)->Name("BM_GridAzimuth/fft/double")->Apply(azimuth_args);
BENCHMARK(BM_TripleAuto<float>)->Name("BM_Triple/auto/float")->Apply(triple_orders);
BENCHMARK(BM_TripleTripling<double>)->Name("BM_Triple/tripling/double")->Apply(triple_orders);
BENCHMARK(BM_TripleOnGrid<double, shtool::FourierProduct>)->Name("BM_Triple/fourier/double")->Apply(triple_orders);
BENCHMARK(BM_TripleOnGrid<double, shtool::GridProduct>)->Name("BM_Triple/grid/double")->Apply(triple_orders);
BENCHMARK(BM_TripleAuto<double>)->Name("BM_Triple/auto/double")->Apply(triple_orders);
BENCHMARK(BM_Multiple<float, kAccurateGrid>)->Name("BM_Multiple/accurate-grid/float")->Apply(multiple_args);
BENCHMARK(BM_Multiple<float, kAccurateFourier>)->Name("BM_Multiple/accurate-fourier/float")->Apply(multiple_args);
BENCHMARK(BM_Multiple<float, kRecursiveTripling>)->Name("BM_Multiple/recursive-tripling/float")->Apply(multiple_args);
BENCHMARK(BM_Multiple<float, kRecursiveAuto>)->Name("BM_Multiple/recursive-auto/float")->Apply(multiple_args);
BENCHMARK(BM_Multiple<double, kAccurateGrid>)->Name("BM_Multiple/accurate-grid/double")->Apply(multiple_args);
BENCHMARK(BM_Multiple<double, kAccurateFourier>)->Name("BM_Multiple/accurate-fourier/double")->Apply(multiple_args);
BENCHMARK(BM_Multiple<double, kRecursiveTripling>)->Name("BM_Multiple/recursive-tripling/double")->Apply(multiple_args);
BENCHMARK(BM_Multiple<double, kRecursiveAuto>)->Name("BM_Multiple/recursive-auto/double")->Apply(multiple_args);
BENCHMARK(BM_TriplingBuild)->Arg(5)->Arg(10)->Arg(15)->Arg(20)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
