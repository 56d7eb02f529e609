#include "shtool/probe_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <nlohmann/json.hpp>

#include "io/load_kind.h"
#include "io/table_format.h"
#include "io/zh_rows.h"
#include "shtool/irradiance.h"

namespace shtool {
namespace {

Error probe_error(const std::string& what) { return Error{"probe-grid table: " + what}; }

using table_format::shape_text;

}  // namespace

template <class T>
std::array<int, 3> ProbeGrid<T>::grid_index(std::size_t probe) const {
  const std::size_t nx = resolution[0], ny = resolution[1];
  return {static_cast<int>(probe % nx), static_cast<int>(probe / nx % ny), static_cast<int>(probe / (nx * ny))};
}

template <class T>
Vec3<T> ProbeGrid<T>::position(std::size_t probe) const {
  const std::array<int, 3> i = grid_index(probe);
  Vec3<T> p;
  for (int a = 0; a < 3; ++a) p[a] = min[a] + (T(i[a]) + T(0.5)) * (max[a] - min[a]) / T(resolution[a]);
  return p;
}

template <class T>
Vec3<T> ProbeGrid<T>::irradiance_of(std::span<const T> c, const Vec3<T>& normal) const noexcept {
  if (encoding != ProbeEncoding::l2) {
    L1Probe<T> l1;
    std::copy_n(c.begin(), l1.coefficients.size(), l1.coefficients.begin());
    if (encoding == ProbeEncoding::l1) return l1_nonlinear_irradiance(l1, normal);
    Zh3Probe<T> zh3;
    zh3.l1 = l1;
    if (zh3_fit == Zh3Fit::hallucinated)
      for (int ch = 0; ch < 3; ++ch) zh3.zonal[ch] = zh3_hallucinated_zonal(l1, zh3_axis, ch);
    else
      std::copy_n(c.begin() + l1.coefficients.size(), 3, zh3.zonal.begin());
    return zh3_irradiance(zh3, zh3_axis, normal);
  }
  T y[kMaxProbeOrder * kMaxProbeOrder];
  eval_sh<T>(order, normal, std::span<T>(y, static_cast<std::size_t>(order) * order));
  Vec3<T> e = Vec3<T>::Zero();
  for (int l = 0; l < order; ++l) {
    const T a = static_cast<T>(clamped_cosine_band(l));
    for (int m = -l; m <= l; ++m) {
      const int k = sh_index(l, m);
      for (int ch = 0; ch < 3; ++ch) e[ch] += a * c[k * 3 + ch] * y[k];
    }
  }
  return e;
}

template <class T>
Vec3<T> ProbeGrid<T>::irradiance(std::size_t probe, const Vec3<T>& normal) const noexcept {
  return irradiance_of(coefficients_of(probe), normal);
}

template <class T>
Vec3<T> ProbeGrid<T>::irradiance_at(const Vec3<T>& x, const Vec3<T>& normal) const noexcept {
  T values[kMaxProbeValues];
  const std::span<T> v(values, values_per_probe());
  sample(x, v);
  return irradiance_of(v, normal);
}

template <class T>
void ProbeGrid<T>::sample(const Vec3<T>& x, std::span<T> out) const noexcept {
  const std::size_t n = values_per_probe();
  int i0[3], i1[3];
  T f[3];
  for (int a = 0; a < 3; ++a) {
    // Continuous probe coordinate: probe i sits at i; clamped to [0, n - 1].
    T u = (x[a] - min[a]) / (max[a] - min[a]) * T(resolution[a]) - T(0.5);
    if (!(u > 0)) u = 0;  // NaN too
    const T top = T(resolution[a] - 1);
    if (u > top) u = top;
    i0[a] = static_cast<int>(std::floor(u));
    i1[a] = std::min(i0[a] + 1, resolution[a] - 1);
    f[a] = u - T(i0[a]);
  }
  for (std::size_t k = 0; k < n && k < out.size(); ++k) out[k] = T(0);
  for (int corner = 0; corner < 8; ++corner) {
    const int ix = corner & 1 ? i1[0] : i0[0], iy = corner & 2 ? i1[1] : i0[1], iz = corner & 4 ? i1[2] : i0[2];
    const T w = (corner & 1 ? f[0] : 1 - f[0]) * (corner & 2 ? f[1] : 1 - f[1]) * (corner & 4 ? f[2] : 1 - f[2]);
    const std::span<const T> c = coefficients_of(probe_index(ix, iy, iz));
    for (std::size_t k = 0; k < n && k < out.size(); ++k) out[k] += w * c[k];
  }
}

template <class T>
Result<ProbeGrid<T>> ProbeGrid<T>::from_table(const Table& t) {
  if (const auto problem = detail::kind_and_order_problem(t, kProbeGridKind, 1, kMaxProbeOrder))
    return probe_error(*problem);
  // read_table checks the major when asked to; a Table built in memory comes here unchecked.
  const std::optional<table_format::Version> version = table_format::parse_version(t.kind_version);
  const table_format::Version ours = *table_format::parse_version(kProbeGridKindVersion);
  if (!version || version->major != ours.major)
    return probe_error("kind_version " + t.kind_version + " is not readable: this reader knows " +
                       std::to_string(ours.major) + ".x (up to " + std::string(kProbeGridKindVersion) + ")" +
                       (version && version->major > ours.major ? "; a newer shtool wrote it" : ""));
  const nlohmann::json meta = nlohmann::json::parse(t.meta, nullptr, /*allow_exceptions=*/false);
  if (meta.is_object() && meta.contains("shard"))
    return probe_error("a partial table (bake-probes --shard): join the parts with shtool merge first");
  ProbeEncoding encoding = ProbeEncoding::l2;
  Zh3Axis axis = Zh3Axis::luminance;
  Zh3Fit fit = Zh3Fit::explicit_fit;
  if (meta.is_object() && meta.contains("encoding")) {
    const auto e = meta["encoding"].is_string() ? parse_probe_encoding(meta["encoding"].get<std::string>())
                                                : std::nullopt;
    if (!e) return probe_error("meta.encoding " + meta["encoding"].dump() + " is not one of l2, l1, zh3");
    encoding = *e;
  }
  if (encoding != ProbeEncoding::l2 && t.order != 2)
    return probe_error("encoding " + std::string(probe_encoding_name(encoding)) + " stores order 2 (bands 0 and 1), not " +
                       std::to_string(t.order));
  if (encoding == ProbeEncoding::zh3) {
    const auto a = meta.contains("zh3_axis") && meta["zh3_axis"].is_string()
                       ? parse_zh3_axis(meta["zh3_axis"].get<std::string>())
                       : std::nullopt;
    if (!a) return probe_error("meta.zh3_axis is missing or not 'luminance' or 'per-channel'");
    axis = *a;
    // 1.0 tables held the explicit fit only (their meta.zh3_fit, when present, says so).
    if (meta.contains("zh3_fit") || version->minor >= 1) {
      const auto f = meta.contains("zh3_fit") && meta["zh3_fit"].is_string()
                         ? parse_zh3_fit(meta["zh3_fit"].get<std::string>())
                         : std::nullopt;
      if (!f) return probe_error("meta.zh3_fit is missing or not 'explicit' or 'hallucinated'");
      fit = *f;
    }
  }
  const bool stores_zonal = encoding == ProbeEncoding::zh3 && fit == Zh3Fit::explicit_fit;
  if (!stores_zonal && t.find("zonal"))
    return probe_error("array 'zonal' in a grid whose encoding stores none (" +
                       std::string(probe_encoding_name(encoding)) +
                       (encoding == ProbeEncoding::zh3 ? ", hallucinated: the zonal coefficient comes from L1" : "") +
                       ")");
  const TableArray* co = t.find("coefficients");
  if (!co || co->shape.size() != 5) return probe_error("array 'coefficients' is missing or not of shape [NZ, NY, NX, N^2, 3]");
  const std::int64_t nz = co->shape[0], ny = co->shape[1], nx = co->shape[2], nn = t.order * t.order;
  if (nx < 1 || ny < 1 || nz < 1 || co->shape[3] != nn || co->shape[4] != 3)
    return probe_error("array 'coefficients' has shape " + shape_text(co->shape) + ", expected [NZ, NY, NX, " +
                       std::to_string(nn) + ", 3]");
  auto c = table_format::finite_f64_array(t, "coefficients", co->shape, "probe-grid table: ");
  if (!c) return c.error();
  auto b = table_format::finite_f64_array(t, "bounds", {2, 3}, "probe-grid table: ");
  if (!b) return b.error();
  const TableArray* va = t.find("valid");
  if (!va || va->dtype != DType::u8 || va->shape != std::vector<std::int64_t>{nz, ny, nx})
    return probe_error("array 'valid' is missing or not u8 of shape [NZ, NY, NX]");
  std::vector<double> zonal;
  if (stores_zonal) {
    auto z = table_format::finite_f64_array(t, "zonal", {nz, ny, nx, 3}, "probe-grid table: ");
    if (!z) return z.error();
    zonal = std::move(z).value();
  }
  ProbeGrid g;
  g.order = t.order;
  g.encoding = encoding;
  g.zh3_axis = axis;
  g.zh3_fit = fit;
  g.resolution = {static_cast<int>(nx), static_cast<int>(ny), static_cast<int>(nz)};
  for (int a = 0; a < 3; ++a) {
    const double lo = b.value()[a], hi = b.value()[3 + a];
    if (!(lo < hi)) return probe_error("bounds: min " + std::to_string(lo) + " is not below max " + std::to_string(hi));
    if (std::abs(lo) > double(std::numeric_limits<T>::max()) || std::abs(hi) > double(std::numeric_limits<T>::max()) ||
        !std::isfinite(static_cast<T>(hi) - static_cast<T>(lo)))
      return probe_error("bounds do not fit the requested precision");
    g.min[a] = static_cast<T>(lo);
    g.max[a] = static_cast<T>(hi);
  }
  for (const std::vector<double>* values : {&c.value(), &zonal})
    for (const double v : *values)
      if (!detail::within_headroom<T>(v)) return probe_error("a coefficient is too large for the requested precision");
  if (stores_zonal) {
    // One probe's values together: its L1 band, then its zonal coefficients.
    const std::size_t probes = zonal.size() / 3;
    g.coefficients.reserve(probes * 15);
    for (std::size_t p = 0; p < probes; ++p) {
      g.coefficients.insert(g.coefficients.end(), c.value().begin() + p * 12, c.value().begin() + p * 12 + 12);
      g.coefficients.insert(g.coefficients.end(), zonal.begin() + p * 3, zonal.begin() + p * 3 + 3);
    }
  } else {
    g.coefficients.assign(c.value().begin(), c.value().end());
  }
  g.valid = va->values<std::uint8_t>();
  for (const std::uint8_t v : g.valid)
    if (v > 1) return probe_error("array 'valid' holds a value other than 0 or 1");
  return g;
}

SHTOOL_LOAD_KIND_FLOAT_AND_DOUBLE(ProbeGrid, kProbeGridKind)

}  // namespace shtool
