#include "tensors/rotation_helpers_gen.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "shtool/euler.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

constexpr double kStructuralZero = 1e-13;

}  // namespace

RotationHelpers compute_rotation_helpers(int order) {
  if (!is_supported_order(order)) throw std::invalid_argument("unsupported order " + std::to_string(order));
  const int n = sh_count(order);
  // Rx(+90): y -> z, z -> -y. g(w) = f(R^-1 w) gives X[i][j] = integral y_i(w) y_j(R^-1 w).
  Mat3<double> rx;
  rx << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  const Mat3<double> rx_inv = rx.transpose();
  const SphereQuadrature q = sphere_quadrature(2 * order - 2);
  // Accumulated in long double: the sums run over ~2 N^2 nodes and a double sum would
  // leave errors of ~1e-14 on exact values such as X90[0][0] = 1.
  using Accum = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  std::vector<Accum> sums(order);
  for (int l = 0; l < order; ++l) sums[l] = Accum::Zero(2 * l + 1, 2 * l + 1);
  std::vector<double> yw(n), yr(n);
  for (std::size_t k = 0; k < q.directions.size(); ++k) {
    eval_sh<double>(order, q.directions[k], yw);
    eval_sh<double>(order, rx_inv * q.directions[k], yr);
    for (int l = 0; l < order; ++l)
      for (int a = 0; a <= 2 * l; ++a)
        for (int b = 0; b <= 2 * l; ++b)
          sums[l](a, b) += static_cast<long double>(q.weights[k] * yw[l * l + a]) * yr[l * l + b];
  }
  std::vector<Eigen::MatrixXd> x90(order);
  for (int l = 0; l < order; ++l) x90[l] = sums[l].cast<double>();

  RotationHelpers h;
  h.order = order;
  h.x90_row.assign(n + 1, 0);
  h.dy_sub.assign(n, 0.0);
  h.ddy_diag.assign(n, 0.0);
  h.ddy_off2.assign(n, 0.0);
  for (int l = 0; l < order; ++l) {
    const int size = 2 * l + 1, first = l * l;
    for (int a = 0; a < size; ++a) {
      for (int b = 0; b < size; ++b) {
        const double v = x90[l](a, b);
        if (std::abs(v) < kStructuralZero) continue;
        h.x90_col.push_back(first + b);
        h.x90_val.push_back(v);
      }
      h.x90_row[first + a + 1] = static_cast<int>(h.x90_col.size());
    }
    // Generator of z-rotations in band l: d/da of (f_m, f_-m) -> (-m f_-m, m f_m).
    Eigen::MatrixXd gz = Eigen::MatrixXd::Zero(size, size);
    for (int m = 1; m <= l; ++m) {
      gz(l + m, l - m) = -m;
      gz(l - m, l + m) = m;
    }
    const Eigen::MatrixXd d1 = x90[l].transpose() * gz * x90[l];
    const Eigen::MatrixXd d2 = d1 * d1;
    for (int a = 0; a < size; ++a) {
      for (int b = 0; b < size; ++b) {
        const bool in_d1 = std::abs(a - b) == 1;
        const bool in_d2 = a == b || std::abs(a - b) == 2;
        if (!in_d1 && std::abs(d1(a, b)) > 1e-10)
          throw std::logic_error("D1 not tridiagonal in band " + std::to_string(l));
        if (!in_d2 && std::abs(d2(a, b)) > 1e-10)
          throw std::logic_error("D2 has entries off its three diagonals in band " + std::to_string(l));
      }
      if (a > 0) {
        const double v = d1(a, a - 1);
        h.dy_sub[first + a] = std::abs(v) < kStructuralZero ? 0.0 : v;
      }
      h.ddy_diag[first + a] = d2(a, a);
      if (a > 1) {
        const double v = d2(a, a - 2);
        h.ddy_off2[first + a] = std::abs(v) < kStructuralZero ? 0.0 : v;
      }
    }
  }
  return h;
}

}  // namespace shtool
