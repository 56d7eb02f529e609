#include "shtool/wrinkle_map.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "io/load_kind.h"
#include "io/table_format.h"
#include "io/zh_rows.h"
#include "shtool/zh_shading.h"

namespace shtool {

template <class T>
WrinkleWeights<T> wrinkle_weights(int g, T max_depth, T x, T depth) noexcept {
  T u = (x - std::floor(x)) * static_cast<T>(g);
  if (!(u >= 0)) u = 0;  // x infinite or NaN: node 0 rather than an index from a NaN
  // x - floor(x) rounds to 1 for x just below an integer: that is the last cell's end.
  const int j0 = std::min(static_cast<int>(std::floor(u)), g - 1);
  const T fx = u - static_cast<T>(j0);
  T q = depth / max_depth;
  if (!(q >= 0)) q = 0;  // a NaN, which std::clamp would keep
  const T v = std::min(q, T(1)) * static_cast<T>(g - 1);
  // d = max_depth lies on the last row of nodes: blended from the cell below it.
  const int k0 = std::min(static_cast<int>(std::floor(v)), g - 2);
  const T fd = v - static_cast<T>(k0);
  const int j1 = (j0 + 1) % g;
  return {{k0 * g + j0, k0 * g + j1, (k0 + 1) * g + j0, (k0 + 1) * g + j1},
          {(1 - fx) * (1 - fd), fx * (1 - fd), (1 - fx) * fd, fx * fd}};
}

template <class T>
void blend_wrinkle_lobes(int order, int lobes, std::span<const T> axes, std::span<const T> coeffs,
                         std::span<const T> direct, const WrinkleWeights<T>& w, WrinkleLobes<T>& out) noexcept {
  out.order = order;
  out.lobes = lobes;
  blend_wrinkle_values<T>(w, direct.data(), kWrinkleDirect, 0, kWrinkleDirect, out.direct.data());
  const std::size_t axis_stride = static_cast<std::size_t>(lobes) * 3, coeff_stride = static_cast<std::size_t>(lobes) * order;
  for (int lobe = 0; lobe < lobes; ++lobe) {
    Vec3<T> axis;
    blend_wrinkle_values<T>(w, axes.data(), axis_stride, static_cast<std::size_t>(lobe) * 3, 3, axis.data());
    blend_wrinkle_values<T>(w, coeffs.data(), coeff_stride, static_cast<std::size_t>(lobe) * order, order,
                            out.coeffs.data() + static_cast<std::size_t>(lobe) * order);
    out.axes[lobe] = axis.normalized();
  }
}

template <class T>
T shade_wrinkle_lobes(std::span<const T> light, const Eigen::Matrix<T, 3, 3>& frame,
                      const WrinkleLobes<T>& lobes) noexcept {
  if (light.size() != static_cast<std::size_t>(lobes.order) * lobes.order || lobes.order < 2)
    return std::numeric_limits<T>::quiet_NaN();
  std::array<Vec3<T>, kMaxWrinkleLobes> turned;
  for (int i = 0; i < lobes.lobes; ++i) turned[i] = frame * lobes.axes[i];
  // [4] Eq. 13 over the lobes, in the lighting's frame.
  T r = zh_shade_exact<T>(light, std::span<const Vec3<T>>(turned.data(), lobes.lobes), lobes.coeff_span());
  // y_1^-1 = -c y, y_1^0 = c z, y_1^1 = -c x: band 1 of the direct part is c v . w with
  // v = (-f_1, -f_-1, f_0), and the rotated function (f(R^-1 w)) has R v instead.
  const Vec3<T> v = frame * Vec3<T>(-lobes.direct[3], -lobes.direct[1], lobes.direct[2]);
  r += lobes.direct[0] * light[0] + (-v.y()) * light[1] + v.z() * light[2] + (-v.x()) * light[3];
  return r;
}

template <class T>
T WrinkleMap<T>::shade(std::span<const T> light, const Eigen::Matrix<T, 3, 3>& frame, T x, T depth) const noexcept {
  if (!std::isfinite(x) || !std::isfinite(depth)) return std::numeric_limits<T>::quiet_NaN();
  WrinkleLobes<T> l;
  lobes_at(x, depth, l);
  return shade_wrinkle_lobes<T>(light, frame, l);
}

namespace {

Error wrinkle_error(const std::string& what) { return Error{"wrinkle-zh table: " + what}; }

using table_format::shape_text;

Result<std::vector<double>> f64_array(const Table& t, const char* name, const std::vector<std::int64_t>& shape) {
  return table_format::finite_f64_array(t, name, shape, "wrinkle-zh table: ");
}

// meta[key] when it is an integer.
bool meta_int(const nlohmann::json& meta, const char* key, std::int64_t& out) {
  if (!meta.is_object() || !meta.contains(key) || !meta[key].is_number_integer()) return false;
  out = meta[key].get<std::int64_t>();
  return true;
}

}  // namespace

template <class T>
Result<WrinkleMap<T>> WrinkleMap<T>::from_table(const Table& t) {
  if (const auto problem = detail::kind_and_order_problem(t, kWrinkleZhKind, 2, kMaxWrinkleOrder))
    return wrinkle_error(*problem);
  const nlohmann::json meta = nlohmann::json::parse(t.meta, nullptr, /*allow_exceptions=*/false);
  std::int64_t G = 0, N = 0;
  if (!meta_int(meta, "grid", G) || G < 2 || G > 4096)
    return wrinkle_error("meta 'grid' is missing or not an integer in 2..4096");
  if (!meta_int(meta, "lobes", N) || N < 1 || N > kMaxWrinkleLobes)
    return wrinkle_error("meta 'lobes' is missing or not an integer in 1.." + std::to_string(kMaxWrinkleLobes));
  if (!meta.contains("max_depth") || !meta["max_depth"].is_number())
    return wrinkle_error("meta 'max_depth' is missing or not a number");
  const double max_depth = meta["max_depth"].get<double>();
  if (!std::isfinite(max_depth) || !(max_depth > 0)) return wrinkle_error("meta 'max_depth' is not a positive number");
  // Stored as T, it divides every depth: it must stay a normal, finite T.
  if (!(static_cast<T>(max_depth) >= std::numeric_limits<T>::min()) ||
      !(static_cast<T>(max_depth) <= std::numeric_limits<T>::max()))
    return wrinkle_error("meta 'max_depth' does not fit the requested precision");
  const std::int64_t n = t.order;
  auto xs = f64_array(t, "x", {G});
  auto ds = f64_array(t, "depth", {G});
  auto ax = f64_array(t, "axes", {G, G, N, 3});
  auto co = f64_array(t, "coeffs", {G, G, N, n});
  auto di = f64_array(t, "direct", {G, G, kWrinkleDirect});
  for (const auto* r : {&xs, &ds, &ax, &co, &di})
    if (!*r) return r->error();
  // The blend places node j at j / G and row k at max_depth k / (G - 1): a table that
  // says otherwise would shade every point at the wrong place.
  for (std::int64_t j = 0; j < G; ++j)
    if (std::abs(xs.value()[j] - static_cast<double>(j) / G) > 1e-12)
      return wrinkle_error("x[" + std::to_string(j) + "] is not " + std::to_string(j) + " / G");
  for (std::int64_t k = 0; k < G; ++k)
    if (std::abs(ds.value()[k] - max_depth * k / (G - 1)) > 1e-12 * max_depth)
      return wrinkle_error("depth[" + std::to_string(k) + "] is not max_depth * " + std::to_string(k) + " / (G - 1)");
  const std::vector<double>& a = ax.value();
  const std::vector<double>& c = co.value();
  const std::vector<double>& dv = di.value();
  for (std::size_t b = 0; b < c.size() / n; ++b)
    if (c[b * n] != 0 || c[b * n + 1] != 0)
      return wrinkle_error("lobe coefficients of bands 0 and 1 must be 0 (array 'direct' holds them), node lobe " +
                           std::to_string(b));
  auto axis = [&](std::int64_t node, std::int64_t lobe) {
    const std::size_t i = static_cast<std::size_t>(node * N + lobe) * 3;
    return Vec3<double>(a[i], a[i + 1], a[i + 2]);
  };
  for (std::int64_t node = 0; node < G * G; ++node)
    for (std::int64_t lobe = 0; lobe < N; ++lobe) {
      // As stored in T too: a tiny axis that a float flushes to zero cannot be normalised.
      const Vec3<T> stored = axis(node, lobe).template cast<T>();
      if (!(axis(node, lobe).norm() > 0) || !(stored.squaredNorm() > T(0)))
        return wrinkle_error("axis of lobe " + std::to_string(lobe) + " at node " + std::to_string(node) + " is zero");
      // Its squared length a normal T, or normalising it in T overflows (1e20 in float)
      // or loses its digits (3e-23).
      const T length2 = stored.squaredNorm();
      if (!(length2 >= std::numeric_limits<T>::min() && length2 <= std::numeric_limits<T>::max() * T(0x1p-8)))
        return wrinkle_error("axis of lobe " + std::to_string(lobe) + " at node " + std::to_string(node) +
                             " cannot be normalised in the requested precision");
    }
  // Four vectors within 90 degrees of one direction have a blend (positive weights) that
  // is never zero, so its normalisation is defined everywhere in the cell.
  for (std::int64_t k = 0; k + 1 < G; ++k)
    for (std::int64_t j = 0; j < G; ++j)
      for (std::int64_t lobe = 0; lobe < N; ++lobe) {
        const std::int64_t j1 = (j + 1) % G;
        const Vec3<double> q[4] = {axis(k * G + j, lobe).normalized(), axis(k * G + j1, lobe).normalized(),
                                   axis((k + 1) * G + j, lobe).normalized(), axis((k + 1) * G + j1, lobe).normalized()};
        const Vec3<double> sum = q[0] + q[1] + q[2] + q[3];
        bool ok = sum.norm() > 0;
        for (const Vec3<double>& e : q) ok = ok && e.dot(sum) > 0;
        if (!ok)
          return wrinkle_error("the axes of lobe " + std::to_string(lobe) + " around cell (depth row " +
                               std::to_string(k) + ", x column " + std::to_string(j) + ") can blend to zero");
      }
  for (const std::vector<double>* values : {&a, &c, &dv})
    for (const double v : *values)
      if (!detail::within_headroom<T>(v)) return wrinkle_error("a value is too large for the requested precision");

  WrinkleMap m;
  m.order = static_cast<int>(n);
  m.lobes = static_cast<int>(N);
  m.grid = static_cast<int>(G);
  m.max_depth = static_cast<T>(max_depth);
  m.axes.assign(a.begin(), a.end());
  m.coeffs.assign(c.begin(), c.end());
  m.direct.assign(dv.begin(), dv.end());
  return m;
}

template WrinkleWeights<float> wrinkle_weights<float>(int, float, float, float) noexcept;
template WrinkleWeights<double> wrinkle_weights<double>(int, double, double, double) noexcept;
template void blend_wrinkle_lobes<float>(int, int, std::span<const float>, std::span<const float>,
                                         std::span<const float>, const WrinkleWeights<float>&,
                                         WrinkleLobes<float>&) noexcept;
template void blend_wrinkle_lobes<double>(int, int, std::span<const double>, std::span<const double>,
                                          std::span<const double>, const WrinkleWeights<double>&,
                                          WrinkleLobes<double>&) noexcept;
template float shade_wrinkle_lobes<float>(std::span<const float>, const Eigen::Matrix<float, 3, 3>&,
                                          const WrinkleLobes<float>&) noexcept;
template double shade_wrinkle_lobes<double>(std::span<const double>, const Eigen::Matrix<double, 3, 3>&,
                                            const WrinkleLobes<double>&) noexcept;
SHTOOL_LOAD_KIND_FLOAT_AND_DOUBLE(WrinkleMap, kWrinkleZhKind)

}  // namespace shtool
