// Written files checked against the project's JSON schemas by tests/validate_json_schema.py
// (python3-jsonschema), the validator the schemas are published for, not a C++ one.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "run_command.h"

namespace shtool::test {

// Every file (a JSON document or a table, whose header is checked) valid against
// schemas/<schema>; one Python run for all of them.
inline void expect_valid_against_schema(const std::string& schema, const std::vector<std::filesystem::path>& files) {
  const std::string source = SHTOOL_SOURCE_DIR;
  std::vector<std::string> argv = {SHTOOL_PYTHON, source + "/tests/validate_json_schema.py",
                                   source + "/schemas/" + schema};
  for (const std::filesystem::path& f : files) argv.push_back(f.string());
  const CommandResult r = run_command(argv);
  EXPECT_EQ(r.exit_code, 0) << describe_command(argv) << "\n" << r.out << r.err;
}

}  // namespace shtool::test
