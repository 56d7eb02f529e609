#include "shtool/irradiance.h"

#include <cmath>
#include <numbers>
#include <vector>

#include "lighting/coefficient_layout.h"
#include "shtool/sh.h"

namespace shtool {

double clamped_cosine_band(int l) {
  constexpr double pi = std::numbers::pi;
  if (l == 0) return pi;
  if (l == 1) return 2 * pi / 3;
  if (l % 2 == 1) return 0;
  // l! / (2^l ((l/2)!)^2) = C(l, l/2) / 2^l, built as a product of factors below 1 so
  // that no factorial overflows at any l.
  double central = 1;
  for (int k = 1; k <= l / 2; ++k) central *= static_cast<double>(l / 2 + k) / (4.0 * k);
  const double sign = (l / 2 - 1) % 2 == 0 ? 1 : -1;
  return 2 * pi * sign / ((l + 2.0) * (l - 1.0)) * central;
}

void scale_bands(std::span<const double> factors, int channels, std::span<double> coefficients) {
  const int order = detail::order_of_layout(coefficients.size(), channels, "scale_bands");
  if (factors.size() < static_cast<std::size_t>(order)) detail::precondition_failed("scale_bands: fewer factors than bands");
  const std::size_t count = coefficients.size() / channels;
  for (std::size_t i = 0; i < count; ++i) {
    const double f = factors[static_cast<std::size_t>(sh_band(static_cast<int>(i)))];
    for (int c = 0; c < channels; ++c) coefficients[i * channels + c] *= f;
  }
}

void radiance_to_irradiance(int channels, std::span<double> coefficients) {
  const int order = detail::order_of_layout(coefficients.size(), channels, "radiance_to_irradiance");
  std::vector<double> a(order);
  for (int l = 0; l < order; ++l) a[l] = clamped_cosine_band(l);
  scale_bands(a, channels, coefficients);
}

}  // namespace shtool
