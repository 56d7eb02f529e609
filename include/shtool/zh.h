// Zonal-harmonic (ZH) lobes: evaluation, conversion to SH and rotation.
//
// A lobe is a unit axis s and convolved coefficients g*_l, l = 0..N-1 ([4]
// Eq. 6-8; docs/conventions.md): it contributes g*_l y_l^m(s) to SH
// coefficient (l, m). Its value in direction w follows from the addition theorem,
//   f(w) = sum_l g*_l sum_m y_l^m(s) y_l^m(w) = sum_l g*_l (2l+1)/(4 pi) P_l(s . w),
// so evaluation needs no SH basis at all. Rotating a lobe rotates its axis (Eq. 10).
//
// Allocation-free, exception-free. Axes must be unit vectors (precondition). Each function
// has a float and a double overload, computing in its own precision.
#pragma once

#include <span>

#include <Eigen/Core>

namespace shtool {

// Value of one lobe at unit direction w; coeffs.size() is the order N.
double eval_zh_lobe(const Eigen::Vector3d& axis, std::span<const double> coeffs, const Eigen::Vector3d& w);
float eval_zh_lobe(const Eigen::Vector3f& axis, std::span<const float> coeffs, const Eigen::Vector3f& w);

// Adds the SH coefficients of one lobe to sh (sh.size() >= N^2, N = coeffs.size()):
// sh[l(l+1)+m] += g*_l y_l^m(axis).
void add_zh_lobe_to_sh(const Eigen::Vector3d& axis, std::span<const double> coeffs, std::span<double> sh);
void add_zh_lobe_to_sh(const Eigen::Vector3f& axis, std::span<const float> coeffs, std::span<float> sh);

// Rotated lobe axis: rotating the lobe's function by R (g(w) = f(R^-1 w), docs/conventions.md)
// gives the same lobe along R s; coefficients are unchanged.
Eigen::Vector3d rotate_zh_axis(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& axis);
Eigen::Vector3f rotate_zh_axis(const Eigen::Matrix3f& rotation, const Eigen::Vector3f& axis);

// Shading with a lobe against SH lighting L (order N): integral of f(w) L(w) dw =
// sum_l g*_l sum_m y_l^m(s) L_lm ([4] Eq. 9 for one lobe).
double zh_lobe_dot_sh(const Eigen::Vector3d& axis, std::span<const double> coeffs, std::span<const double> light);
float zh_lobe_dot_sh(const Eigen::Vector3f& axis, std::span<const float> coeffs, std::span<const float> light);

}  // namespace shtool
