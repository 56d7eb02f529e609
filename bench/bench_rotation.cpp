// SH rotations, every method side by side: rotations per second for
// N = 2..20, one rotation = build from a unit quaternion (matrix_from_quaternion +
// ShRotation::set) and apply it to one vector, or to three (an RGB light, interleaved
// or as three vectors).
//
//   BM_Rotate/<type>/<method>/<tilt>/<vectors>/N
//     type     float | double
//     method   reference | zxzxz | taylor1 | taylor1.5 | taylor2 | auto
//     tilt     large: uniformly random rotations (generic tilt);
//              small: zyz tilt b = kSmallTilt, random alpha and gamma, so that `auto`
//              (default tolerance) takes a Taylor branch. The Taylor methods are timed on
//              the small tilts only (on large ones they are fast but wrong); the exact
//              methods cost the same at every tilt and are timed on the large ones.
//     vectors  1: one vector, apply(in, out);
//              3: an RGB light, interleaved (i * 3 + c), one apply(in, out, 3) call;
//              3x1: the same light as three separate vectors, three apply() calls
//   items_per_second = rotations per second; label of `auto` = the method it chose.
//
//   BM_RotateBatch/<type>/<method>/<tilt>/N: the same rotations (one vector each) through
//     rotate_batch, kRotations (rotation, vector) pairs per call, matrices from the
//     quaternions inside the timed loop; items_per_second = rotations per second,
//     comparable with BM_Rotate/<type>/<method>/<tilt>/1/N.
//
//   BM_Apply/<type>/<vectors>/N: apply alone, one generic rotation set once (zxzxz),
//     vectors 3 (interleaved, one apply(in, out, 3) call) or 3x1 (three apply() calls);
//     items_per_second = RGB lights per second. The cost of the colour layout, without
//     set() in the time.
//
//   BM_ComputeRotationHelpers/N/threads: the helpers of an order past the shipped table,
//     as `shtool rotate` and the Python module compute them (the N^5 quadrature sums on
//     `threads` threads, 0 = every core); with the offline library only.
//
// Run: build/bench/bench_rotation --benchmark_filter='BM_Rotate/double/.*/1/'
// Figures, the machine and the peer comparison: docs/benchmarks.md, "Rotations".
#include <array>
#include <cmath>
#include <memory>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "shtool/euler.h"
#include "shtool/rotation.h"
#include "shtool/rotation_helpers.h"
#include "shtool/sh.h"
#include "bench_util.h"

#ifdef SHTOOL_BENCH_HAVE_OFFLINE
#include "tensors/rotation_helpers_gen.h"
#endif

