// Test data shared by the benchmark programs (header-only; each bench is its own program),
// so every benchmark times the same rotations and vectors.
#pragma once

#include <array>
#include <cmath>
#include <cstddef>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "shtool/sh.h"

namespace shtool::bench {

// The end of main() in a program that registers its benchmarks at run time (one per
// order and type) before the command line is read.
inline int run_benchmarks(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}

// Number of precomputed rotations a timed loop cycles through: enough that branch
// predictors cannot learn one rotation, small enough to stay in L1.
inline constexpr int kRotations = 64;

// The index after k in a cycle of `size` (the rotation a timed loop takes next). A
// compare, not `(k + 1) % size`: with a run-time size the modulo is a 64-bit integer
// division, tens of cycles on the chain from one iteration to the next, which a
// low-order rotation (tens of nanoseconds) would pay on top of its own time.
inline std::size_t next_index(std::size_t k, std::size_t size) { return k + 1 == size ? 0 : k + 1; }

// Unit quaternions (w, x, y, z) in T, drawn in double so float and double see the same
// rotations. tilt < 0: uniform on SO(3) (normalised 4D Gaussian, seed 42); tilt >= 0:
// Rz(a) Ry(tilt) Rz(g) with random a, g (seed 2024), the small-angle set.
template <class T>
std::vector<std::array<T, 4>> random_quaternions(double tilt = -1) {
  std::mt19937_64 rng(tilt >= 0 ? 2024 : 42);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::vector<std::array<T, 4>> q(kRotations);
  for (auto& out : q) {
    std::array<double, 4> v;
    if (tilt >= 0) {
      // q = qz(a) qy(b) qz(g).
      const double a = angle(rng), g = angle(rng);
      const double cb = std::cos(tilt / 2), sb = std::sin(tilt / 2);
      const double s = (a + g) / 2, d = (a - g) / 2;
      v = {cb * std::cos(s), -sb * std::sin(d), sb * std::cos(d), cb * std::sin(s)};
    } else {
      double norm = 0;
      for (double& x : v) {
        x = gauss(rng);
        norm += x * x;
      }
      for (double& x : v) x /= std::sqrt(norm);
    }
    for (int c = 0; c < 4; ++c) out[c] = static_cast<T>(v[c]);
  }
  return q;
}

// `count` SH vectors of order N with coefficients uniform in [-1, 1] (fixed seed).
template <class T>
std::vector<std::vector<T>> random_sh_vectors(int order, int count) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<std::vector<T>> f(count, std::vector<T>(sh_count(order)));
  for (auto& v : f)
    for (auto& x : v) x = static_cast<T>(u(rng));
  return f;
}

}  // namespace shtool::bench
