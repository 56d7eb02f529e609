// shtool light: analytic lights as SH (docs/lighting.md), in the lighting JSON that
// project-env writes. One light from the command line, or several from a JSON list,
// summed.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/enum_names.h"
#include "lighting/lighting_output.h"

namespace shtool::lighting {

enum class LightType { directional, cone, sphere, hemisphere, constant };
const EnumNames<LightType>& light_type_names();

struct LightSpec {
  LightType type = LightType::directional;
  std::optional<std::array<double, 3>> direction;  // need not be unit; not zero
  std::optional<double> half_angle_degrees;         // cone, sphere
  std::array<double, 3> color{1, 1, 1};             // sky colour for hemisphere
  std::array<double, 3> ground{0, 0, 0};            // hemisphere only
};

struct LightRequest {
  std::vector<LightSpec> lights;     // from the command line (at most one) ...
  std::filesystem::path list;        // ... or a JSON list of lights
  int order = 3;
  Quantity quantity = Quantity::radiance;
  std::filesystem::path json;
  std::filesystem::path out;
  TableEncoding encoding = TableEncoding::binary;
};

// The lights of a JSON list: [{"type": "cone", "dir": [x, y, z], "half_angle": 5,
// "color": [r, g, b], "ground": [r, g, b]}, ...] (keys as the options). InputError
// naming the file and the light on anything else.
std::vector<LightSpec> parse_light_list(std::string_view text, const std::filesystem::path& path);

// The summed lights (checked: directions, angles, colours).
Lighting light_coefficients(const std::vector<LightSpec>& lights, int order, Quantity quantity);

Lighting run_light(const LightRequest& request);

}  // namespace shtool::lighting
