#include "shtool/analytic_lights.h"

#include <cmath>
#include <numbers>

#include "lighting/coefficient_layout.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

int order_of(std::span<double> coefficients, int channels) {
  return detail::order_of_layout(coefficients.size(), channels, "analytic light");
}

// Adds color * sum_l weights[l] sum_m y_l^m(d) y_l^m(w): by the addition theorem, the
// function sum_l weights[l] (2l+1) / (4 pi) P_l(w . d) of w . d alone.
void add_rotated_zonal(const Eigen::Vector3d& direction, std::span<const double> weights,
                       std::span<const double> color, int channels, std::span<double> coefficients) {
  const int order = order_of(coefficients, channels);
  std::vector<double> y(sh_count(order));
  eval_sh<double>(order, direction, y);
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) {
      const int i = sh_index(l, m);
      for (int c = 0; c < channels; ++c) coefficients[i * channels + c] += color[c] * weights[l] * y[i];
    }
}

}  // namespace

std::vector<double> cap_zonal_coefficients(double half_angle, int order) {
  // 2 pi integral_x^1 P_l = 2 pi (P_{l-1}(x) - P_{l+1}(x)) / (2l+1), from
  // (2l+1) P_l = P'_{l+1} - P'_{l-1} and P_l(1) = 1; Bonnet's recurrence for P_l(x).
  // For small caps 1 - x is formed as 2 sin^2(a/2), without cancellation.
  const double x = std::cos(half_angle);
  const double one_minus_x = 2 * std::pow(std::sin(half_angle / 2), 2);
  std::vector<double> p(order + 1);
  p[0] = 1;
  if (order >= 1) p[1] = x;
  for (int l = 1; l < order; ++l) p[l + 1] = ((2 * l + 1) * x * p[l] - l * p[l - 1]) / (l + 1);
  std::vector<double> z(order);
  for (int l = 0; l < order; ++l)
    z[l] = 2 * std::numbers::pi * (l == 0 ? one_minus_x : (p[l - 1] - p[l + 1]) / (2 * l + 1));
  return z;
}

void add_directional_light(const Eigen::Vector3d& direction, std::span<const double> color, int channels,
                           std::span<double> coefficients) {
  const int order = order_of(coefficients, channels);
  std::vector<double> y(sh_count(order));
  eval_sh<double>(order, direction, y);
  for (int i = 0; i < sh_count(order); ++i)
    for (int c = 0; c < channels; ++c) coefficients[i * channels + c] += color[c] * y[i];
}

void add_cone_light(const Eigen::Vector3d& direction, double half_angle, std::span<const double> color,
                    int channels, std::span<double> coefficients) {
  // The cap's indicator is sum_l (2l+1)/2 I_l P_l(w . d), I_l = integral_{cos a}^1 P_l:
  // weights 2 pi I_l (cap_zonal_coefficients).
  add_rotated_zonal(direction, cap_zonal_coefficients(half_angle, order_of(coefficients, channels)), color,
                    channels, coefficients);
}

void add_hemisphere_light(const Eigen::Vector3d& direction, std::span<const double> sky,
                          std::span<const double> ground, int channels, std::span<double> coefficients) {
  std::vector<double> difference(channels);
  for (int c = 0; c < channels; ++c) difference[c] = sky[c] - ground[c];
  add_constant_light(ground, channels, coefficients);
  add_cone_light(direction, std::numbers::pi / 2, difference, channels, coefficients);
}

void add_constant_light(std::span<const double> color, int channels, std::span<double> coefficients) {
  for (int c = 0; c < channels; ++c) coefficients[c] += color[c] * std::sqrt(4 * std::numbers::pi);
}

}  // namespace shtool