namespace {

using shtool::RotationMethod;

constexpr int kMinOrder = 2;
constexpr int kMaxOrder = 20;
// Tilt of the "small" set: with the default tolerance 1e-10 the 2nd order Taylor bound
// (b (N - 1))^3 / 6 passes up to N = 20 (1.1e-12), so `auto` picks a Taylor method.
constexpr double kSmallTilt = 1e-5;

std::shared_ptr<const shtool::RotationHelpers> helpers() {
  static const std::shared_ptr<const shtool::RotationHelpers> h = [] {
#ifdef SHTOOL_BENCH_HAVE_OFFLINE
    return std::make_shared<const shtool::RotationHelpers>(shtool::compute_rotation_helpers(kMaxOrder));
#else
    auto loaded = shtool::RotationHelpers::load(shtool::default_rotation_helpers_path());
    if (!loaded) throw std::runtime_error("bench_rotation: no rotation-helpers table; run shtool gen-tensors");
    return std::make_shared<const shtool::RotationHelpers>(std::move(loaded).value());
#endif
  }();
  return h;
}

// vectors: 1 (one vector), 3 (interleaved RGB, one call), -3 (three vectors, three calls).
template <class T>
void BM_Rotate(benchmark::State& state, RotationMethod method, bool small_tilt, int vectors) {
  const int order = static_cast<int>(state.range(0));
  shtool::ShRotation<T> rotation(order, helpers());
  const auto q = shtool::bench::random_quaternions<T>(small_tilt ? kSmallTilt : -1);
  const int count = vectors < 0 ? -vectors : vectors;
  const auto in = shtool::bench::random_sh_vectors<T>(order, count);
  auto out = shtool::bench::random_sh_vectors<T>(order, count);
  const std::size_t n = in[0].size();
  std::vector<T> in_rgb(3 * n), out_rgb(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3 && c < count; ++c) in_rgb[3 * i + c] = in[c][i];

  std::size_t k = 0;
  bool ok = true;
  for (auto _ : state) {
    const auto& qk = q[k];
    k = shtool::bench::next_index(k, q.size());
    const shtool::Mat3<T> r = shtool::matrix_from_quaternion<T>(qk[0], qk[1], qk[2], qk[3]);
    ok &= rotation.set(r, method);
    if (vectors == 3) {
      ok &= rotation.apply(in_rgb, out_rgb, 3);
      benchmark::DoNotOptimize(out_rgb.data());
    } else {
      for (int v = 0; v < count; ++v) rotation.apply(in[v], out[v]);
      benchmark::DoNotOptimize(out.data());
    }
    benchmark::ClobberMemory();
  }
  if (!ok) state.SkipWithError("ShRotation::set or apply failed (helpers missing?)");
  state.SetItemsProcessed(state.iterations());
  if (method == RotationMethod::automatic)
    state.SetLabel(std::string(shtool::rotation_method_name(rotation.method())));
}

template <class T>
void BM_Apply(benchmark::State& state, bool interleaved) {
  const int order = static_cast<int>(state.range(0));
  shtool::ShRotation<T> rotation(order, helpers());
  const auto q = shtool::bench::random_quaternions<T>(-1)[0];
  bool ok = rotation.set(shtool::matrix_from_quaternion<T>(q[0], q[1], q[2], q[3]), RotationMethod::zxzxz);
  const auto in = shtool::bench::random_sh_vectors<T>(order, 3);
  auto out = shtool::bench::random_sh_vectors<T>(order, 3);
  const std::size_t n = in[0].size();
  std::vector<T> in_rgb(3 * n), out_rgb(3 * n);
  for (std::size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) in_rgb[3 * i + c] = in[c][i];
  for (auto _ : state) {
    if (interleaved) {
      ok &= rotation.apply(in_rgb, out_rgb, 3);
      benchmark::DoNotOptimize(out_rgb.data());
    } else {
      for (int c = 0; c < 3; ++c) rotation.apply(in[c], out[c]);
      benchmark::DoNotOptimize(out.data());
    }
    benchmark::ClobberMemory();
  }
  if (!ok) state.SkipWithError("ShRotation::set or apply failed (helpers missing?)");
  state.SetItemsProcessed(state.iterations());
}

template <class T>
void BM_RotateBatch(benchmark::State& state, RotationMethod method, bool small_tilt) {
  const int order = static_cast<int>(state.range(0));
  shtool::ShRotation<T> rotation(order, helpers());
  const auto q = shtool::bench::random_quaternions<T>(small_tilt ? kSmallTilt : -1);
  const int count = static_cast<int>(q.size());
  std::vector<T> in;  // count vectors of N^2, one after the other
  for (const auto& v : shtool::bench::random_sh_vectors<T>(order, count)) in.insert(in.end(), v.begin(), v.end());
  std::vector<T> out(in.size());
  std::vector<shtool::Mat3<T>> r(q.size());
  bool ok = true;
  for (auto _ : state) {
    for (int k = 0; k < count; ++k) r[k] = shtool::matrix_from_quaternion<T>(q[k][0], q[k][1], q[k][2], q[k][3]);
    ok &= shtool::rotate_batch<T>(rotation, r, in, out, method);
    benchmark::DoNotOptimize(out.data());
    benchmark::ClobberMemory();
  }
  if (!ok) state.SkipWithError("rotate_batch failed (helpers missing?)");
  state.SetItemsProcessed(state.iterations() * count);
}

template <class T>
void register_all(const char* type) {
  struct Case {
    RotationMethod method;
    bool small_tilt;
  };
  const Case cases[] = {
      {RotationMethod::reference, false}, {RotationMethod::zxzxz, false},
      {RotationMethod::taylor1, true},    {RotationMethod::taylor15, true},
      {RotationMethod::taylor2, true},    {RotationMethod::automatic, true},
      {RotationMethod::automatic, false},
  };
  for (int vectors : {1, 3, -3})
    for (const Case& c : cases) {
      const std::string name = std::string("BM_Rotate/") + type + "/" +
                               std::string(shtool::rotation_method_name(c.method)) + "/" +
                               (c.small_tilt ? "small" : "large") + "/" +
                               (vectors < 0 ? std::string("3x1") : std::to_string(vectors));
      benchmark::RegisterBenchmark(name.c_str(), [c, vectors](benchmark::State& s) {
        BM_Rotate<T>(s, c.method, c.small_tilt, vectors);
      })->DenseRange(kMinOrder, kMaxOrder);
    }
  for (bool interleaved : {true, false}) {
    const std::string name = std::string("BM_Apply/") + type + "/" + (interleaved ? "3" : "3x1");
    benchmark::RegisterBenchmark(name.c_str(), [interleaved](benchmark::State& s) {
      BM_Apply<T>(s, interleaved);
    })->DenseRange(kMinOrder, kMaxOrder);
  }
  for (const Case& c : cases) {
    const std::string name = std::string("BM_RotateBatch/") + type + "/" +
                             std::string(shtool::rotation_method_name(c.method)) + "/" +
                             (c.small_tilt ? "small" : "large");
    benchmark::RegisterBenchmark(name.c_str(), [c](benchmark::State& s) {
      BM_RotateBatch<T>(s, c.method, c.small_tilt);
    })->DenseRange(kMinOrder, kMaxOrder);
  }
}

#ifdef SHTOOL_BENCH_HAVE_OFFLINE
void BM_ComputeRotationHelpers(benchmark::State& state) {
  const int order = static_cast<int>(state.range(0)), threads = static_cast<int>(state.range(1));
  for (auto _ : state) benchmark::DoNotOptimize(shtool::compute_rotation_helpers(order, threads));
}
#endif

}  // namespace

int main(int argc, char** argv) {
  register_all<float>("float");
  register_all<double>("double");
#ifdef SHTOOL_BENCH_HAVE_OFFLINE
  benchmark::RegisterBenchmark("BM_ComputeRotationHelpers", BM_ComputeRotationHelpers)
      ->ArgsProduct({{40, 64}, {1, 0}})
      ->Unit(benchmark::kSecond)
      ->UseRealTime();
#endif
  return shtool::bench::run_benchmarks(argc, argv);
}
