// Identification of the offline tool, recorded in every table's "generator" field.
#include "common/generator_record.h"

#include "shtool/version.h"

namespace shtool {

nlohmann::json generator_record(const std::string& command, const nlohmann::json& parameters) {
  return {{"tool", "shtool"}, {"version", kVersion}, {"command", command}, {"parameters", parameters}};
}

}  // namespace shtool
