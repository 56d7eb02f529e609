// The lighting JSON and table that `project-env` and `light` write, and that later
// commands (render, export-light) read (docs/lighting.md):
//   {"order": N, "quantity": "radiance"|"irradiance", "channels": ["r","g","b"],
//    "window": {...}, "coefficients": [[r, g, b], ... N^2 rows in index order]}
// The table (kind "env-sh", schemas/env-sh.schema.json) holds the same coefficients as
// one f64 array [N^2, 3] with the window and quantity in its meta.
#pragma once

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/enum_names.h"
#include "shtool/table.h"

namespace shtool::lighting {

enum class Quantity { radiance, irradiance };
const char* quantity_name(Quantity q);
// The (name, value) list of --quantity.
const EnumNames<Quantity>& quantity_names();

struct Lighting {
  int order = 0;
  Quantity quantity = Quantity::radiance;
  std::vector<double> coefficients;  // [i * 3 + c]
  nlohmann::json window = {{"type", "none"}};
};

std::string lighting_json(const Lighting& lighting);
Table lighting_table(const Lighting& lighting, const nlohmann::json& generator);

// Reads the lighting JSON (any order, RGB): InputError naming the file on anything else.
Lighting read_lighting_json(const std::filesystem::path& path, std::string_view what);

// Channel c of the lighting as an order-n vector: truncated, or padded with zeros (a dot
// product with an order-n quantity then uses the bands both sides have).
std::vector<double> light_channel(const Lighting& lighting, int c, int n);

}  // namespace shtool::lighting
