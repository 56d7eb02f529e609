#include "shtool/zh.h"

#include <algorithm>
#include <numbers>

#include "shtool/sh.h"

namespace shtool {
namespace {

template <class T>
T eval_zh_lobe_t(const Eigen::Vector3<T>& axis, std::span<const T> coeffs,
               const Eigen::Vector3<T>& w) {
  const T x = std::clamp(axis.dot(w), T(-1), T(1));
  // Bonnet's recurrence: (l+1) P_{l+1} = (2l+1) x P_l - l P_{l-1}.
  T p_prev = 1, p = x, sum = 0;
  const int order = static_cast<int>(coeffs.size());
  for (int l = 0; l < order; ++l) {
    const T pl = l == 0 ? T(1) : p;
    sum += coeffs[l] * T(2 * l + 1) * pl;
    if (l >= 1) {
      const T next = (T(2 * l + 1) * x * p - T(l) * p_prev) / T(l + 1);
      p_prev = p;
      p = next;
    }
  }
  return sum / (T(4) * std::numbers::pi_v<T>);
}

template <class T>
void add_zh_lobe_to_sh_t(const Eigen::Vector3<T>& axis, std::span<const T> coeffs,
                       std::span<T> sh) {
  const int order = static_cast<int>(coeffs.size());
  T y[kMaxOrder * kMaxOrder];
  eval_sh<T>(order, axis, std::span<T>(y, sh_count(order)));
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) sh[sh_index(l, m)] += coeffs[l] * y[sh_index(l, m)];
}

template <class T>
Eigen::Vector3<T> rotate_zh_axis_t(const Eigen::Matrix3<T>& rotation, const Eigen::Vector3<T>& axis) {
  return rotation * axis;
}

template <class T>
T zh_lobe_dot_sh_t(const Eigen::Vector3<T>& axis, std::span<const T> coeffs,
                 std::span<const T> light) {
  const int order = static_cast<int>(coeffs.size());
  T y[kMaxOrder * kMaxOrder];
  eval_sh<T>(order, axis, std::span<T>(y, sh_count(order)));
  T sum = 0;
  for (int l = 0; l < order; ++l) {
    T band = 0;
    for (int m = -l; m <= l; ++m) band += y[sh_index(l, m)] * light[sh_index(l, m)];
    sum += coeffs[l] * band;
  }
  return sum;
}

}  // namespace

double eval_zh_lobe(const Eigen::Vector3d& axis, std::span<const double> coeffs, const Eigen::Vector3d& w) {
  return eval_zh_lobe_t(axis, coeffs, w);
}
float eval_zh_lobe(const Eigen::Vector3f& axis, std::span<const float> coeffs, const Eigen::Vector3f& w) {
  return eval_zh_lobe_t(axis, coeffs, w);
}
void add_zh_lobe_to_sh(const Eigen::Vector3d& axis, std::span<const double> coeffs, std::span<double> sh) {
  add_zh_lobe_to_sh_t(axis, coeffs, sh);
}
void add_zh_lobe_to_sh(const Eigen::Vector3f& axis, std::span<const float> coeffs, std::span<float> sh) {
  add_zh_lobe_to_sh_t(axis, coeffs, sh);
}
Eigen::Vector3d rotate_zh_axis(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& axis) {
  return rotate_zh_axis_t(rotation, axis);
}
Eigen::Vector3f rotate_zh_axis(const Eigen::Matrix3f& rotation, const Eigen::Vector3f& axis) {
  return rotate_zh_axis_t(rotation, axis);
}
double zh_lobe_dot_sh(const Eigen::Vector3d& axis, std::span<const double> coeffs, std::span<const double> light) {
  return zh_lobe_dot_sh_t(axis, coeffs, light);
}
float zh_lobe_dot_sh(const Eigen::Vector3f& axis, std::span<const float> coeffs, std::span<const float> light) {
  return zh_lobe_dot_sh_t(axis, coeffs, light);
}

}  // namespace shtool
