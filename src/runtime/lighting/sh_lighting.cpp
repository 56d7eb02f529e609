#include "shtool/lighting.h"

#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "io/load_kind.h"
#include "shtool/env_projection.h"
#include "shtool/sh.h"

namespace shtool {

namespace {

Error lighting_error(const std::string& what) { return Error{"env-sh table: " + what}; }

}  // namespace

template <class T>
Result<ShLighting<T>> ShLighting<T>::from_table(const Table& t) {
  if (const auto problem = detail::kind_and_order_problem(t, kEnvShKind, 1, kMaxEnvOrder))
    return lighting_error(*problem);
  const TableArray* a = t.find("coefficients");
  if (!a) return lighting_error("no array 'coefficients'");
  if (a->dtype != DType::f64 || a->shape != std::vector<std::int64_t>{sh_count(t.order), kChannels})
    return lighting_error("array 'coefficients' is not f64 of shape [order^2, 3]");
  const nlohmann::json meta = nlohmann::json::parse(t.meta, nullptr, /*allow_exceptions=*/false);
  const auto q = meta.is_object() ? meta.find("quantity") : meta.end();
  if (!meta.is_object() || q == meta.end() || !q->is_string() || (*q != "radiance" && *q != "irradiance"))
    return lighting_error("meta.quantity is neither \"radiance\" nor \"irradiance\"");
  ShLighting l;
  l.order = t.order;
  l.quantity = *q == "radiance" ? LightQuantity::radiance : LightQuantity::irradiance;
  for (double v : a->values<double>()) {
    if (!std::isfinite(v)) return lighting_error("a coefficient is not finite");
    if (!detail::within_headroom<T>(v)) return lighting_error("a coefficient is too large for the requested precision");
    l.coefficients.push_back(static_cast<T>(v));
  }
  return l;
}

SHTOOL_LOAD_KIND_FLOAT_AND_DOUBLE(ShLighting, kEnvShKind)

}  // namespace shtool
