// Error of the small-angle Taylor y-rotations against the tilt b: [2] Sec. 3.2 and
// Fig. 3 (orders 5 and 8, b in [0, 40 deg]). For each b the error matrix is
// D(b) = M(Ry(b)) - approximation over the whole order-N vector (block diagonal by
// band), with M(Ry(b)) from the reference (Ivanic-Ruedenberg) rotation; its largest
// singular value is the maximum error over unit-length vectors, and the mean of its
// N^2 singular values is the paper's "average error". The third row of the paper's
// figure, the error for a Phong lobe cos^7, is computed for a unit-length lobe along z.
//
// Besides asserting the properties the paper's figure shows, this test writes the data
// behind docs/rotation-error.png when SHTOOL_WRITE_ERROR_CSV names a file:
//   SHTOOL_WRITE_ERROR_CSV=/tmp/rotation-error.csv build/tests/test_rotation_error_curve
//   /usr/bin/python3 scripts/plot_rotation_error.py /tmp/rotation-error.csv docs/rotation-error.png
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "shtool/euler.h"
#include "shtool/quadrature.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "tensors/rotation_helpers_gen.h"

namespace shtool {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr int kMaxOrderHere = 8;
constexpr RotationMethod kMethods[] = {RotationMethod::taylor1, RotationMethod::taylor15,
                                       RotationMethod::taylor2};

const RotationHelpers& helpers() {
  static const RotationHelpers h = compute_rotation_helpers(kMaxOrderHere);
  return h;
}

Mat3<double> ry(double b) {
  Mat3<double> r;
  r << std::cos(b), 0, std::sin(b), 0, 1, 0, -std::sin(b), 0, std::cos(b);
  return r;
}

// Band-l block of the Taylor approximation ([2] Sec. 3):
// I + b D1 (+ b^2/2 diag(D2) for 1.5th order, + b^2/2 D2 for 2nd order).
Eigen::MatrixXd taylor_block(RotationMethod method, int l, double b) {
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
std::vector<double> phong_lobe(int order) {
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

ErrorPoint error_at(RotationMethod method, int order, double b) {
  ShRotation<double> exact(order, nullptr);
  EXPECT_TRUE(exact.set(ry(b), RotationMethod::reference));
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
double beta_at(int k) { return k * kMaxDegrees / kSteps * kPi / 180; }

using Curve = std::vector<ErrorPoint>;

const std::map<std::pair<int, RotationMethod>, Curve>& curves() {
  static const std::map<std::pair<int, RotationMethod>, Curve> all = [] {
    std::map<std::pair<int, RotationMethod>, Curve> c;
    for (int order : {5, 8})
      for (RotationMethod m : kMethods)
        for (int k = 0; k <= kSteps; ++k) c[{order, m}].push_back(error_at(m, order, beta_at(k)));
    return c;
  }();
  return all;
}

// Rounding of the reference rotation and of the Taylor matrices (entries ~1e-15).
constexpr double kRounding = 1e-13;

TEST(RotationErrorCurve, ZeroAtZeroTiltAndGrowingWithTilt) {
  for (const auto& [key, curve] : curves()) {
    const auto [order, method] = key;
    const std::string what = "N " + std::to_string(order) + " " + std::string(rotation_method_name(method));
    EXPECT_LE(curve[0].max_error, kRounding) << what;
    EXPECT_LE(curve[0].lobe_error, kRounding) << what;
    for (int k = 1; k <= kSteps; ++k) {
      // Max and mean errors never decrease with b: for the 1st and 2nd orders every
      // singular value |e^{i m b} - poly(i m b)| has derivative m b (1 - cos mb) >= 0
      // resp. (m b)^2 / 2 (m b - sin mb) >= 0; the 1.5th order is checked the same way
      // (measured monotone on this range).
      EXPECT_GE(curve[k].max_error, curve[k - 1].max_error - kRounding) << what << " step " << k;
      EXPECT_GE(curve[k].mean_error, curve[k - 1].mean_error - kRounding) << what << " step " << k;
      EXPECT_GT(curve[k].max_error, 0.0) << what;
      EXPECT_LE(curve[k].mean_error, curve[k].max_error + kRounding) << what;
      EXPECT_LE(curve[k].lobe_error, curve[k].max_error + kRounding) << what;
    }
  }
}

TEST(RotationErrorCurve, HigherOrderIsMoreAccurateAtSmallTilt) {
  // 2nd < 1.5th < 1st at every b up to 0.1 rad (5.7 degrees), max and mean error.
  for (int order : {5, 8}) {
    const Curve& c1 = curves().at({order, RotationMethod::taylor1});
    const Curve& c15 = curves().at({order, RotationMethod::taylor15});
    const Curve& c2 = curves().at({order, RotationMethod::taylor2});
    for (int k = 1; beta_at(k) <= 0.1; ++k) {
      EXPECT_LT(c2[k].max_error, c15[k].max_error) << "N " << order << " b " << beta_at(k);
      EXPECT_LT(c15[k].max_error, c1[k].max_error) << "N " << order << " b " << beta_at(k);
      EXPECT_LT(c2[k].mean_error, c15[k].mean_error) << "N " << order << " b " << beta_at(k);
      EXPECT_LT(c15[k].mean_error, c1[k].mean_error) << "N " << order << " b " << beta_at(k);
    }
  }
  // At b = 0.1 rad exactly.
  for (int order : {5, 8}) {
    const double e1 = error_at(RotationMethod::taylor1, order, 0.1).max_error;
    const double e15 = error_at(RotationMethod::taylor15, order, 0.1).max_error;
    const double e2 = error_at(RotationMethod::taylor2, order, 0.1).max_error;
    EXPECT_LT(e2, e15) << order;
    EXPECT_LT(e15, e1) << order;
    // Closed forms at t = 0.1 (N - 1): |e^{it} - 1 - it| and |e^{it} - 1 - it + t^2/2|.
    const double t = 0.1 * (order - 1);
    EXPECT_NEAR(e1, std::hypot(std::cos(t) - 1, std::sin(t) - t), 1e-13) << order;
    EXPECT_NEAR(e2, std::hypot(std::cos(t) - 1 + t * t / 2, std::sin(t) - t), 1e-13) << order;
  }
}

TEST(RotationErrorCurve, MaxErrorEqualsTheRuntimeBoundForFirstAndSecondOrder) {
  for (const auto& [key, curve] : curves()) {
    const auto [order, method] = key;
    if (method == RotationMethod::taylor15) continue;
    for (int k = 0; k <= kSteps; ++k)
      EXPECT_NEAR(curve[k].max_error, taylor_error_bound(method, order, beta_at(k)),
                  1e-12 * curve[k].max_error + kRounding)
          << "N " << order << " " << rotation_method_name(method) << " b " << beta_at(k);
  }
}

TEST(RotationErrorCurve, WriteCsvWhenAsked) {
  const char* path = std::getenv("SHTOOL_WRITE_ERROR_CSV");
  if (!path || !*path) GTEST_SKIP() << "set SHTOOL_WRITE_ERROR_CSV=FILE to write the figure data";
  std::ofstream out(path);
  ASSERT_TRUE(out) << "cannot write " << path;
  out << "order,method,beta_deg,max_error,mean_error,phong7_error\n";
  char line[256];
  for (const auto& [key, curve] : curves()) {
    const auto [order, method] = key;
    for (int k = 0; k <= kSteps; ++k) {
      std::snprintf(line, sizeof line, "%d,%s,%.17g,%.17g,%.17g,%.17g\n", order,
                    std::string(rotation_method_name(method)).c_str(), k * kMaxDegrees / kSteps,
                    curve[k].max_error, curve[k].mean_error, curve[k].lobe_error);
      out << line;
    }
  }
  ASSERT_TRUE(out.good());
}

}  // namespace
}  // namespace shtool
