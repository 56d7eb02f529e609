// The "generator" record of a table: which tool and version made it, with which
// command and effective parameters. Deliberately no time, host or git hash, so that
// the same inputs and seed give byte-identical tables on any machine and commit.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "shtool/table.h"

namespace shtool {

nlohmann::json generator_record(const std::string& command, const nlohmann::json& parameters);

// The "parameters" object of a table's generator record; an empty object where the
// record is not JSON or holds none (a table written by another tool), so that a caller
// reads only the keys it needs and decides what their absence means.
nlohmann::json recorded_parameters(const Table& table);

}  // namespace shtool
