// shtool: one executable, one subcommand per file in src/cli/. Each file registers its
// options with setup_<name>(app) and does its work through the libraries; errors are
// turned into a message and an exit code here, in one place.
#include <exception>
#include <iostream>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "shtool/version.h"

int main(int argc, char** argv) {
  CLI::App app{"shtool: spherical-harmonics precomputation (lobe search, ZH fitting, tensors) "
               "and checks of the runtime library"};
  app.set_version_flag("--version", std::string("shtool ") + shtool::kVersion);
  app.require_subcommand(1);
  shtool::cli::setup_eval(app);
  shtool::cli::setup_inspect(app);
  shtool::cli::setup_gen_tensors(app);
  shtool::cli::setup_rotate(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e);
  } catch (const shtool::cli::UserError& e) {
    std::cerr << "shtool: error: " << e.what() << '\n';
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "shtool: internal error: " << e.what() << '\n';
    return 3;
  }
  return 0;
}
