#include "shtool/analytic_lights.h"

#include <cmath>
#include <numbers>

#include "lighting/coefficient_layout.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

template <class T>
int order_of(std::span<T> coefficients, int channels) {
  return detail::order_of_layout(coefficients.size(), channels, "analytic light");
}

// Adds color * sum_l weights[l] sum_m y_l^m(d) y_l^m(w): by the addition theorem, the
// function sum_l weights[l] (2l+1) / (4 pi) P_l(w . d) of w . d alone.
template <class T>
void add_rotated_zonal(const Eigen::Vector3<T>& direction, const std::vector<double>& weights,
                       std::span<const T> color, int channels, std::span<T> coefficients) {
  const int order = order_of(coefficients, channels);
  std::vector<T> y(sh_count(order));
  eval_sh<T>(order, direction, y);
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) {
      const int i = sh_index(l, m);
      for (int c = 0; c < channels; ++c) coefficients[i * channels + c] += color[c] * T(weights[l]) * y[i];
    }
}

}  // namespace

std::vector<double> cap_zonal_coefficients(double half_angle, int order) {
  // 2 pi integral_x^1 P_l, x = cos a. Band 0: 2 pi (1 - x), with 1 - x formed as
  // 2 sin^2(a/2). Bands l >= 1: integral_x^1 P_l = (1 - x^2) P'_l(x) / (l (l + 1))
  // (Legendre's equation integrated from x to 1), with 1 - x^2 = sin^2 a and P'_l from
  // P'_{l+1} = P'_{l-1} + (2l+1) P_l, which near x = 1 adds terms of one sign: the form
  // (P_{l-1} - P_{l+1}) / (2l+1) cancels there and lost eps / a^2 (9 % at 1e-6 degrees).
  const double x = std::cos(half_angle), s = std::sin(half_angle);
  std::vector<double> p(order + 1), dp(order + 1);
  p[0] = 1, dp[0] = 0;
  if (order >= 1) p[1] = x, dp[1] = 1;
  for (int l = 1; l < order; ++l) {
    p[l + 1] = ((2 * l + 1) * x * p[l] - l * p[l - 1]) / (l + 1);  // Bonnet
    dp[l + 1] = dp[l - 1] + (2 * l + 1) * p[l];
  }
  std::vector<double> z(order);
  for (int l = 0; l < order; ++l)
    z[l] = 2 * std::numbers::pi *
           (l == 0 ? 2 * std::pow(std::sin(half_angle / 2), 2) : s * s * dp[l] / (static_cast<double>(l) * (l + 1)));
  return z;
}

namespace {

template <class T>
void add_directional_light_t(const Eigen::Vector3<T>& direction, std::span<const T> color,
                           int channels, std::span<T> coefficients) {
  const int order = order_of(coefficients, channels);
  std::vector<T> y(sh_count(order));
  eval_sh<T>(order, direction, y);
  for (int i = 0; i < sh_count(order); ++i)
    for (int c = 0; c < channels; ++c) coefficients[i * channels + c] += color[c] * y[i];
}

template <class T>
void add_cone_light_t(const Eigen::Vector3<T>& direction, T half_angle, std::span<const T> color,
                    int channels, std::span<T> coefficients) {
  // The cap's indicator is sum_l (2l+1)/2 I_l P_l(w . d), I_l = integral_{cos a}^1 P_l:
  // weights 2 pi I_l (cap_zonal_coefficients, in double whatever T).
  add_rotated_zonal<T>(direction, cap_zonal_coefficients(half_angle, order_of(coefficients, channels)), color,
                       channels, coefficients);
}

template <class T>
void add_constant_light_t(std::span<const T> color, int channels, std::span<T> coefficients) {
  for (int c = 0; c < channels; ++c) coefficients[c] += color[c] * std::sqrt(T(4) * std::numbers::pi_v<T>);
}

template <class T>
void add_hemisphere_light_t(const Eigen::Vector3<T>& direction, std::span<const T> sky,
                          std::span<const T> ground, int channels,
                          std::span<T> coefficients) {
  std::vector<T> difference(channels);
  for (int c = 0; c < channels; ++c) difference[c] = sky[c] - ground[c];
  add_constant_light_t<T>(ground, channels, coefficients);
  add_cone_light_t<T>(direction, std::numbers::pi_v<T> / 2, difference, channels, coefficients);
}

}  // namespace

void add_directional_light(const Eigen::Vector3d& direction, std::span<const double> color, int channels,
                           std::span<double> coefficients) {
  add_directional_light_t(direction, color, channels, coefficients);
}
void add_directional_light(const Eigen::Vector3f& direction, std::span<const float> color, int channels,
                           std::span<float> coefficients) {
  add_directional_light_t(direction, color, channels, coefficients);
}
void add_cone_light(const Eigen::Vector3d& direction, double half_angle, std::span<const double> color,
                    int channels, std::span<double> coefficients) {
  add_cone_light_t(direction, half_angle, color, channels, coefficients);
}
void add_cone_light(const Eigen::Vector3f& direction, float half_angle, std::span<const float> color,
                    int channels, std::span<float> coefficients) {
  add_cone_light_t(direction, half_angle, color, channels, coefficients);
}
void add_hemisphere_light(const Eigen::Vector3d& direction, std::span<const double> sky,
                          std::span<const double> ground, int channels, std::span<double> coefficients) {
  add_hemisphere_light_t(direction, sky, ground, channels, coefficients);
}
void add_hemisphere_light(const Eigen::Vector3f& direction, std::span<const float> sky,
                          std::span<const float> ground, int channels, std::span<float> coefficients) {
  add_hemisphere_light_t(direction, sky, ground, channels, coefficients);
}
void add_constant_light(std::span<const double> color, int channels, std::span<double> coefficients) {
  add_constant_light_t(color, channels, coefficients);
}
void add_constant_light(std::span<const float> color, int channels, std::span<float> coefficients) {
  add_constant_light_t(color, channels, coefficients);
}

}  // namespace shtool
