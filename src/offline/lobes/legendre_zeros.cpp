#include "lobes/legendre_zeros.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>

#include "basis/legendre_recurrence.h"

namespace shtool {

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
      detail::legendre_q_and_derivative(l, m, std::cos(t), q, dq);
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
