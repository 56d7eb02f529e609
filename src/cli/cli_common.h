// Shared pieces of the thin CLI layer: strict parsing of
// numeric lists, and JSON printing with round-trip precision.
#pragma once

#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <nlohmann/json.hpp>

#include "common/enum_names.h"
#include "common/input_error.h"
#include "common/mesh_frame.h"
#include "shtool/table.h"
#include "view/camera.h"

#include <CLI/CLI.hpp>

namespace shtool::cli {

// Bad input (malformed option, unreadable file, invalid table...) is
// shtool::InputError (common/input_error.h), from the libraries and the CLI alike;
// main() turns it into "shtool: error: <message>" on stderr and exit code 1.
using shtool::InputError;

// Parses "a,b,c" into finite doubles; `what` names the option in error messages.
// Throws InputError on empty fields, trailing garbage, NaN or infinity.
std::vector<double> parse_number_list(const std::string& text, const std::string& what);

// --camera of render and export-web: "eye,target,up", nine numbers in shtool's frame.
// Empty text: no camera (the mesh is framed). Throws InputError on any other count.
std::optional<view::Camera> parse_camera(const std::string& text);

// "a,b,c" -> {"a", "b", "c"}; empty items are kept (so that they can be reported).
std::vector<std::string> split_list(const std::string& text);

// An option that takes one of `names` and stores the matching enum value into `target`
// (default: whatever `target` holds, shown in --help as `default_name`). A value not in
// the list is a CLI11 error naming the option and the accepted values.
template <class E>
CLI::Option* add_enum_option(CLI::App* app, const std::string& name, E& target,
                             const EnumNames<E>& names, const std::string& help,
                             const std::string& default_name) {
  std::vector<std::string> accepted;
  for (const auto& n : names) accepted.push_back(n.first);
  return app
      ->add_option_function<std::string>(
          name,
          [&target, names](const std::string& v) {
            for (const auto& n : names)
              if (n.first == v) target = n.second;
          },
          help)
      ->check(CLI::IsMember(accepted))
      ->default_str(default_name);
}

// --up y|z: the up axis of an OBJ mesh (default y); a glTF is +Y up by its specification.
// Every command that reads a mesh takes it.
CLI::Option* add_up_option(CLI::App* app, UpAxis& target);

// --seed: `help` says what it seeds. CLI11 reads "-1" into a std::uint64_t as 2^64 - 1;
// this option refuses a sign instead.
CLI::Option* add_seed_option(CLI::App* app, std::uint64_t& target, const std::string& help);

// --threads: worker threads, 0 for all cores.
CLI::Option* add_threads_option(CLI::App* app, int& target);

// --format binary|json: the encoding of the table written (default binary).
CLI::Option* add_table_format_option(CLI::App* app, TableEncoding& target,
                                     const std::string& help = "table encoding: binary or json");

// Prints JSON to stdout followed by a newline. nlohmann-json writes doubles with the
// shortest representation that reads back to the same bits (round-trip exact).
void print_json(const nlohmann::json& value);

// Each subcommand adds its options and callback to `sub`, which main.cpp creates with
// its name and help.
void setup_eval(CLI::App* sub);
void setup_inspect(CLI::App* sub);
void setup_gen_tensors(CLI::App* sub);
void setup_gen_shader(CLI::App* sub);
void setup_render(CLI::App* sub);
void setup_deform(CLI::App* sub);
void setup_fit_wrinkles(CLI::App* sub);
void setup_fit_glossy(CLI::App* sub);
void setup_rotate(CLI::App* sub);
void setup_product(CLI::App* sub);
void setup_fit_zh(CLI::App* sub);
void setup_merge(CLI::App* sub);
void setup_search_lobes(CLI::App* sub);
void setup_project_env(CLI::App* sub);
void setup_light(CLI::App* sub);
void setup_transform_splats(CLI::App* sub);
void setup_export_light(CLI::App* sub);
void setup_import_light(CLI::App* sub);
void setup_bake_probes(CLI::App* sub);
void setup_export_web(CLI::App* sub);

}  // namespace shtool::cli
