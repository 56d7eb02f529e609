#include "shtool/zh_fit_table.h"

#include <cmath>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "io/load_kind.h"
#include "io/table_format.h"
#include "io/zh_rows.h"

namespace shtool {
namespace {

Error zh_fit_error(const std::string& what) { return Error{"zh-fit table: " + what}; }

using table_format::shape_text;

}  // namespace

namespace table_format {

Result<std::vector<double>> finite_f64_array(const Table& t, const char* name, const std::vector<std::int64_t>& shape,
                                             const std::string& prefix) {
  const TableArray* a = t.find(name);
  if (!a) return Error{prefix + "missing array '" + std::string(name) + "'"};
  if (a->dtype != DType::f64) return Error{prefix + "array '" + std::string(name) + "' is not f64"};
  if (a->shape != shape)
    return Error{prefix + "array '" + std::string(name) + "' has shape " + shape_text(a->shape) + ", expected " +
                 shape_text(shape)};
  std::vector<double> v = a->values<double>();
  for (std::size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i]))
      return Error{prefix + "array '" + std::string(name) + "' element " + std::to_string(i) + " is not finite"};
  return v;
}

Result<std::vector<std::uint32_t>> optional_vertex_index(const Table& t, std::size_t vertices,
                                                         const std::string& v_is) {
  const TableArray* vi = t.find("vertex_index");
  if (!vi) return std::vector<std::uint32_t>{};
  if (vi->dtype != DType::u32 || vi->shape != std::vector<std::int64_t>{static_cast<std::int64_t>(vertices)})
    return Error{"array 'vertex_index' is not u32 of shape [V] (" + v_is + "), got " + shape_text(vi->shape)};
  return vi->values<std::uint32_t>();
}

template <class T>
Result<ZhFitTable<T>> zh_rows_from_table(const Table& t, const std::string& prefix) {
  auto zh_fit_error = [&](const std::string& what) { return Error{prefix + what}; };
  auto f64_array = [&](const Table& table, const char* name, const std::vector<std::int64_t>& shape) {
    return finite_f64_array(table, name, shape, prefix);
  };
  if (!is_supported_order(t.order)) return zh_fit_error("unsupported order " + std::to_string(t.order));
  const TableArray* axes = t.find("axes");
  if (!axes || axes->shape.size() != 3 || axes->shape[2] != 3)
    return zh_fit_error("array 'axes' is missing or not of shape [V, N, 3]");
  const std::int64_t V = axes->shape[0], N = axes->shape[1], n = t.order;
  // 64 lobes is fit-zh's own limit; V is bounded by the bytes the reader accepted.
  if (V < 1 || N < 1 || N > 64) return zh_fit_error("axes shape " + shape_text(axes->shape) + " is out of range");
  auto ax = f64_array(t, "axes", {V, N, 3});
  auto co = f64_array(t, "coeffs", {V, N, n});
  auto re = f64_array(t, "residual", {V});
  auto no = f64_array(t, "norm", {V});
  for (const auto* r : {&ax, &co, &re, &no})
    if (!*r) return r->error();

  ZhFitTable<T> z;
  z.order = static_cast<int>(n);
  z.lobes = static_cast<int>(N);
  z.vertices = static_cast<std::size_t>(V);
  const std::vector<double>& a = ax.value();
  z.axes.reserve(a.size() / 3);
  for (std::size_t i = 0; i < a.size(); i += 3) {
    const Vec3<double> w(a[i], a[i + 1], a[i + 2]);
    if (std::abs(w.norm() - 1.0) > 1e-6)
      return zh_fit_error("axis " + std::to_string(i / 3) + " is not a unit vector");
    z.axes.push_back(w.cast<T>());
  }
  auto narrow = [](const std::vector<double>& in, std::vector<T>& out) {
    out.assign(in.begin(), in.end());
  };
  for (const double r : re.value())
    if (r < 0) return zh_fit_error("negative residual");
  for (const double r : no.value())
    if (r < 0) return zh_fit_error("negative norm");
  // A float table must not overflow on the way in: every value it stores must fit T, and
  // the coefficients, which shading multiplies and sums, with room for that.
  auto fits = [](const std::vector<double>& values) {
    for (const double c : values)
      if (std::abs(c) > static_cast<double>(std::numeric_limits<T>::max())) return false;
    return true;
  };
  for (const double c : co.value())
    if (!detail::within_headroom<T>(c)) return zh_fit_error("a coefficient is too large for the requested precision");
  if (!fits(re.value()) || !fits(no.value()))
    return zh_fit_error("a residual or norm does not fit the requested precision");
  narrow(co.value(), z.coeffs);
  narrow(re.value(), z.residual);
  narrow(no.value(), z.norm);

  if (const TableArray* d = t.find("direct")) {
    if (d->shape.size() != 2 || d->shape[0] != V || (d->shape[1] != 1 && d->shape[1] != 4))
      return zh_fit_error("array 'direct' has shape " + shape_text(d->shape) + ", expected [V, 1] or [V, 4]");
    // Direct coefficients are SH coefficients of the fit's own order: DC, then band 1.
    if (d->shape[1] > static_cast<std::int64_t>(z.order) * z.order)
      return zh_fit_error("array 'direct' holds " + std::to_string(d->shape[1]) + " coefficients, more than order " +
                          std::to_string(z.order) + " has");
    auto dv = f64_array(t, "direct", d->shape);
    if (!dv) return dv.error();
    for (const double c : dv.value())
      if (!detail::within_headroom<T>(c))
        return zh_fit_error("a direct coefficient is too large for the requested precision");
    z.direct_count = static_cast<int>(d->shape[1]);
    narrow(dv.value(), z.direct);
  }
  return z;
}

template Result<ZhFitTable<float>> zh_rows_from_table<float>(const Table&, const std::string&);
template Result<ZhFitTable<double>> zh_rows_from_table<double>(const Table&, const std::string&);

}  // namespace table_format

template <class T>
Result<ZhFitTable<T>> ZhFitTable<T>::from_table(const Table& t) {
  if (t.kind != kZhFitKind) return zh_fit_error("wrong kind '" + t.kind + "'");
  if (const auto problem = detail::array_sizes_problem(t)) return zh_fit_error(*problem);
  // A shard of a bake holds a range of the vertices only; shading it as the whole mesh
  // would misplace every row.
  const nlohmann::json meta = nlohmann::json::parse(t.meta, nullptr, /*allow_exceptions=*/false);
  if (meta.is_object() && meta.contains("shard"))
    return zh_fit_error("a partial table (fit-zh --shard): join the parts with shtool merge first");
  Result<ZhFitTable> rows = table_format::zh_rows_from_table<T>(t, "zh-fit table: ");
  if (!rows) return rows.error();
  ZhFitTable z = std::move(rows).value();
  auto index = table_format::optional_vertex_index(t, z.vertices, "V = " + std::to_string(z.vertices));
  if (!index) return zh_fit_error(index.error().message);
  z.vertex_index = std::move(index).value();
  return z;
}

SHTOOL_LOAD_KIND_FLOAT_AND_DOUBLE(ZhFitTable, kZhFitKind)

}  // namespace shtool
