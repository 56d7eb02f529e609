// shtool: one executable, one subcommand per file in src/cli/. Each file registers its
// options with setup_<name>(app) and does its work through the libraries; errors are
// turned into a message and an exit code here, in one place.
#include <exception>
#include <iostream>
#include <new>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "shtool/version.h"

int main(int argc, char** argv) {
  CLI::App app{"shtool: spherical-harmonics precomputation (lobe search, ZH fitting, tensors) "
               "lighting projection, and checks of the runtime library"};
  app.set_version_flag("--version", std::string("shtool ") + shtool::kVersion);
  // 0..1 rather than exactly 1, so that an unknown subcommand is reported by name.
  app.require_subcommand(0, 1);
  shtool::cli::setup_eval(app);
  shtool::cli::setup_inspect(app);
  shtool::cli::setup_gen_tensors(app);
  shtool::cli::setup_gen_shader(app);
  shtool::cli::setup_render(app);
  shtool::cli::setup_deform(app);
  shtool::cli::setup_fit_wrinkles(app);
  shtool::cli::setup_fit_glossy(app);
  shtool::cli::setup_rotate(app);
  shtool::cli::setup_product(app);
  shtool::cli::setup_fit_zh(app);
  shtool::cli::setup_merge(app);
  shtool::cli::setup_search_lobes(app);
  shtool::cli::setup_project_env(app);
  shtool::cli::setup_light(app);
  shtool::cli::setup_transform_splats(app);
  shtool::cli::setup_export_light(app);
  shtool::cli::setup_import_light(app);
  shtool::cli::setup_bake_probes(app);
  shtool::cli::setup_export_web(app);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help/--version exit 0; every command-line error exits 1 like other user errors.
    return app.exit(e) == 0 ? 0 : 1;
  } catch (const shtool::InputError& e) {
    std::cerr << "shtool: error: " << e.what() << '\n';
    return 1;
  } catch (const std::bad_alloc&) {
    // An input too large for this machine (the jobs refuse what they can estimate first).
    std::cerr << "shtool: error: out of memory\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "shtool: internal error: " << e.what() << '\n';
    return 3;
  }
  if (app.get_subcommands().empty()) {
    std::cerr << "shtool: error: a subcommand is required\n" << app.help();
    return 1;
  }
  return 0;
}
