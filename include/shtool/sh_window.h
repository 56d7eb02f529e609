// Windowing of SH coefficients (docs/lighting.md): zonal, per-band factors w_l that damp
// the ringing of a truncated expansion, and the search for the smallest value of a
// reconstruction over the sphere that the automatic window relies on.
//
// With x = l / cutoff (cutoff > 0), every window is 0 for x >= 1 and
//   hann    (1 + cos(pi x)) / 2
//   lanczos sinc(pi x) = sin(pi x) / (pi x)
//   sinc4   sinc(pi x)^4 (the window filament's cmgen applies)
// "auto" is sinc4 with the largest cutoff whose reconstruction is non-negative in every
// channel ([14] explains why windowing removes the negative lobes).
#pragma once

#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "shtool/result.h"

namespace shtool {

enum class ShWindow { none, hann, lanczos, sinc4 };

std::string_view sh_window_name(ShWindow window);
std::optional<ShWindow> sh_window_from_name(std::string_view name);

// w_l for l = 0..order-1 (none: all 1).
std::vector<double> sh_window_factors(ShWindow window, double cutoff, int order);

// The smallest value of sum_i coefficients[i * channels + channel] y_i(w) over the unit
// sphere, and where: a dense spherical Fibonacci set (at least 64 points per band^2),
// then projected gradient descent on the sphere from the lowest few points.
struct ShMinimum {
  double value = 0;
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();
};
ShMinimum sh_minimum(std::span<const double> coefficients, int channels, int channel);

// The automatic window: the largest cutoff (found by bisection to 1e-9 relative) for
// which the sinc4-windowed reconstruction of every channel has a non-negative minimum
// (sh_minimum). No window at all when the coefficients are non-negative already (then
// cutoff is empty and every factor 1). An error when a channel's mean is negative
// (no window can help).
struct AutoWindow {
  std::optional<double> cutoff;
  std::vector<double> factors;
  std::vector<double> minimum;  // per channel, after the window
};
Result<AutoWindow> choose_auto_window(std::span<const double> coefficients, int channels);

}  // namespace shtool
