#include "shtool/quadrature.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace shtool {

namespace {

// P_n(x) and P_n'(x) by the three-term recurrence (n >= 1). In long double: near
// x = +-1 the recurrence carries ~n^2/6 ulp of noise, which the weight formula would
// pass on to the small outer weights (3e-13 relative at n = 200 in double).
void legendre_and_derivative(int n, long double x, long double& pn, long double& dpn) {
  long double p0 = 1.0L, p1 = x;
  for (int k = 2; k <= n; ++k) {
    const long double pk = ((2.0L * k - 1.0L) * x * p1 - (k - 1.0L) * p0) / k;
    p0 = p1;
    p1 = pk;
  }
  pn = p1;
  dpn = n * (x * p1 - p0) / (x * x - 1.0L);
}

}  // namespace

GaussLegendre gauss_legendre(int n) {
  GaussLegendre rule;
  rule.nodes.assign(n, 0.0);
  rule.weights.assign(n, 0.0);
  for (int i = 0; i < (n + 1) / 2; ++i) {
    // Tricomi's approximation of the (i+1)-th largest root, then Newton on P_n.
    long double x = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
    long double pn = 0, dpn = 1;
    for (int iter = 0; iter < 100; ++iter) {
      legendre_and_derivative(n, x, pn, dpn);
      const long double dx = pn / dpn;
      x -= dx;
      if (std::abs(dx) <= 1e-19L) break;
    }
    legendre_and_derivative(n, x, pn, dpn);
    // Standard Gauss-Legendre weight.
    const double w = static_cast<double>(2.0L / ((1.0L - x * x) * dpn * dpn));
    rule.nodes[n - 1 - i] = static_cast<double>(x);
    rule.nodes[i] = -static_cast<double>(x);
    rule.weights[n - 1 - i] = w;
    rule.weights[i] = w;
  }
  if (n % 2 == 1) rule.nodes[n / 2] = 0.0;
  return rule;
}

SphereQuadrature sphere_quadrature(int degree) {
  const int nz = degree / 2 + 1;  // ceil((degree + 1) / 2)
  const int np = degree + 1;
  const GaussLegendre gl = gauss_legendre(nz);
  SphereQuadrature q;
  q.directions.reserve(static_cast<std::size_t>(nz) * np);
  q.weights.reserve(static_cast<std::size_t>(nz) * np);
  const double dphi = 2.0 * std::numbers::pi / np;
  for (int i = 0; i < nz; ++i) {
    const double z = gl.nodes[i];
    const double s = std::sqrt((1.0 - z) * (1.0 + z));
    for (int j = 0; j < np; ++j) {
      const double p = dphi * j;
      q.directions.emplace_back(s * std::cos(p), s * std::sin(p), z);
      q.weights.push_back(gl.weights[i] * dphi);
    }
  }
  return q;
}

std::vector<double> project_sh(int order, const std::function<double(const Vec3<double>&)>& f,
                               int exact_order) {
  const int n = sh_count(order);
  const int exact = std::max(order, exact_order);
  const SphereQuadrature q = sphere_quadrature(order + exact - 2);
  std::vector<double> coeffs(n, 0.0), basis(n);
  for (std::size_t k = 0; k < q.directions.size(); ++k) {
    const double fw = f(q.directions[k]) * q.weights[k];
    eval_sh<double>(order, q.directions[k], basis);
    for (int i = 0; i < n; ++i) coeffs[i] += fw * basis[i];
  }
  return coeffs;
}

}  // namespace shtool
