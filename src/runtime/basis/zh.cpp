#include "shtool/zh.h"

#include <algorithm>
#include <numbers>

#include "shtool/sh.h"

namespace shtool {

double eval_zh_lobe(const Eigen::Vector3d& axis, std::span<const double> coeffs, const Eigen::Vector3d& w) {
  const double x = std::clamp(axis.dot(w), -1.0, 1.0);
  // Bonnet's recurrence: (l+1) P_{l+1} = (2l+1) x P_l - l P_{l-1}.
  double p_prev = 1.0, p = x, sum = 0.0;
  const int order = static_cast<int>(coeffs.size());
  for (int l = 0; l < order; ++l) {
    const double pl = l == 0 ? 1.0 : p;
    sum += coeffs[l] * (2 * l + 1) * pl;
    if (l >= 1) {
      const double next = ((2 * l + 1) * x * p - l * p_prev) / (l + 1);
      p_prev = p;
      p = next;
    }
  }
  return sum / (4.0 * std::numbers::pi);
}

void add_zh_lobe_to_sh(const Eigen::Vector3d& axis, std::span<const double> coeffs, std::span<double> sh) {
  const int order = static_cast<int>(coeffs.size());
  double y[kMaxOrder * kMaxOrder];
  eval_sh<double>(order, axis, std::span<double>(y, sh_count(order)));
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) sh[sh_index(l, m)] += coeffs[l] * y[sh_index(l, m)];
}

Eigen::Vector3d rotate_zh_axis(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& axis) {
  return rotation * axis;
}

double zh_lobe_dot_sh(const Eigen::Vector3d& axis, std::span<const double> coeffs, std::span<const double> light) {
  const int order = static_cast<int>(coeffs.size());
  double y[kMaxOrder * kMaxOrder];
  eval_sh<double>(order, axis, std::span<double>(y, sh_count(order)));
  double sum = 0.0;
  for (int l = 0; l < order; ++l) {
    double band = 0.0;
    for (int m = -l; m <= l; ++m) band += y[sh_index(l, m)] * light[sh_index(l, m)];
    sum += coeffs[l] * band;
  }
  return sum;
}

}  // namespace shtool
