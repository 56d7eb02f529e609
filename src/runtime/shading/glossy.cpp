#include "shtool/glossy.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "io/load_kind.h"
#include "io/table_format.h"
#include "io/zh_rows.h"
#include "shtool/zh_shading.h"

namespace shtool {
namespace {

Error glossy_error(const std::string& what) { return Error{"glossy-zh table: " + what}; }

// Largest view map side accepted (the paper's is 32; 1024^2 view samples would already
// make the bake's BRDF matrix gigabytes).
constexpr std::int64_t kMaxViewResolution = 1024;

}  // namespace

template <class T>
Vec3<T> glossy_view_direction(T a, T b) noexcept {
  constexpr T quarter = std::numbers::pi_v<T> / 4;
  const T sx = 2 * a - 1, sy = 2 * b - 1;
  if (sx == 0 && sy == 0) return Vec3<T>(0, 0, 1);
  // Shirley and Chiu 1997: the square's concentric squares become the disk's circles.
  T r, phi;
  if (std::abs(sx) > std::abs(sy)) {
    r = sx;
    phi = quarter * (sy / sx);
  } else {
    r = sy;
    phi = 2 * quarter - quarter * (sx / sy);
  }
  const T x = r * std::cos(phi), y = r * std::sin(phi);
  const T rho2 = std::min<T>(x * x + y * y, 1);
  const T lift = std::sqrt(2 - rho2);  // equal area: a disk ring of area dA covers 2 dA of hemisphere
  return Vec3<T>(x * lift, y * lift, 1 - rho2);
}

template <class T>
std::array<T, 2> glossy_view_square(const Vec3<T>& v) noexcept {
  constexpr T quarter = std::numbers::pi_v<T> / 4;
  // Scaled by its largest component first: the squared length of a valid view overflows
  // above 1e154 (1e19 in float) and underflows below 1e-154.
  if (!v.allFinite()) return {T(0.5), T(0.5)};  // NaN or infinite: the normal
  const T big = v.cwiseAbs().maxCoeff();
  if (!(big > 0)) return {T(0.5), T(0.5)};  // zero: the normal
  const Vec3<T> u = v / big;
  const T z = std::max<T>(u.z() / u.norm(), 0);
  const T planar = std::hypot(u.x(), u.y());
  if (!(planar > 0)) return {T(0.5), T(0.5)};
  // Disk radius sqrt(1 - z) in the view's azimuth (the inverse of the lift).
  const T r = std::sqrt(std::max<T>(1 - z, 0));
  T phi = std::atan2(u.y(), u.x());
  if (phi < -quarter) phi += 8 * quarter;  // [-pi/4, 7 pi/4): one branch per square side
  T sx, sy;
  if (phi < quarter) {
    sx = r;
    sy = r * phi / quarter;
  } else if (phi < 3 * quarter) {
    sy = r;
    sx = -r * (phi - 2 * quarter) / quarter;
  } else if (phi < 5 * quarter) {
    sx = -r;
    sy = -r * (phi - 4 * quarter) / quarter;
  } else {
    sy = -r;
    sx = r * (phi - 6 * quarter) / quarter;
  }
  return {std::clamp<T>((sx + 1) / 2, 0, 1), std::clamp<T>((sy + 1) / 2, 0, 1)};
}

template <class T>
void GlossyFit<T>::view_factors_at(const Vec3<T>& view, std::span<T> out) const noexcept {
  const std::array<T, 2> ab = glossy_view_square(view);
  const int g = view_resolution;
  // Bilinear between texel centres, clamped to the border texels.
  auto axis = [g](T s, int& i0, T& t) {
    T f = s * g - T(0.5);
    if (!(f >= 0)) f = 0;  // also a NaN, which std::clamp would keep
    f = std::min(f, static_cast<T>(g - 1));
    i0 = std::min(static_cast<int>(f), std::max(g - 2, 0));
    t = g > 1 ? f - static_cast<T>(i0) : T(0);
  };
  int a0, b0;
  T ta, tb;
  axis(ab[0], a0, ta);
  axis(ab[1], b0, tb);
  const int a1 = std::min(a0 + 1, g - 1), b1 = std::min(b0 + 1, g - 1);
  const std::size_t nb = static_cast<std::size_t>(terms);
  const T* u00 = &view_factors[(std::size_t(b0) * g + a0) * nb];
  const T* u10 = &view_factors[(std::size_t(b0) * g + a1) * nb];
  const T* u01 = &view_factors[(std::size_t(b1) * g + a0) * nb];
  const T* u11 = &view_factors[(std::size_t(b1) * g + a1) * nb];
  for (std::size_t j = 0; j < nb; ++j)
    out[j] = (1 - tb) * ((1 - ta) * u00[j] + ta * u10[j]) + tb * ((1 - ta) * u01[j] + ta * u11[j]);
}

template <class T>
void GlossyFit<T>::row_radiance(std::span<const T> light, std::size_t vertex, std::span<T> out) const noexcept {
  for (int j = 0; j < terms; ++j) {
    const std::size_t row = vertex * terms + j;
    T r = zh_shade_exact<T>(light, rows.axes_of(row), rows.coeffs_of(row));
    const std::span<const T> direct = rows.direct_of(row);
    for (std::size_t i = 0; i < direct.size() && i < light.size(); ++i) r += direct[i] * light[i];
    out[j] = r;
  }
}

template <class T>
T GlossyFit<T>::shade(std::span<const T> light, std::size_t vertex, const Vec3<T>& view) const noexcept {
  T u[kMaxGlossyTerms], r[kMaxGlossyTerms];  // n_b <= kMaxGlossyTerms (from_table)
  const std::size_t nb = static_cast<std::size_t>(terms);
  view_factors_at(view, std::span<T>(u, nb));
  row_radiance(light, vertex, std::span<T>(r, nb));
  T sum = 0;
  for (std::size_t j = 0; j < nb; ++j) sum += u[j] * r[j];
  return sum;
}

template <class T>
Result<GlossyFit<T>> GlossyFit<T>::from_table(const Table& t) {
  if (t.kind != kGlossyZhKind) return glossy_error("wrong kind '" + t.kind + "'");
  if (const auto problem = detail::array_sizes_problem(t)) return glossy_error(*problem);
  const TableArray* u = t.find("view_factors");
  if (!u || u->shape.size() != 3 || u->shape[0] != u->shape[1] || u->shape[0] < 1 ||
      u->shape[0] > kMaxViewResolution || u->shape[2] < 1 || u->shape[2] > kMaxGlossyTerms)
    return glossy_error("array 'view_factors' is missing or not of shape [G, G, n_b] with 1 <= G <= " +
                        std::to_string(kMaxViewResolution) + " and 1 <= n_b <= " + std::to_string(kMaxGlossyTerms));
  Result<ZhFitTable<T>> rows = table_format::zh_rows_from_table<T>(t, "glossy-zh table: ");
  if (!rows) return rows.error();
  const std::int64_t nb = u->shape[2], g = u->shape[0];
  if (nb > static_cast<std::int64_t>(t.order) * t.order)
    return glossy_error("n_b = " + std::to_string(nb) + " terms, more than order " + std::to_string(t.order) +
                        " has coefficients");
  if (rows.value().vertices % static_cast<std::size_t>(nb) != 0)
    return glossy_error(std::to_string(rows.value().vertices) + " rows are not a whole number of vertices of " +
                        std::to_string(nb) + " terms");
  auto factors = table_format::finite_f64_array(t, "view_factors", u->shape, "glossy-zh table: ");
  if (!factors) return factors.error();
  GlossyFit g_fit;
  g_fit.rows = std::move(rows).value();
  g_fit.terms = static_cast<int>(nb);
  g_fit.view_resolution = static_cast<int>(g);
  g_fit.vertices = g_fit.rows.vertices / static_cast<std::size_t>(nb);
  for (const double f : factors.value())
    if (!detail::within_headroom<T>(f)) return glossy_error("a view factor is too large for the requested precision");
  g_fit.view_factors.assign(factors.value().begin(), factors.value().end());
  auto index =
      table_format::optional_vertex_index(t, g_fit.vertices, "V = rows / n_b = " + std::to_string(g_fit.vertices));
  if (!index) return glossy_error(index.error().message);
  g_fit.vertex_index = std::move(index).value();
  return g_fit;
}

SHTOOL_LOAD_KIND_FLOAT_AND_DOUBLE(GlossyFit, kGlossyZhKind)
template Vec3<float> glossy_view_direction<float>(float, float) noexcept;
template Vec3<double> glossy_view_direction<double>(double, double) noexcept;
template std::array<float, 2> glossy_view_square<float>(const Vec3<float>&) noexcept;
template std::array<double, 2> glossy_view_square<double>(const Vec3<double>&) noexcept;

}  // namespace shtool
