// The "generator" record of a table: which tool and version made it, with which
// command and effective parameters. Deliberately no time, host or git hash, so that
// the same inputs and seed give byte-identical tables on any machine and commit.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace shtool {

nlohmann::json generator_record(const std::string& command, const nlohmann::json& parameters);

}  // namespace shtool
