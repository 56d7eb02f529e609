#include "shtool/orthogonal_map.h"

#include <cmath>
#include <type_traits>
#include <vector>

#include <Eigen/Dense>

#include "shtool/rotation.h"
#include "shtool/sh.h"

namespace shtool {

namespace {

template <class T>
Result<Ok> apply_orthogonal_map_t(const Eigen::Matrix3<T>& q_in, int channels, std::span<T> coefficients) {
  const Eigen::Matrix3d q = q_in.template cast<double>();
  if (!q.allFinite() || !(q.transpose() * q).isApprox(Eigen::Matrix3d::Identity(), std::is_same_v<T, float> ? 1e-6 : 1e-9))
    return Error{"the frame map is not an orthogonal matrix"};
  if (channels < 1 || coefficients.size() % static_cast<std::size_t>(channels) != 0)
    return Error{"the coefficients are not a whole number of channels"};
  const int order = static_cast<int>(std::lround(std::sqrt(static_cast<double>(coefficients.size() / channels))));
  if (static_cast<std::size_t>(sh_count(order)) * channels != coefficients.size() || !is_supported_order(order))
    return Error{"the coefficient count is not channels x N^2 for a supported order N"};
  const bool reflection = q.determinant() < 0;
  const Eigen::Matrix3d p = reflection ? Eigen::Matrix3d(-q) : q;
  ShRotation<double> rotation(order, nullptr);
  rotation.set(p, RotationMethod::reference);
  std::vector<double> f(sh_count(order)), g(f.size());
  for (int c = 0; c < channels; ++c) {
    for (int i = 0; i < sh_count(order); ++i) {
      const double sign = reflection && sh_band(i) % 2 == 1 ? -1 : 1;
      f[i] = sign * double(coefficients[static_cast<std::size_t>(i) * channels + c]);
    }
    rotation.apply(f, g);
    for (int i = 0; i < sh_count(order); ++i) coefficients[static_cast<std::size_t>(i) * channels + c] = T(g[i]);
  }
  return Ok{};
}

}  // namespace

Result<Ok> apply_orthogonal_map(const Eigen::Matrix3d& q, int channels, std::span<double> coefficients) {
  return apply_orthogonal_map_t(q, channels, coefficients);
}
Result<Ok> apply_orthogonal_map(const Eigen::Matrix3f& q, int channels, std::span<float> coefficients) {
  return apply_orthogonal_map_t(q, channels, coefficients);
}

}  // namespace shtool
