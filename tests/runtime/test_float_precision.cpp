// The engine-facing functions that take float as well as double (zh.h, analytic_lights.h,
// orthogonal_map.h): the float result must equal the double one to float rounding, so
// that an engine working in float loses nothing but precision.
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "shtool/analytic_lights.h"
#include "shtool/orthogonal_map.h"
#include "shtool/sh.h"
#include "shtool/zh.h"

namespace shtool {
namespace {

std::vector<float> to_float(const std::vector<double>& v) { return {v.begin(), v.end()}; }

// Agreement to float rounding: a few ulps of `scale`, the largest magnitude involved
// (for a sum, the sum of its terms' magnitudes: cancellation is no fault of float).
void expect_close(const std::vector<float>& f, const std::vector<double>& d, const char* what, double scale = 0) {
  ASSERT_EQ(f.size(), d.size()) << what;
  for (double x : d) scale = std::max(scale, std::abs(x));
  for (std::size_t i = 0; i < d.size(); ++i) EXPECT_NEAR(f[i], d[i], 1e-6 * scale) << what << " [" << i << "]";
}

double sum_abs(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += std::abs(x);
  return s;
}

TEST(FloatPrecision, ZhLobesInFloatEqualDouble) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (int order : {1, 3, 6, 12}) {
    const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    const Eigen::Vector3d w = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    std::vector<double> coeffs(order), light(sh_count(order)), sh(sh_count(order), 0.0);
    for (double& c : coeffs) c = g(rng);
    for (double& c : light) c = g(rng);
    const std::vector<float> coeffs_f = to_float(coeffs), light_f = to_float(light);
    const Eigen::Vector3f axis_f = axis.cast<float>(), w_f = w.cast<float>();

    add_zh_lobe_to_sh(axis, coeffs, sh);
    std::vector<float> sh_f(sh.size(), 0.0f);
    add_zh_lobe_to_sh(axis_f, coeffs_f, sh_f);
    expect_close(sh_f, sh, "add_zh_lobe_to_sh");

    // |(2l+1) P_l / (4 pi)| <= (2l+1) / (4 pi) <= N; |y_l^m| <= 1 up to these orders.
    expect_close({eval_zh_lobe(axis_f, coeffs_f, w_f)}, {eval_zh_lobe(axis, coeffs, w)}, "eval_zh_lobe",
                 order * sum_abs(coeffs));
    expect_close({zh_lobe_dot_sh(axis_f, coeffs_f, light_f)}, {zh_lobe_dot_sh(axis, coeffs, light)},
                 "zh_lobe_dot_sh", sum_abs(coeffs) * sum_abs(light));
    const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, axis).toRotationMatrix();
    const Eigen::Vector3f turned = rotate_zh_axis(Eigen::Matrix3f(r.cast<float>()), w_f);
    const Eigen::Vector3d turned_d = rotate_zh_axis(r, w);
    expect_close({turned.x(), turned.y(), turned.z()}, {turned_d.x(), turned_d.y(), turned_d.z()}, "rotate_zh_axis");
  }
}

TEST(FloatPrecision, AnalyticLightsInFloatEqualDouble) {
  const int order = 5, channels = 3;
  const Eigen::Vector3d d = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  const std::vector<double> color = {1.5, 0.25, 3.0}, ground = {0.1, 0.2, 0.05};
  std::vector<double> c(static_cast<std::size_t>(sh_count(order)) * channels, 0.0);
  std::vector<float> c_f(c.size(), 0.0f);
  add_directional_light(d, color, channels, c);
  add_cone_light(d, 0.2, color, channels, c);
  add_hemisphere_light(d, color, ground, channels, c);
  add_constant_light(ground, channels, c);
  const Eigen::Vector3f d_f = d.cast<float>();
  add_directional_light(d_f, to_float(color), channels, c_f);
  add_cone_light(d_f, 0.2f, to_float(color), channels, c_f);
  add_hemisphere_light(d_f, to_float(color), to_float(ground), channels, c_f);
  add_constant_light(to_float(ground), channels, c_f);
  expect_close(c_f, c, "four lights");
}

TEST(FloatPrecision, OrthogonalMapsInFloatEqualDouble) {
  std::mt19937 rng(5);
  std::normal_distribution<double> g;
  const int order = 4, channels = 2;
  std::vector<double> c(static_cast<std::size_t>(sh_count(order)) * channels);
  for (double& x : c) x = g(rng);
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(1.1, Eigen::Vector3d(1, 2, -0.5).normalized()).toRotationMatrix();
  for (const Eigen::Matrix3d& q : {rotation, Eigen::Matrix3d(-rotation), Eigen::Matrix3d(Eigen::Vector3d(1, -1, 1).asDiagonal())}) {
    std::vector<double> d = c;
    std::vector<float> f = to_float(c);
    ASSERT_TRUE(apply_orthogonal_map(q, channels, d).ok());
    ASSERT_TRUE(apply_orthogonal_map(Eigen::Matrix3f(q.cast<float>()), channels, f).ok());
    expect_close(f, d, "orthogonal map");
  }
  std::vector<float> f = to_float(c);
  EXPECT_FALSE(apply_orthogonal_map(Eigen::Matrix3f(2 * Eigen::Matrix3f::Identity()), channels, f).ok());
}

}  // namespace
}  // namespace shtool
