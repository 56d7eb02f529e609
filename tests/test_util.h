// Small helpers shared by the test programs (header-only; each test is its own program).
#pragma once

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool::test {

// Random SH coefficients uniform in [-1, 1] (the papers' test vectors).
inline std::vector<double> random_coeffs(int order, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> f(sh_count(order));
  for (double& v : f) v = u(rng);
  return f;
}

// Euclidean norm of a coefficient vector.
inline double norm(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return std::sqrt(s);
}

// Property values in scientific notation (std::to_string would print 0.000000).
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

}  // namespace shtool::test
