#include "lighting/light_job.h"

#include <cmath>
#include <numbers>

#include "common/job_outputs.h"
#include "common/enum_names.h"
#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "common/table_writer.h"
#include "shtool/analytic_lights.h"
#include "shtool/env_projection.h"
#include "shtool/irradiance.h"
#include "shtool/sh.h"

namespace shtool::lighting {
namespace {

std::string type_name(LightType t) { return name_of(t, light_type_names()); }

nlohmann::json spec_json(const LightSpec& s) {
  nlohmann::json j = {{"type", type_name(s.type)}, {"color", s.color}};
  if (s.direction) j["dir"] = *s.direction;
  if (s.half_angle_degrees) j["half_angle"] = *s.half_angle_degrees;
  if (s.type == LightType::hemisphere) j["ground"] = s.ground;
  return j;
}

}  // namespace

const EnumNames<LightType>& light_type_names() {
  using enum LightType;
  static const EnumNames<LightType> names = {
      {"directional", directional}, {"cone", cone}, {"sphere", sphere}, {"hemisphere", hemisphere},
      {"constant", constant}};
  return names;
}

std::vector<LightSpec> parse_light_list(std::string_view text, const std::filesystem::path& path) {
  const nlohmann::json doc = parse_json_input(text, path, "--lights");
  auto bad = [&](std::size_t k, const std::string& why) {
    return InputError("--lights '" + path.string() + "': light " + std::to_string(k) + ": " + why);
  };
  if (!doc.is_array() || doc.empty()) throw InputError("--lights '" + path.string() + "': expected a non-empty JSON list of lights");
  std::vector<LightSpec> lights;
  for (std::size_t k = 0; k < doc.size(); ++k) {
    const nlohmann::json& j = doc[k];
    if (!j.is_object()) throw bad(k, "not an object");
    LightSpec s;
    const auto type = j.find("type");
    bool known = false;
    if (type != j.end() && type->is_string())
      for (const auto& [n, v] : light_type_names())
        if (*type == n) s.type = v, known = true;
    if (!known) throw bad(k, "\"type\" must be directional, cone, sphere, hemisphere or constant");
    auto triple = [&](const char* key) {
      const nlohmann::json& v = j.at(key);
      if (!v.is_array() || v.size() != 3) throw bad(k, std::string("\"") + key + "\" must be [x, y, z]");
      std::array<double, 3> out{};
      for (int i = 0; i < 3; ++i) {
        if (!v[i].is_number()) throw bad(k, std::string("\"") + key + "\" must hold numbers");
        out[i] = v[i].get<double>();
      }
      return out;
    };
    for (const auto& [key, value] : j.items()) {
      if (key == "type") continue;
      if (key == "dir") s.direction = triple("dir");
      else if (key == "color") s.color = triple("color");
      else if (key == "ground") {
        if (s.type != LightType::hemisphere)
          throw bad(k, "\"ground\" is a hemisphere light's (its lower half's colour)");
        s.ground = triple("ground");
      }
      else if (key == "half_angle") {
        if (!value.is_number()) throw bad(k, "\"half_angle\" must be a number (degrees)");
        s.half_angle_degrees = value.get<double>();
      } else
        throw bad(k, "unknown key \"" + key + "\" (type, dir, half_angle, color, ground)");
    }
    lights.push_back(s);
  }
  return lights;
}

Lighting light_coefficients(const std::vector<LightSpec>& lights, int order, Quantity quantity) {
  if (order < 1 || order > kMaxEnvOrder)
    throw InputError("--order " + std::to_string(order) + " is outside 1.." + std::to_string(kMaxEnvOrder));
  Lighting out;
  out.order = order;
  out.quantity = quantity;
  out.coefficients.assign(static_cast<std::size_t>(sh_count(order)) * 3, 0.0);
  for (std::size_t k = 0; k < lights.size(); ++k) {
    const LightSpec& s = lights[k];
    const std::string who = "light " + std::to_string(k) + " (" + type_name(s.type) + "): ";
    for (double v : s.color)
      if (!std::isfinite(v)) throw InputError(who + "the colour must be finite");
    for (double v : s.ground)
      if (!std::isfinite(v)) throw InputError(who + "the ground colour must be finite");
    Eigen::Vector3d d = Eigen::Vector3d::UnitZ();
    if (s.type == LightType::constant && s.direction)
      throw InputError(who + "takes no direction (it is the same from all)");
    if (s.type != LightType::constant) {
      if (!s.direction) throw InputError(who + "needs a direction (--dir x,y,z; \"dir\" in a list)");
      d = Eigen::Vector3d((*s.direction)[0], (*s.direction)[1], (*s.direction)[2]);
      // Scaled by its largest component first: the norm of (1e200, 1e200, 1e200) or of
      // (1e-200, ...) is out of a double's range, the direction is not.
      const double largest = d.cwiseAbs().maxCoeff();
      if (!d.allFinite() || largest == 0) throw InputError(who + "the direction must be finite and not zero");
      d = (d / largest).normalized();
    }
    const bool angled = s.type == LightType::cone || s.type == LightType::sphere;
    if (angled && !s.half_angle_degrees)
      throw InputError(who + "needs a half-angle in degrees (--half-angle; \"half_angle\" in a list)");
    if (!angled && s.half_angle_degrees) throw InputError(who + "takes no half-angle");
    if (angled && !(*s.half_angle_degrees > 0 && *s.half_angle_degrees <= 180))
      throw InputError(who + "the half-angle must be in (0, 180] degrees");
    switch (s.type) {
      case LightType::directional: add_directional_light(d, s.color, 3, out.coefficients); break;
      case LightType::cone:
      case LightType::sphere:
        add_cone_light(d, *s.half_angle_degrees * std::numbers::pi / 180, s.color, 3, out.coefficients);
        break;
      case LightType::hemisphere: add_hemisphere_light(d, s.color, s.ground, 3, out.coefficients); break;
      case LightType::constant: add_constant_light(s.color, 3, out.coefficients); break;
    }
  }
  if (quantity == Quantity::irradiance) radiance_to_irradiance(3, out.coefficients);
  for (double v : out.coefficients)
    if (!std::isfinite(v)) throw InputError("the lights' coefficients overflow a double (colours too large)");
  return out;
}

Lighting run_light(const LightRequest& r) {
  if (r.json.empty()) throw InputError("--json is required");
  std::vector<LightSpec> lights = r.lights;
  nlohmann::json params = {{"order", r.order}, {"quantity", quantity_name(r.quantity)}};
  JobOutputs io;
  io.input(r.list, "the --lights list");
  io.output(r.json, "--json");
  io.output(r.out, "--out");
  if (!r.list.empty()) {
    if (!lights.empty()) throw InputError("--lights replaces --type and its options: give one or the other");
    const std::string text = read_input_file(r.list, "--lights");
    lights = parse_light_list(text, r.list);
    params["lights_file"] = r.list.filename().string();
    params["input_crc32"] = input_crc32(text);
  }
  if (lights.empty()) throw InputError("no light: give --type (and its options) or --lights LIST.json");
  const Lighting l = light_coefficients(lights, r.order, r.quantity);
  nlohmann::json specs = nlohmann::json::array();
  for (const LightSpec& s : lights) specs.push_back(spec_json(s));
  params["lights"] = specs;
  io.set("--json", lighting_json(l));
  if (io.requested("--out"))
    io.set("--out", encode_table(lighting_table(l, generator_record("shtool light", params)), r.encoding));
  io.commit();
  return l;
}

}  // namespace shtool::lighting
