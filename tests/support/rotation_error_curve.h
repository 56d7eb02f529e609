// The error of the small-angle Taylor y-rotations against the tilt b ([2] Sec. 3.2 and
// Fig. 3, orders 5 and 8, b in [0, 40 deg]), shared by the test that asserts the
// figure's properties (tests/offline/test_rotation_error_curve.cpp) and the program that
// writes its data (scripts/rotation_error_csv.cpp, run by scripts/plot_rotation_error.sh).
// For each b the error matrix is D(b) = M(Ry(b)) - approximation over the whole order-N
// vector (block diagonal by band), with M(Ry(b)) from the reference (Ivanic-Ruedenberg)
// rotation; its largest singular value is the maximum error over unit-length vectors, and
// the mean of its N^2 singular values is the paper's "average error". The third row of
// the figure, the error for a Phong lobe cos^7, is computed for a unit-length lobe along z.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <stdexcept>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "shtool/euler.h"
#include "shtool/quadrature.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "tensors/rotation_helpers_gen.h"

namespace shtool::error_curve {

inline constexpr double kPi = std::numbers::pi;
inline constexpr int kMaxOrderHere = 8;
inline constexpr RotationMethod kMethods[] = {RotationMethod::taylor1, RotationMethod::taylor15,
                                       RotationMethod::taylor2};

inline const RotationHelpers& helpers() {
  static const RotationHelpers h = compute_rotation_helpers(kMaxOrderHere);
  return h;
}

inline Mat3<double> ry(double b) {
  Mat3<double> r;
  r << std::cos(b), 0, std::sin(b), 0, 1, 0, -std::sin(b), 0, std::cos(b);
  return r;
}

// Band-l block of the Taylor approximation ([2] Sec. 3):
// I + b D1 (+ b^2/2 diag(D2) for 1.5th order, + b^2/2 D2 for 2nd order).
inline Eigen::MatrixXd taylor_block(RotationMethod method, int l, double b) {
  const RotationHelpers& h = helpers();
  const int size = 2 * l + 1, first = l * l;
  Eigen::MatrixXd d1 = Eigen::MatrixXd::Zero(size, size), d2 = Eigen::MatrixXd::Zero(size, size);
  for (int a = 0; a < size; ++a) {
    if (a > 0) {
      d1(a, a - 1) = h.dy_sub[first + a];
      d1(a - 1, a) = -h.dy_sub[first + a];
    }
    d2(a, a) = h.ddy_diag[first + a];
    if (a > 1) d2(a, a - 2) = d2(a - 2, a) = h.ddy_off2[first + a];
  }
  Eigen::MatrixXd t = Eigen::MatrixXd::Identity(size, size) + b * d1;
  if (method == RotationMethod::taylor15) t += 0.5 * b * b * Eigen::MatrixXd(d2.diagonal().asDiagonal());
  if (method == RotationMethod::taylor2) t += 0.5 * b * b * d2;
  return t;
}

// Unit-length SH vector of the Phong lobe max(cos t, 0)^7 around z: only m = 0 terms,
// f_l = 2 pi sqrt((2l+1)/(4 pi)) int_0^1 x^7 P_l(x) dx, integrated exactly by 16-point
// Gauss-Legendre on [0, 1] (the integrand is a polynomial of degree <= 7 + 7).
inline std::vector<double> phong_lobe(int order) {
  const GaussLegendre gl = gauss_legendre(16);
  std::vector<double> f(sh_count(order), 0.0);
  for (std::size_t k = 0; k < gl.nodes.size(); ++k) {
    const double x = 0.5 * (gl.nodes[k] + 1), w = 0.5 * gl.weights[k];
    double p0 = 1, p1 = x;  // Bonnet recurrence for P_l(x)
    for (int l = 0; l < order; ++l) {
      const double pl = l == 0 ? p0 : p1;
      f[sh_index(l, 0)] += 2 * kPi * std::sqrt((2 * l + 1) / (4 * kPi)) * w * std::pow(x, 7) * pl;
      if (l >= 1) {
        const double next = ((2 * l + 1) * x * p1 - l * p0) / (l + 1);
        p0 = p1;
        p1 = next;
      }
    }
  }
  double n = 0;
  for (double v : f) n += v * v;
  for (double& v : f) v /= std::sqrt(n);
  return f;
}

struct ErrorPoint {
  double max_error = 0, mean_error = 0, lobe_error = 0;
};

inline ErrorPoint error_at(RotationMethod method, int order, double b) {
  ShRotation<double> exact(order, nullptr);
  if (!exact.set(ry(b), RotationMethod::reference)) throw std::logic_error("the reference rotation refused Ry(b)");
  const std::span<const double> blocks = exact.reference_blocks();
  const std::vector<double> lobe = phong_lobe(order);
  ErrorPoint p;
  double sum = 0, lobe2 = 0;
  std::size_t offset = 0;
  for (int l = 0; l < order; ++l) {
    const int size = 2 * l + 1;
    Eigen::MatrixXd m(size, size);
    for (int a = 0; a < size; ++a)
      for (int c = 0; c < size; ++c) m(a, c) = blocks[offset + a * size + c];
    offset += size * size;
    const Eigen::MatrixXd e = m - taylor_block(method, l, b);
    // Singular values of a block-diagonal matrix: the union of the blocks' ones.
    const Eigen::VectorXd s = Eigen::JacobiSVD<Eigen::MatrixXd>(e).singularValues();
    p.max_error = std::max(p.max_error, s.maxCoeff());
    sum += s.sum();
    const Eigen::VectorXd fl = Eigen::Map<const Eigen::VectorXd>(lobe.data() + l * l, size);
    lobe2 += (e * fl).squaredNorm();
  }
  p.mean_error = sum / sh_count(order);
  p.lobe_error = std::sqrt(lobe2);
  return p;
}

// b = 0, 0.5, ..., 40 degrees, as in the paper's figure.
constexpr int kSteps = 80;
constexpr double kMaxDegrees = 40.0;
inline double beta_at(int k) { return k * kMaxDegrees / kSteps * kPi / 180; }

using Curve = std::vector<ErrorPoint>;

inline const std::map<std::pair<int, RotationMethod>, Curve>& curves() {
  static const std::map<std::pair<int, RotationMethod>, Curve> all = [] {
    std::map<std::pair<int, RotationMethod>, Curve> c;
    for (int order : {5, 8})
      for (RotationMethod m : kMethods)
        for (int k = 0; k <= kSteps; ++k) c[{order, m}].push_back(error_at(m, order, beta_at(k)));
    return c;
  }();
  return all;
}

}  // namespace shtool::error_curve
