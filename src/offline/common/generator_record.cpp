// Identification of the offline tool, recorded in every table's "generator" field.
#include "common/generator_record.h"

#include <utility>

#include "shtool/version.h"

namespace shtool {

nlohmann::json generator_record(const std::string& command, const nlohmann::json& parameters) {
  return {{"tool", "shtool"}, {"version", kVersion}, {"command", command}, {"parameters", parameters}};
}

nlohmann::json recorded_parameters(const Table& table) {
  nlohmann::json generator = nlohmann::json::parse(table.generator, nullptr, false);
  if (!generator.is_object() || !generator.contains("parameters") || !generator["parameters"].is_object())
    return nlohmann::json::object();
  return std::move(generator["parameters"]);
}

}  // namespace shtool
