// ZHF rotation ([1] Sec. 7.1) against zxzxz and the reference, side by side in one
// run: rotations per second for N = 2..10. One rotation = build from a unit quaternion
// (matrix_from_quaternion + set) and apply to one vector.
//
//   BM_Zhf/<type>/<method>/N
//     type     float | double
//     method   reference  ShRotation, dense Ivanic-Ruedenberg blocks
//              zxzxz      ShRotation, the sparse X90 factorisation (the paper's CPU rival)
//              zhf        ZhfRotation (Eq. 10): set(R) + apply(f), shipped shared lobes
//              zhf-tailored
//                         ZhfTailoredSignal (Eq. 11): f prepared once outside the loop,
//                         rotate(R) per iteration (sampling f~_l at R^-1 w_d + sparse A^)
//   items_per_second = rotations per second.
//
// The shared-lobe tables are tables/zhf-shared-N4..N10.shtb; N = 2, 3 use the N = 4 table
// truncated (its directions are nested), as default_zhf_lobes_path() does. The rotations
// are uniform on SO(3), the same 64 for every method and type (as in bench_rotation).
//
// Run: build/bench/bench_zhf                       (both types, a minute or two)
//      build/bench/bench_zhf --benchmark_filter='double'
// Figures: the zhfbench report / docs/benchmarks.md.
#include <array>
#include <cmath>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include <benchmark/benchmark.h>

#include "shtool/euler.h"
#include "shtool/rotation.h"
#include "shtool/rotation_helpers.h"
#include "shtool/sh.h"
#include "shtool/zhf_rotation.h"
#include "bench_util.h"

namespace {

using shtool::RotationMethod;

constexpr int kMinOrder = 2;
constexpr int kMaxOrder = 10;

std::shared_ptr<const shtool::RotationHelpers> helpers() {
  static const std::shared_ptr<const shtool::RotationHelpers> h = [] {
    auto loaded = shtool::RotationHelpers::load(shtool::default_rotation_helpers_path());
    if (!loaded) throw std::runtime_error("bench_zhf: " + loaded.error().message);
    return std::make_shared<const shtool::RotationHelpers>(std::move(loaded).value());
  }();
  return h;
}

std::shared_ptr<const shtool::ZhfLobes> lobes(int order) {
  static std::map<int, std::shared_ptr<const shtool::ZhfLobes>> cache;
  auto& slot = cache[order];
  if (!slot) {
    const auto path = shtool::default_zhf_lobes_path(order);
    if (path.empty()) throw std::runtime_error("bench_zhf: no shipped zhf-shared table for N = " + std::to_string(order));
    auto loaded = shtool::ZhfLobes::load(path);
    if (loaded) loaded = loaded.value().bands_below(order);
    if (!loaded) throw std::runtime_error("bench_zhf: " + loaded.error().message);
    slot = std::make_shared<const shtool::ZhfLobes>(std::move(loaded).value());
  }
  return slot;
}

enum class Method { reference, zxzxz, zhf, zhf_tailored };

const char* method_name(Method m) {
  switch (m) {
    case Method::reference: return "reference";
    case Method::zxzxz: return "zxzxz";
    case Method::zhf: return "zhf";
    case Method::zhf_tailored: return "zhf-tailored";
  }
  return "?";
}

template <class T>
void BM_Zhf(benchmark::State& state, Method method) {
  const int order = static_cast<int>(state.range(0));
  const auto q = shtool::bench::random_quaternions<T>();
  const std::vector<T> in = shtool::bench::random_sh_vectors<T>(order, 1)[0];
  std::vector<T> out(in.size());
  std::size_t k = 0;
  auto next = [&]() {
    const auto& qk = q[k];
    k = shtool::bench::next_index(k, q.size());
    return shtool::matrix_from_quaternion<T>(qk[0], qk[1], qk[2], qk[3]);
  };

  if (method == Method::reference || method == Method::zxzxz) {
    shtool::ShRotation<T> rotation(order, helpers());
    const RotationMethod rm = method == Method::reference ? RotationMethod::reference : RotationMethod::zxzxz;
    bool ok = true;
    for (auto _ : state) {
      ok &= rotation.set(next(), rm);
      rotation.apply(in, out);
      benchmark::DoNotOptimize(out.data());
      benchmark::ClobberMemory();
    }
    if (!ok) state.SkipWithError("ShRotation::set failed (helpers missing?)");
  } else if (method == Method::zhf) {
    shtool::ZhfRotation<T> rotation(order, lobes(order));
    for (auto _ : state) {
      rotation.set(next());
      rotation.apply(in, out);
      benchmark::DoNotOptimize(out.data());
      benchmark::ClobberMemory();
    }
  } else {
    shtool::ZhfTailoredSignal<T> signal(lobes(order), in);
    for (auto _ : state) {
      signal.set(next());
      signal.apply(out);
      benchmark::DoNotOptimize(out.data());
      benchmark::ClobberMemory();
    }
  }
  state.SetItemsProcessed(state.iterations());
}

template <class T>
void register_all(const char* type) {
  // Interleaved by order, so that the methods compared at one N run back to back and see
  // the same load on this shared machine.
  for (int n = kMinOrder; n <= kMaxOrder; ++n)
    for (Method m : {Method::reference, Method::zxzxz, Method::zhf, Method::zhf_tailored}) {
      const std::string name = std::string("BM_Zhf/") + type + "/" + method_name(m);
      benchmark::RegisterBenchmark(name.c_str(), [m](benchmark::State& s) { BM_Zhf<T>(s, m); })->Arg(n);
    }
}

}  // namespace

int main(int argc, char** argv) {
  register_all<float>("float");
  register_all<double>("double");
  return shtool::bench::run_benchmarks(argc, argv);
}
