// shtool inspect TABLE [--json]: header, summary and checksum verification of a table.
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_common.h"

namespace shtool::cli {

void setup_inspect(CLI::App& app) {
  (void)app;  // registered by the table module (see table.cpp work in progress)
}

}  // namespace shtool::cli
