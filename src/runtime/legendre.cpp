#include "shtool/legendre.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>

#include "shtool/sh.h"

namespace shtool {
namespace {

// Q_l^m(z) = K_l^m P_l^m(z) / sin^m t and dQ/dz, by the recurrence in l documented
// in sh.cpp (here in double only, off the hot path).
void q_and_derivative(int l, int m, double z, double& q, double& dq) {
  double qmm = 0.5 / std::sqrt(std::numbers::pi);
  for (int k = 1; k <= m; ++k) qmm *= -std::sqrt((2.0 * k + 1.0) / (2.0 * k));
  double q2 = 0, dq2 = 0, q1 = qmm, dq1 = 0;
  for (int k = m + 1; k <= l; ++k) {
    const double kk = k, mm = m;
    const double a = std::sqrt((4 * kk * kk - 1) / (kk * kk - mm * mm));
    const double b = std::sqrt(((kk - 1) * (kk - 1) - mm * mm) / (4 * (kk - 1) * (kk - 1) - 1));
    const double q0 = a * (z * q1 - b * q2);
    const double dq0 = a * (q1 + z * dq1 - b * dq2);
    q2 = q1;
    dq2 = dq1;
    q1 = q0;
    dq1 = dq0;
  }
  q = q1;
  dq = dq1;
}

}  // namespace

double normalized_legendre(int l, int m, double theta) {
  double q, dq;
  q_and_derivative(l, m, std::cos(theta), q, dq);
  return q * std::pow(std::sin(theta), m);
}

void normalized_legendre_all(int order, long double z, long double s, long double p00, std::span<long double> out) {
  long double diag = p00;  // Q_m^m sin^m t, carried along the diagonal
  for (int m = 0; m < order; ++m) {
    if (m > 0) diag *= -std::sqrt((2.0L * m + 1.0L) / (2.0L * m)) * s;
    long double p2 = 0, p1 = diag;
    out[static_cast<std::size_t>(m) * (m + 1) / 2 + m] = p1;
    for (int l = m + 1; l < order; ++l) {
      long double p;
      if (l == m + 1) {
        p = std::sqrt(2.0L * m + 3.0L) * z * p1;
      } else {
        const long double ld = l, md = m;
        const long double a = std::sqrt((4 * ld * ld - 1) / (ld * ld - md * md));
        const long double b = std::sqrt(((ld - 1) * (ld - 1) - md * md) / (4 * (ld - 1) * (ld - 1) - 1));
        p = a * (z * p1 - b * p2);
      }
      out[static_cast<std::size_t>(l) * (l + 1) / 2 + m] = p;
      p2 = p1;
      p1 = p;
    }
  }
}

std::vector<double> legendre_zeros(int l, int m) {
  const int n = l - m;
  std::vector<double> zeros;
  if (n <= 0) return zeros;
  // Golub-Welsch: the zeros of the orthonormal polynomial Q_l^m in z are the
  // eigenvalues of its symmetric Jacobi matrix, whose off-diagonal entries are
  // 1 / a_k^m = sqrt((k^2 - m^2) / (4k^2 - 1)) for k = m+1 .. l-1 (diagonal zero,
  // since the weight (1 - z^2)^m is even).
  Eigen::VectorXd diag = Eigen::VectorXd::Zero(n);
  Eigen::VectorXd sub(std::max(n - 1, 0));
  for (int j = 0; j + 1 < n; ++j) {
    const double k = m + 1 + j;
    sub[j] = std::sqrt((k * k - double(m) * m) / (4 * k * k - 1));
  }
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver;
  solver.computeFromTridiagonal(diag, sub, Eigen::EigenvaluesOnly);
  const Eigen::VectorXd z = solver.eigenvalues();
  zeros.reserve(n);
  for (int j = 0; j < n; ++j) {
    // Polish with Newton in t: f(t) = Q(cos t), f'(t) = -sin t Q'(cos t). Working in t
    // keeps full relative accuracy near the poles, where z = cos t is ill-conditioned.
    const double zj = std::clamp(z[j], -1.0, 1.0);
    double t = std::atan2(std::sqrt((1.0 - zj) * (1.0 + zj)), zj);
    for (int iter = 0; iter < 20; ++iter) {
      double q, dq;
      q_and_derivative(l, m, std::cos(t), q, dq);
      const double step = q / (-std::sin(t) * dq);
      t -= step;
      if (std::abs(step) < 1e-17) break;
    }
    zeros.push_back(t);
  }
  std::sort(zeros.begin(), zeros.end());
  return zeros;
}

}  // namespace shtool
