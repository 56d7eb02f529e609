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
  if (t.kind != kEnvShKind) return lighting_error("wrong kind '" + t.kind + "'");
  if (t.order < 1 || t.order > kMaxEnvOrder)
    return lighting_error("order " + std::to_string(t.order) + " outside 1.." + std::to_string(kMaxEnvOrder));
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
    l.coefficients.push_back(static_cast<T>(v));
  }
  return l;
}

template <class T>
Result<ShLighting<T>> ShLighting<T>::load(const std::filesystem::path& path) {
  return detail::load_kind<ShLighting>(path, kEnvShKind);
}

template struct ShLighting<float>;
template struct ShLighting<double>;

}  // namespace shtool
