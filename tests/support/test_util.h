// Small helpers shared by the test programs (header-only; each test is its own program).
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>

#include "shtool/quadrature.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"

namespace shtool::test {

// Random SH coefficients uniform in [-1, 1] (the papers' test vectors).
inline std::vector<double> random_coeffs(int order, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> f(sh_count(order));
  for (double& v : f) v = u(rng);
  return f;
}

// `count` product inputs of order N, coefficients uniform in [-1, 1], from one seed.
inline std::vector<std::vector<double>> random_inputs(int order, int count, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::vector<std::vector<double>> f;
  for (int i = 0; i < count; ++i) f.push_back(random_coeffs(order, rng));
  return f;
}

// Legendre polynomial P_l(x) by Bonnet's recurrence, k P_k = (2k - 1) x P_{k-1} - (k - 1) P_{k-2},
// in R (long double where a reference needs the digits): the quadrature references' P_l.
template <class R>
R legendre_p(int l, R x) {
  R p0 = 1, p1 = x;
  if (l == 0) return p0;
  for (int k = 2; k <= l; ++k) {
    const R pk = ((2 * k - 1) * x * p1 - (k - 1) * p0) / k;
    p0 = p1;
    p1 = pk;
  }
  return p1;
}

// Euclidean norm of a coefficient vector.
inline double norm(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

// Property values in scientific notation (std::to_string would print 0.000000).
// Relative L2 distance of got (any floating type) from ref: sqrt(sum err^2 / sum ref^2).
template <class T>
double relative_l2(const std::vector<T>& got, const std::vector<double>& ref) {
  double e = 0, r = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const double d = static_cast<double>(got[i]) - ref[i];
    e += d * d;
    r += ref[i] * ref[i];
  }
  return std::sqrt(e / r);
}

inline std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3e", v);
  return buf;
}

// SH projection of the pointwise product of the inputs, with a sphere rule exact for the
// integrand (degree (count + 1)(N - 1)), evaluated with eval_sh and accumulated in long
// double: no FFT, no Legendre table, no tensor, so it is independent of every product
// method it checks.
inline std::vector<double> reference_product(int order, const std::vector<std::vector<double>>& f) {
  const int n = sh_count(order);
  const SphereQuadrature q = sphere_quadrature((static_cast<int>(f.size()) + 1) * (order - 1));
  std::vector<long double> g(n, 0.0L);
  std::vector<double> y(n);
  for (std::size_t p = 0; p < q.weights.size(); ++p) {
    eval_sh<double>(order, q.directions[p], y);
    long double v = q.weights[p];
    for (const auto& fi : f) {
      long double s = 0;
      for (int i = 0; i < n; ++i) s += fi[i] * y[i];
      v *= s;
    }
    for (int i = 0; i < n; ++i) g[i] += v * y[i];
  }
  return std::vector<double>(g.begin(), g.end());
}

// Fixed-seed test data, identical on every platform and standard library (unlike the
// <random> distributions).
struct Lcg {
  std::uint64_t s;
  double uniform() {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    return static_cast<double>(s >> 11) * 0x1.0p-53;
  }
  Eigen::Vector3d unit() {
    const double z = 2 * uniform() - 1, p = 2 * std::numbers::pi * uniform(), r = std::sqrt(1 - z * z);
    return {r * std::cos(p), r * std::sin(p), z};
  }
};

// Unit-length SH vector with coefficients uniform in [-1, 1] before normalising (the
// random vectors of [4] Fig. 2).
inline std::vector<double> random_unit_vector(Lcg& rng, int order) {
  std::vector<double> t(sh_count(order));
  double n = 0;
  for (double& x : t) {
    x = 2 * rng.uniform() - 1;
    n += x * x;
  }
  for (double& x : t) x /= std::sqrt(n);
  return t;
}

// Dense M(R) of the reference rotation (block diagonal, n x n).
inline Eigen::MatrixXd reference_matrix(int order, const Mat3<double>& r) {
  ShRotation<double> rotation(order, nullptr);
  EXPECT_TRUE(rotation.set(r, RotationMethod::reference));
  const std::span<const double> blocks = rotation.reference_blocks();
  const int n = sh_count(order);
  Eigen::MatrixXd m = Eigen::MatrixXd::Zero(n, n);
  std::size_t offset = 0;
  for (int l = 0; l < order; ++l) {
    const int size = 2 * l + 1;
    for (int a = 0; a < size; ++a)
      for (int b = 0; b < size; ++b) m(l * l + a, l * l + b) = blocks[offset + a * size + b];
    offset += size * size;
  }
  return m;
}

}  // namespace shtool::test
