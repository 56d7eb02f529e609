// The properties [2] Fig. 3 shows for the small-angle Taylor rotations, asserted on the
// curves of tests/support/rotation_error_curve.h (the figure's data itself is written by
// scripts/plot_rotation_error.sh).
#include <cmath>

#include <gtest/gtest.h>

#include "rotation_error_curve.h"

namespace shtool {
namespace {

using namespace error_curve;

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

}  // namespace
}  // namespace shtool
