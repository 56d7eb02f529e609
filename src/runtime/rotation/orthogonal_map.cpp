#include "shtool/orthogonal_map.h"

#include <cmath>
#include <type_traits>
#include <vector>

#include <Eigen/Dense>

#include "shtool/sh.h"

namespace shtool {

OrthogonalMap::OrthogonalMap(const Eigen::Matrix3d& proper, bool reflects, int order)
    : proper_(proper), reflects_(reflects), rotation_(order, nullptr) {
  rotation_.set(proper_, RotationMethod::reference);
}

Result<OrthogonalMap> OrthogonalMap::make(const Eigen::Matrix3d& q, int order, double tolerance) {
  if (!q.allFinite() || !(q.transpose() * q).isApprox(Eigen::Matrix3d::Identity(), tolerance))
    return Error{"the frame map is not an orthogonal matrix"};
  if (!is_supported_order(order)) return Error{"the SH order is not supported"};
  const bool reflects = q.determinant() < 0;
  return OrthogonalMap(reflects ? Eigen::Matrix3d(-q) : q, reflects, order);
}

// The rotation keeps each band within itself, so the inversion's signs may come after it.
void OrthogonalMap::invert_odd_bands(std::span<double> out, int channels) const {
  if (!reflects_) return;
  const std::size_t c = static_cast<std::size_t>(channels);
  for (int l = 1; l < order(); l += 2)
    for (std::size_t i = c * static_cast<std::size_t>(l * l); i < c * static_cast<std::size_t>((l + 1) * (l + 1)); ++i)
      out[i] = -out[i];
}

void OrthogonalMap::apply(std::span<const double> in, std::span<double> out) const {
  rotation_.apply(in, out);
  invert_odd_bands(out);
}

bool OrthogonalMap::apply(std::span<const double> in, std::span<double> out, int channels) const {
  if (!rotation_.apply(in, out, channels)) return false;
  invert_odd_bands(out, channels);
  return true;
}

namespace {

template <class T>
Result<Ok> apply_orthogonal_map_t(const Eigen::Matrix3<T>& q, int channels, std::span<T> coefficients) {
  if (channels < 1 || coefficients.size() % static_cast<std::size_t>(channels) != 0)
    return Error{"the coefficients are not a whole number of channels"};
  const int order = static_cast<int>(std::lround(std::sqrt(static_cast<double>(coefficients.size() / channels))));
  if (static_cast<std::size_t>(sh_count(order)) * channels != coefficients.size() || !is_supported_order(order))
    return Error{"the coefficient count is not channels x N^2 for a supported order N"};
  Result<OrthogonalMap> map =
      OrthogonalMap::make(q.template cast<double>(), order, std::is_same_v<T, float> ? 1e-6 : 1e-9);
  if (!map) return map.error();
  const std::vector<double> f(coefficients.begin(), coefficients.end());
  std::vector<double> g(f.size());
  map.value().apply(f, g, channels);
  for (std::size_t i = 0; i < g.size(); ++i) coefficients[i] = T(g[i]);
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
