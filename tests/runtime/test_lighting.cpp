// Analytic lights, the clamped-cosine kernel and the windows, against closed forms and
// quadrature.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "shtool/analytic_lights.h"
#include "shtool/irradiance.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"
#include "shtool/sh_window.h"
#include "test_util.h"

namespace shtool {
namespace {

constexpr double kPi = std::numbers::pi;

using test::legendre_p;

// integral_a^b f(x) dx by a 64-node Gauss rule (exact for the polynomials used here).
template <class F>
double integrate(F f, double a, double b) {
  static const GaussLegendre g = gauss_legendre(64);
  double s = 0;
  for (std::size_t i = 0; i < g.nodes.size(); ++i) s += g.weights[i] * f((a + b) / 2 + (b - a) / 2 * g.nodes[i]);
  return s * (b - a) / 2;
}

TEST(ClampedCosine, ClosedFormsAndFunkHecke) {
  EXPECT_DOUBLE_EQ(clamped_cosine_band(0), kPi);
  EXPECT_DOUBLE_EQ(clamped_cosine_band(1), 2 * kPi / 3);
  EXPECT_DOUBLE_EQ(clamped_cosine_band(2), kPi / 4);
  EXPECT_EQ(clamped_cosine_band(3), 0.0);
  EXPECT_NEAR(clamped_cosine_band(4), -kPi / 24, 1e-16);
  // Funk-Hecke: A_l = 2 pi integral_0^1 z P_l(z) dz.
  for (int l = 0; l < 40; ++l) {
    const double ref = 2 * kPi * integrate([l](double z) { return z * legendre_p(l, z); }, 0, 1);
    EXPECT_NEAR(clamped_cosine_band(l), ref, 1e-14) << "l " << l;
  }
}

TEST(ClampedCosine, UniformIrradianceIsPi) {
  std::vector<double> c(9, 0.0);
  const double one = 1;
  add_constant_light({&one, 1}, 1, c);
  radiance_to_irradiance(1, c);
  EXPECT_NEAR(reconstruct<double>(c, Eigen::Vector3d(0.6, 0, 0.8)), kPi, 1e-15);
}

TEST(AnalyticLights, ConeAgainstQuadratureAndTheDirectionalLimit) {
  const int order = 10;
  for (double a : {0.01, 0.3, 1.0, kPi / 2, 2.5}) {
    const std::vector<double> z = cap_zonal_coefficients(a, order);
    for (int l = 0; l < order; ++l) {
      const double ref = 2 * kPi * integrate([l](double x) { return legendre_p(l, x); }, std::cos(a), 1);
      EXPECT_NEAR(z[l], ref, 1e-13) << "a " << a << " l " << l;
    }
  }
  // Projected by quadrature of the cap's indicator along a tilted axis: the cone light
  // is the cap turned to d (smooth enough at this order for a rule of high degree).
  const Eigen::Vector3d d = Eigen::Vector3d(0.3, -0.5, 0.81).normalized();
  std::vector<double> cone(sh_count(4), 0.0);
  const double red = 2.0;
  add_cone_light(d, 0.7, {&red, 1}, 1, cone);
  const std::vector<double> ref = project_sh(
      4, [&](const Eigen::Vector3d& w) { return w.dot(d) >= std::cos(0.7) ? 2.0 : 0.0; }, 800);
  for (int i = 0; i < sh_count(4); ++i) EXPECT_NEAR(cone[i], ref[i], 2e-3) << i;
  // As the cone shrinks, cone / solid angle -> directional light.
  std::vector<double> dir(sh_count(order), 0.0);
  const double one = 1;
  add_directional_light(d, {&one, 1}, 1, dir);
  // Down to caps whose 1 - cos a is below double's epsilon (the sun is 4.7e-3 rad; a
  // CLI's --half-angle 1e-6 degrees is 1.7e-8 rad): the band sums once cancelled there.
  for (double a : {1e-2, 1e-3, 1e-4, 1e-6, 1.7e-8, 1e-12}) {
    std::vector<double> c(sh_count(order), 0.0);
    add_cone_light(d, a, {&one, 1}, 1, c);
    const double solid = 4 * kPi * std::pow(std::sin(a / 2), 2);
    double err = 0;
    for (int i = 0; i < sh_count(order); ++i) err = std::max(err, std::abs(c[i] / solid - dir[i]));
    EXPECT_LT(err, 10 * a * a * order * order + 1e-13) << "a " << a;
  }
}

TEST(AnalyticLights, HemisphereAndConstant) {
  const Eigen::Vector3d d = Eigen::Vector3d(0, 0, 1);
  const double sky[3] = {1, 2, 3}, ground[3] = {0.5, 0.5, 0.5};
  std::vector<double> c(sh_count(8) * 3, 0.0);
  add_hemisphere_light(d, sky, ground, 3, c);
  // The mean is the average of sky and ground; odd zonal bands only, apart from l = 0.
  for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(c[ch], (sky[ch] + ground[ch]) / 2 * std::sqrt(4 * kPi), 1e-14);
  for (int l = 2; l < 8; l += 2) EXPECT_NEAR(c[sh_index(l, 0) * 3], 0.0, 1e-15) << l;
  std::vector<double> same(sh_count(8) * 3, 0.0), constant(sh_count(8) * 3, 0.0);
  add_hemisphere_light(d, ground, ground, 3, same);
  add_constant_light(ground, 3, constant);
  for (std::size_t i = 0; i < same.size(); ++i) EXPECT_NEAR(same[i], constant[i], 1e-15);
}

TEST(Windows, FactorsFollowTheirFormulas) {
  const std::vector<double> h = sh_window_factors(ShWindow::hann, 4, 6);
  EXPECT_DOUBLE_EQ(h[0], 1);
  EXPECT_NEAR(h[2], 0.5, 1e-16);
  EXPECT_EQ(h[4], 0.0);
  EXPECT_EQ(h[5], 0.0);
  const std::vector<double> l = sh_window_factors(ShWindow::lanczos, 3, 3);
  EXPECT_NEAR(l[1], std::sin(kPi / 3) / (kPi / 3), 1e-16);
  const std::vector<double> s = sh_window_factors(ShWindow::sinc4, 3, 3);
  EXPECT_NEAR(s[1], std::pow(std::sin(kPi / 3) / (kPi / 3), 4), 1e-16);
  for (double v : sh_window_factors(ShWindow::none, 2, 5)) EXPECT_EQ(v, 1.0);
}

TEST(Windows, MinimumSearchFindsTheMinimum) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n;
  for (int order : {2, 5, 8}) {
    std::vector<double> c(sh_count(order));
    for (double& v : c) v = n(rng);
    const ShMinimum m = sh_minimum(c, 1, 0);
    EXPECT_NEAR(reconstruct<double>(c, m.direction), m.value, 1e-12);
    // No point of a much denser random set is lower (beyond rounding).
    std::uniform_real_distribution<double> u(-1, 1);
    for (int k = 0; k < 200000; ++k) {
      const Eigen::Vector3d w = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
      ASSERT_GE(reconstruct<double>(c, w), m.value - 1e-10) << "order " << order;
    }
  }
}

TEST(Windows, AutoWindowRemovesTheRingingOfASun) {
  // A sun of 1e4 (a cone of 0.5 degrees) over a dim sky, order 8.
  const int order = 8;
  std::vector<double> c(sh_count(order) * 3, 0.0);
  const double sun[3] = {1e4, 0.9e4, 0.8e4}, sky[3] = {0.2, 0.3, 0.5};
  add_constant_light(sky, 3, c);
  add_cone_light(Eigen::Vector3d(0.2, 0.3, 0.9).normalized(), 0.5 * kPi / 180, sun, 3, c);
  for (int ch = 0; ch < 3; ++ch) EXPECT_LT(sh_minimum(c, 3, ch).value, 0.0);
  const Result<AutoWindow> w = choose_auto_window(c, 3);
  ASSERT_TRUE(w) << w.error().message;
  ASSERT_TRUE(w.value().cutoff.has_value());
  std::vector<double> windowed = c;
  scale_bands(w.value().factors, 3, windowed);
  for (int ch = 0; ch < 3; ++ch) {
    EXPECT_GE(w.value().minimum[ch], 0.0);
    EXPECT_GE(sh_minimum(windowed, 3, ch).value, 0.0);
  }
  // The largest such cutoff: a little more lets one channel ring again.
  std::vector<double> more = c;
  scale_bands(sh_window_factors(ShWindow::sinc4, *w.value().cutoff * 1.01, order), 3, more);
  double lowest = 0;
  for (int ch = 0; ch < 3; ++ch) lowest = std::min(lowest, sh_minimum(more, 3, ch).value);
  EXPECT_LT(lowest, 0.0);
  // A non-negative input keeps every band.
  std::vector<double> plain(sh_count(order) * 3, 0.0);
  add_constant_light(sky, 3, plain);
  const Result<AutoWindow> none = choose_auto_window(plain, 3);
  ASSERT_TRUE(none);
  EXPECT_FALSE(none.value().cutoff.has_value());
}

}  // namespace
}  // namespace shtool
