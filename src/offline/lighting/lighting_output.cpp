#include "lighting/lighting_output.h"

#include <algorithm>
#include <cmath>

#include "common/finite.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "common/table_writer.h"
#include "shtool/env_projection.h"
#include "shtool/sh.h"

namespace shtool::lighting {

const char* quantity_name(Quantity q) { return q == Quantity::radiance ? "radiance" : "irradiance"; }

const EnumNames<Quantity>& quantity_names() {
  using enum Quantity;
  static const EnumNames<Quantity> names = {{"radiance", radiance}, {"irradiance", irradiance}};
  return names;
}

std::string lighting_json(const Lighting& l) {
  check_finite(std::span<const double>(l.coefficients), "lighting coefficient");
  // Written by hand for a readable layout (one [r, g, b] row per line, the keys in the
  // documented order); every value goes through nlohmann's dump, which prints doubles
  // with the shortest text that reads back to the same bits.
  std::string out = "{\n  \"order\": " + std::to_string(l.order) + ",\n  \"quantity\": \"" +
                    quantity_name(l.quantity) + "\",\n  \"channels\": [\"r\", \"g\", \"b\"],\n  \"window\": " +
                    l.window.dump() + ",\n  \"coefficients\": [\n";
  for (int i = 0; i < sh_count(l.order); ++i) {
    out += "    " + nlohmann::json({l.coefficients[3 * i], l.coefficients[3 * i + 1], l.coefficients[3 * i + 2]}).dump();
    out += i + 1 < sh_count(l.order) ? ",\n" : "\n";
  }
  return out + "  ]\n}\n";
}

Table lighting_table(const Lighting& l, const nlohmann::json& generator) {
  Table t = new_table(kEnvShKind, l.order, generator,
                      {{"quantity", quantity_name(l.quantity)}, {"channels", {"r", "g", "b"}}, {"window", l.window}});
  t.arrays.push_back(TableArray::from<double>("coefficients", {sh_count(l.order), 3}, l.coefficients));
  return t;
}

Lighting read_lighting_json(const std::filesystem::path& path, std::string_view what) {
  const nlohmann::json doc = read_json_input(path, what);
  auto bad = [&](const std::string& why) -> InputError {
    return InputError(std::string(what) + " '" + path.string() + "': " + why);
  };
  if (!doc.is_object()) throw bad("not a lighting JSON object");
  Lighting l;
  const auto order = doc.find("order");
  if (order == doc.end() || !order->is_number_integer() || order->get<long long>() < 1 ||
      order->get<long long>() > kMaxEnvOrder)
    throw bad("\"order\" must be an integer in 1.." + std::to_string(kMaxEnvOrder));
  l.order = order->get<int>();
  const auto q = doc.find("quantity");
  if (q == doc.end() || !q->is_string() || (*q != "radiance" && *q != "irradiance"))
    throw bad("\"quantity\" must be \"radiance\" or \"irradiance\"");
  l.quantity = *q == "radiance" ? Quantity::radiance : Quantity::irradiance;
  const auto channels = doc.find("channels");
  if (channels == doc.end() || *channels != nlohmann::json({"r", "g", "b"}))
    throw bad("\"channels\" must be [\"r\", \"g\", \"b\"]");
  const auto rows = doc.find("coefficients");
  if (rows == doc.end() || !rows->is_array() || rows->size() != static_cast<std::size_t>(sh_count(l.order)))
    throw bad("\"coefficients\" must hold order^2 = " + std::to_string(sh_count(l.order)) + " rows");
  for (std::size_t i = 0; i < rows->size(); ++i) {
    const nlohmann::json& row = (*rows)[i];
    if (!row.is_array() || row.size() != 3) throw bad("coefficient row " + std::to_string(i) + " is not [r, g, b]");
    for (const nlohmann::json& v : row) {
      if (!v.is_number() || !std::isfinite(v.get<double>()))
        throw bad("coefficient row " + std::to_string(i) + " holds a value that is not a finite number");
      l.coefficients.push_back(v.get<double>());
    }
  }
  if (const auto w = doc.find("window"); w != doc.end()) l.window = *w;
  return l;
}

std::vector<double> light_channel(const Lighting& lighting, int c, int n) {
  std::vector<double> e(static_cast<std::size_t>(n) * n, 0.0);
  const std::size_t shared = std::min<std::size_t>(e.size(), lighting.coefficients.size() / 3);
  for (std::size_t i = 0; i < shared; ++i) e[i] = lighting.coefficients[i * 3 + c];
  return e;
}

}  // namespace shtool::lighting
