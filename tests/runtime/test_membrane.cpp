// The thin-membrane model ([4] Eq. 22-23) against a direct quadrature of Eq. 22: for a
// band-limited light L of order n, (1/pi) integral g(s . z) L(s) ds, the integrand split at
// the horizon (where g has its kink) and each hemisphere integrated by Gauss-Legendre in
// s . z (exact for the polynomial pieces) times a uniform azimuth rule, about the normal.
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "shtool/membrane.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"
#include "shtool/zh_shading.h"

namespace {

using namespace shtool;

// (1/pi) integral over the sphere of g(s . normal) L(s), L = sum light_i y_i.
double membrane_quadrature(int n, const std::vector<double>& light, const Eigen::Vector3d& normal, double alpha) {
  const GaussLegendre gl = gauss_legendre(n + 2);
  const int azimuths = 2 * n + 2;
  Eigen::Vector3d t = normal.unitOrthogonal(), b = normal.cross(t);
  std::vector<double> y(n * n);
  double sum = 0;
  for (int half = 0; half < 2; ++half)  // s . normal in [0, 1], then [-1, 0]
    for (std::size_t k = 0; k < gl.nodes.size(); ++k) {
      const double c = half == 0 ? 0.5 * (gl.nodes[k] + 1) : 0.5 * (gl.nodes[k] - 1);
      const double w = 0.5 * gl.weights[k], sine = std::sqrt(std::max(0.0, 1 - c * c));
      const double g = c >= 0 ? c : -alpha * c;  // Eq. 22
      for (int a = 0; a < azimuths; ++a) {
        const double p = 2 * std::numbers::pi * (a + 0.5) / azimuths;
        const Eigen::Vector3d s = c * normal + sine * (std::cos(p) * t + std::sin(p) * b);
        eval_sh<double>(n, s, y);
        double l = 0;
        for (int i = 0; i < n * n; ++i) l += light[i] * y[i];
        sum += w * (2 * std::numbers::pi / azimuths) * g * l;
      }
    }
  return sum / std::numbers::pi;
}

TEST(Membrane, SingleLobeEqualsTheQuadratureOfEq22) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  std::normal_distribution<double> g;
  for (int n : {1, 2, 3, 4, 6, 9}) {
    for (double alpha : {0.0, 0.3, 1.0}) {
      for (int trial = 0; trial < 5; ++trial) {
        std::vector<double> light(n * n);
        for (double& v : light) v = u(rng);
        const Eigen::Vector3d normal = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
        std::vector<double> lobe(n);
        membrane_lobe(alpha, lobe);
        const std::vector<Vec3<double>> axes = {normal};
        const double r = zh_shade_exact<double>(light, axes, lobe);
        const double q = membrane_quadrature(n, light, normal, alpha);
        EXPECT_NEAR(r, q, 1e-13 * (1 + std::abs(q))) << "n " << n << " alpha " << alpha;
      }
    }
  }
}

// Eq. 23 as printed, term by term.
TEST(Membrane, CoefficientsAsEq23Prints) {
  const double alpha = 0.4;
  std::vector<double> lobe(8);
  membrane_lobe(alpha, lobe);
  EXPECT_NEAR(lobe[0], 1 + alpha, 1e-15);
  EXPECT_NEAR(lobe[1], 2.0 / 3.0 * (1 - alpha), 1e-15);
  for (int l = 2; l < 8; ++l) {
    if (l % 2) {
      EXPECT_EQ(lobe[l], 0.0) << l;
      continue;
    }
    const double fact = std::tgamma(l + 1.0), half = std::tgamma(l / 2 + 1.0);
    const double printed = 2 * (1 + alpha) * std::pow(-1.0, l / 2 - 1) / ((l + 2.0) * (l - 1.0)) * fact /
                           (std::pow(2.0, l) * half * half);
    EXPECT_NEAR(lobe[l], printed, 1e-15) << l;
  }
}

// Under constant radiance 1 the membrane returns 1 + alpha (front and back cosine lobes).
TEST(Membrane, ConstantLightGivesOnePlusAlpha) {
  for (double alpha : {0.0, 0.5, 1.0}) {
    std::vector<double> light(16, 0.0);
    light[0] = std::sqrt(4 * std::numbers::pi);
    std::vector<double> lobe(4);
    membrane_lobe(alpha, lobe);
    const std::vector<Vec3<double>> axes = {Vec3<double>(0.6, 0, 0.8)};
    EXPECT_NEAR(zh_shade_exact<double>(light, axes, lobe), 1 + alpha, 1e-14);
  }
}

}  // namespace
