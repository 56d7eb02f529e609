// Glossy LDPRT ([4] Sec. 3.2): a BRDF-specialised transfer matrix per vertex, each of its
// rows fitted with rotated ZH lobes, and the view-factor table u(v) that turns the rows'
// shading into exit radiance. `shtool fit-glossy` writes the table (kind "glossy-zh",
// docs/table-format.md); this header loads and shades it.
//
// For SH lighting e of order n, the exit radiance towards view direction v is (Eq. 16)
//   r(v) = sum_j u_j(v) r_j,   r_j = sum_i sum_l g*_jil sum_m y_l^m(s*_ji) e_lm + direct_j . e,
// j < n_b over the rows of M', i < N over each row's lobes: each r_j is a diffuse-style ZH
// shading (Eq. 13, shtool/zh_shading.h). v is expressed in the vertex's local frame
// (x tangent, y = n x tangent, z normal), the frame the bake used (docs/ldprt.md, "Glossy
// transfer"); after a deformation that frame is the deformed one and the lobes are rotated
// with it ([4] Sec. 6).
//
// u(v) is tabulated on a G x G square (G = 32 in [4]) mapped to the hemisphere by
// Shirley and Chiu's concentric square-to-disk map followed by the area-preserving
// (Lambert azimuthal) lift of the disk to the hemisphere, so every texel covers the same
// solid angle 2 pi / G^2. Texel (a, b) has its centre at ((a + 1/2) / G, (b + 1/2) / G);
// look-ups interpolate bilinearly between centres and clamp at the square's border (the
// horizon).
//
// The look-ups and the shading allocate nothing and throw nothing; loading returns Result.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "shtool/result.h"
#include "shtool/sh.h"
#include "shtool/table.h"
#include "shtool/zh_fit_table.h"

namespace shtool {

inline constexpr std::string_view kGlossyZhKind = "glossy-zh";
// Most rows of M' (n_b) a table may have: [4] keeps 3, and the shading keeps its per-call
// scratch on the stack.
inline constexpr int kMaxGlossyTerms = 64;

// The unit view direction (z >= 0) of the point (a, b) of the unit square: Shirley-Chiu
// concentric disk point (x, y) of radius r, lifted to z = 1 - r^2 with the disk point
// scaled by sqrt(2 - r^2) (equal area).
template <class T>
Vec3<T> glossy_view_direction(T a, T b) noexcept;

// The inverse: the square point of a direction, (0.5, 0.5) at the normal. A direction
// below the horizon (z < 0) is taken at the horizon in its azimuth; the zero vector, or
// one with a NaN or an infinite component, maps to the centre.
template <class T>
std::array<T, 2> glossy_view_square(const Vec3<T>& v) noexcept;

template <class T>
struct GlossyFit {
  // Row v * terms + j is the ZH fit of row j of vertex v's M' (order n, N lobes, the DC
  // and the linear band stored directly when N >= 3). rows.vertices = vertices * terms.
  ZhFitTable<T> rows;
  std::size_t vertices = 0;
  int terms = 0;            // n_b
  int view_resolution = 0;  // G
  // view_factors[(b * G + a) * terms + j] = u_j at the centre of texel (a, b): the rows of
  // U~ of the BRDF's SVD ([4] Eq. 14-15).
  std::vector<T> view_factors;
  // vertices entries (may be empty): 0-based OBJ vertex of each vertex's rows.
  std::vector<std::uint32_t> vertex_index;

  // u(v) for a unit view direction in the local frame (out.size() >= terms).
  void view_factors_at(const Vec3<T>& view, std::span<T> out) const noexcept;

  // r_j (Eq. 13 per row) of vertex `vertex` for lighting of order rows.order
  // (light.size() == order^2); out.size() >= terms. NaN on a light of another size.
  void row_radiance(std::span<const T> light, std::size_t vertex, std::span<T> out) const noexcept;

  // Eq. 16 at one vertex for one lighting channel: sum_j u_j(view) r_j.
  T shade(std::span<const T> light, std::size_t vertex, const Vec3<T>& view) const noexcept;

  // Checks kind, the rows as zh-fit checks them (shapes, finiteness, unit axes), the
  // row count against vertices x terms, the view table's shape and finiteness.
  static Result<GlossyFit> from_table(const Table& table);
  // read_table + from_table, the path prefixed to any message.
  static Result<GlossyFit> load(const std::filesystem::path& path);
};

extern template struct GlossyFit<float>;
extern template struct GlossyFit<double>;
extern template Vec3<float> glossy_view_direction<float>(float, float) noexcept;
extern template Vec3<double> glossy_view_direction<double>(double, double) noexcept;
extern template std::array<float, 2> glossy_view_square<float>(const Vec3<float>&) noexcept;
extern template std::array<double, 2> glossy_view_square<double>(const Vec3<double>&) noexcept;

}  // namespace shtool
