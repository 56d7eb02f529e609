// Small helpers shared by the test programs (header-only; each test is its own program).
#pragma once

#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

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

}  // namespace shtool::test
