// Light-specialized shading of zonal-harmonic (ZH) transfer ([4] Sec. 5, Eq. 24-25).
//
// A point's transfer is N lobes (unit axis s_i, convolved coefficients g*_il, l < n, in the
// convention of docs/conventions.md: a lobe adds g*_l y_l^m(s) to SH coefficient (l, m)).
// Shaded against distant SH lighting e of order n, its exit radiance is (Eq. 13)
//   r = sum_i sum_l g*_il sum_m y_l^m(s_i) e_lm.
// For a lighting shared by many points, Eq. 24 tabulates the inner sums over the sphere,
//   e^_l(s) = sum_m y_l^m(s) e_lm,      l = 0..n-1,
// and Eq. 25 shades with N look-ups and N n-term dot products:
//   r = sum_i e^(s_i) . g*_i.
// By the addition theorem e^_l(s) is also the band-l part of the lighting evaluated at s
// (it equals (2l+1)/(4 pi) times the lighting convolved with P_l about s).
//
// Two paths, both compiled and tested against each other (docs/fit-zh.md,
// "Light-specialized shading"):
//   exact      zh_light_bands / zh_shade_exact: the band sums at s directly
//              (n^2 SH values per lobe, no table);
//   tabulated  ZhLightTable: e^ sampled on the nodes of a cube map, (R+1) x (R+1) nodes
//              per face including the face edges (edge and corner nodes are stored once per
//              face that touches them), looked up with bilinear interpolation. Nodes on a
//              shared edge are the same points of the sphere, so the interpolant is
//              continuous across faces with no border texels, and each face's (gnomonic)
//              map is smooth, so the error falls as R^-2 everywhere.
//
// The per-point calls allocate nothing and throw nothing. Coefficient counts that do not
// match the table's order make them return a quiet NaN (one comparison per call), so an
// order mismatch is visible in the image rather than silently shading the wrong bands.
// Axes are expected to be unit vectors; the cube-map look-up only uses the direction. An
// axis with a NaN, a zero axis or one with more than one infinite component gives NaN;
// no axis leads to a read outside the table.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "shtool/sh.h"

namespace shtool {

// Cube-map cells per face edge (R). Bilinear interpolation errs by about
// h^2/8 (|f_aa| + |f_bb|) with h = 2/R, and band l's second derivatives grow as l(l+1):
// measured, the look-up error of e^_l stays below 0.5 l(l+1) / R^2 of the band scale
// sqrt((2l+1)/(4 pi)) |e_l| (the largest |e^_l| can be). At R = 32 and order 6 that is
// 1.5e-2 for band 5 (measured 1.1e-2) and 1e-3 for band 1; the table holds 6 (R+1)^2 n
// values, 306 KiB in double and 153 KiB in float at order 6 (docs/fit-zh.md).
inline constexpr int kDefaultZhLightResolution = 32;
// Bound on the error of ZhLightTable::lookup for band l relative to the band scale: the
// documented and tested 0.6 l(l+1) / R^2 (measured constant <= 0.50, plus 20% margin).
inline constexpr double zh_light_table_error_bound(int band, int resolution) {
  return 0.6 * band * (band + 1) / (static_cast<double>(resolution) * resolution);
}
// Largest accepted R (a 6 x 4097^2 x n table is already gigabytes at moderate orders).
inline constexpr int kMaxZhLightResolution = 4096;

// Exact band sums (Eq. 24) at one axis: out[l] = sum_m y_l^m(axis) light[l(l+1)+m] for
// l < order, where order^2 = light.size() (precondition: a perfect square of an order in
// 1..kMaxOrder) and out.size() >= order.
template <class T>
void zh_light_bands(std::span<const T> light, const Vec3<T>& axis, std::span<T> out) noexcept;

// Exact Eq. 25 for N = axes.size() lobes: coeffs holds N * order values, lobe-major
// (coeffs[i * order + l] = g*_il). Returns NaN if coeffs.size() != N * order or the light
// size is not a perfect square of a supported order.
template <class T>
T zh_shade_exact(std::span<const T> light, std::span<const Vec3<T>> axes, std::span<const T> coeffs) noexcept;

// e^_l(s), l < order, of one lighting, tabulated on a cube map.
template <class T>
class ZhLightTable {
 public:
  // Builds the table from SH lighting of the given order (light.size() must be order^2),
  // computing the nodes in double and storing them as T. Throws std::invalid_argument
  // naming the problem when the order is outside 1..kMaxOrder, light.size() != order^2,
  // a lighting coefficient is NaN or infinite, the resolution is outside
  // 1..kMaxZhLightResolution, or the table would exceed 2^28 values.
  ZhLightTable(int order, std::span<const double> light, int resolution = kDefaultZhLightResolution);
  // The same from float lighting (ShLighting<float>), widened to double first.
  ZhLightTable(int order, std::span<const float> light, int resolution = kDefaultZhLightResolution);

  int order() const noexcept { return order_; }
  int resolution() const noexcept { return resolution_; }
  // The node values, face-major, then node row, node column, band:
  // nodes()[((face (R+1) + j) (R+1) + i) order + l]. Face f = 2k + (axis component < 0),
  // k = 0, 1, 2 for x, y, z; node (i, j) sits at the cube point whose k-th coordinate is
  // +-1 and whose ((k+1) mod 3)-th and ((k+2) mod 3)-th coordinates are -1 + 2i/R and
  // -1 + 2j/R.
  std::span<const T> nodes() const noexcept { return nodes_; }
  std::size_t bytes() const noexcept { return nodes_.size() * sizeof(T); }

  // Bilinearly interpolated e^_l(axis) for l < order into out (out.size() >= order:
  // precondition).
  void lookup(const Vec3<T>& axis, std::span<T> out) const noexcept;

  // Eq. 25 for one lobe: sum_l e^_l(axis) g*_l. NaN if coeffs.size() != order().
  T shade_lobe(const Vec3<T>& axis, std::span<const T> coeffs) const noexcept;

  // Eq. 25 for N = axes.size() lobes, coeffs lobe-major as in zh_shade_exact.
  // NaN if coeffs.size() != N * order().
  T shade(std::span<const Vec3<T>> axes, std::span<const T> coeffs) const noexcept;

 private:
  // Face, first node index (i, j) of the cell and the bilinear fractions of an axis.
  struct Cell {
    const T* n00;  // node (i, j); (i+1, j) follows after order values, (i, j+1) after a row
    T u, v;
  };
  Cell locate(const Vec3<T>& axis) const noexcept;
  // Eq. 25 for one located lobe with coefficients g (order() values).
  T blend(const Cell& cell, const T* g) const noexcept;

  int order_;
  int resolution_;
  std::size_t row_;  // values per node row: (R+1) * order
  std::vector<T> nodes_;
};

extern template class ZhLightTable<float>;
extern template class ZhLightTable<double>;

}  // namespace shtool
