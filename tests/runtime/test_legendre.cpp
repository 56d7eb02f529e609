// Values of the normalised associated Legendre functions (include/shtool/legendre.h)
// against closed forms, std::sph_legendre and eval_sh.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "shtool/legendre.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

constexpr double kPi = std::numbers::pi;

TEST(NormalizedLegendre, ClosedFormsAndConventions) {
  for (double t : {0.0, 0.2, 1.0, kPi / 2, 2.5, kPi}) {
    const double c = std::cos(t), s = std::sin(t);
    // Values are O(1); closed forms and recurrence agree to a few ulp.
    constexpr double kTol = 4e-16;
    EXPECT_NEAR(normalized_legendre(0, 0, t), 0.5 / std::sqrt(kPi), kTol);
    EXPECT_NEAR(normalized_legendre(1, 0, t), std::sqrt(3 / (4 * kPi)) * c, kTol);
    // Condon-Shortley phase: negative for 0 < t < pi.
    EXPECT_NEAR(normalized_legendre(1, 1, t), -std::sqrt(3 / (8 * kPi)) * s, kTol) << "t " << t;
    EXPECT_NEAR(normalized_legendre(2, 0, t), std::sqrt(5 / (16 * kPi)) * (3 * c * c - 1), kTol);
    EXPECT_NEAR(normalized_legendre(2, 1, t), -std::sqrt(15 / (8 * kPi)) * s * c, kTol);
    EXPECT_NEAR(normalized_legendre(2, 2, t), std::sqrt(15 / (32 * kPi)) * s * s, kTol);
    EXPECT_NEAR(normalized_legendre(3, 3, t), -std::sqrt(35 / (64 * kPi)) * s * s * s, kTol);
  }
}

TEST(NormalizedLegendre, MatchesStdSphLegendreAndEvalSh) {
  // std::sph_legendre(l, m, t) is K_l^m P_l^m(cos t) with the Condon-Shortley phase; and
  // y_l^m at azimuth 0 is sqrt2 times it (m > 0). Angles are kept off the poles, where
  // std::sph_legendre loses precision (it forms sin t as sqrt(1 - cos^2 t)).
  const int order = 31;
  std::vector<double> y(sh_count(order));
  for (double t : {0.05, 0.3, 1.0, 1.5707, 2.0, 3.0}) {
    eval_sh<double>(order, direction_from_angles(t, 0.0), y);
    for (int l = 0; l < order; ++l)
      for (int m = 0; m <= l; ++m) {
        const double v = normalized_legendre(l, m, t);
        // Both run recurrences in l; (4 + l^2/3) ulp of the band scale bounds each one
        // (the budget derived in test_sh.cpp), so twice that for the difference.
        const double scale = std::sqrt((2.0 * l + 1) / (4 * kPi));
        const double tol = 2 * (4.0 + l * l / 3.0) * 2.220446049250313e-16 * scale;
        EXPECT_NEAR(v, std::sph_legendre(l, m, t), tol) << "l " << l << " m " << m << " t " << t;
        EXPECT_NEAR(y[sh_index(l, m)], (m ? std::sqrt(2.0) : 1.0) * v, tol)
            << "l " << l << " m " << m << " t " << t;
      }
  }
}

TEST(NormalizedLegendre, AllAtOnePointMatchesStdSphLegendre) {
  // normalized_legendre_all (long double, the table builders' recurrence) against
  // std::sph_legendre, with p00 = 1/sqrt(4 pi) (plain K_l^m P_l^m) and a second scale
  // that must multiply every value; exact zeros for m > 0 at the poles.
  const int order = 31;
  std::vector<long double> out(order * (order + 1) / 2);
  for (double t : {0.05, 0.3, 1.0, 1.5707, 2.0, 3.0}) {
    const long double p00 = 0.5L / std::sqrt(std::numbers::pi_v<long double>);
    normalized_legendre_all(order, std::cos(static_cast<long double>(t)), std::sin(static_cast<long double>(t)), p00, out);
    std::vector<long double> scaled(out.size());
    normalized_legendre_all(order, std::cos(static_cast<long double>(t)), std::sin(static_cast<long double>(t)),
                            3 * p00, scaled);
    for (int l = 0; l < order; ++l)
      for (int m = 0; m <= l; ++m) {
        const std::size_t k = static_cast<std::size_t>(l) * (l + 1) / 2 + m;
        // std::sph_legendre's own error dominates: the budget of the test above.
        const double scale = std::sqrt((2.0 * l + 1) / (4 * kPi));
        const double tol = 2 * (4.0 + l * l / 3.0) * 2.220446049250313e-16 * scale;
        EXPECT_NEAR(static_cast<double>(out[k]), std::sph_legendre(l, m, t), tol) << "l " << l << " m " << m << " t " << t;
        EXPECT_NEAR(static_cast<double>(scaled[k]), 3 * static_cast<double>(out[k]), 1e-15 * scale) << "l " << l << " m " << m;
      }
  }
  for (long double z : {1.0L, -1.0L}) {
    normalized_legendre_all(order, z, 0.0L, 1.0L, out);
    for (int l = 0; l < order; ++l)
      for (int m = 1; m <= l; ++m) EXPECT_EQ(out[static_cast<std::size_t>(l) * (l + 1) / 2 + m], 0.0L) << l << " " << m;
  }
}

}  // namespace
}  // namespace shtool
