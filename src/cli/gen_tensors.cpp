// shtool gen-tensors: writes the precomputed tables the runtime needs.
#include <filesystem>
#include <iostream>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "offline_version.h"
#include "shtool/sh.h"
#include "shtool/table.h"
#include "tensors/rotation_helpers_gen.h"

namespace shtool::cli {
namespace {

struct GenTensorsOptions {
  int order = 8;
  std::string out = "tables";
  std::string what = "rotation";
  std::string format = "binary";
};

void write_or_throw(const Table& table, const std::filesystem::path& path, TableEncoding encoding) {
  const TableResult<TableOk> written = write_table(table, path, encoding);
  if (!written) throw UserError(written.error().message);
}

void run_gen_tensors(const GenTensorsOptions& opt) {
  if (!is_supported_order(opt.order))
    throw UserError("--order " + std::to_string(opt.order) + " is not supported (1.." +
                    std::to_string(kMaxOrder) + ")");
  std::set<std::string> what;
  {
    std::stringstream ss(opt.what);
    std::string item;
    while (std::getline(ss, item, ',')) {
      if (item != "rotation")
        throw UserError("--what: unknown table '" + item + "' (known: rotation)");
      what.insert(item);
    }
  }
  if (what.empty()) throw UserError("--what: nothing to generate");
  if (opt.format != "binary" && opt.format != "json")
    throw UserError("--format must be 'binary' or 'json', got '" + opt.format + "'");
  const TableEncoding encoding = opt.format == "json" ? TableEncoding::json : TableEncoding::binary;
  const std::string ext = opt.format == "json" ? ".json" : ".shtb";
  std::error_code ec;
  std::filesystem::create_directories(opt.out, ec);
  if (ec) throw UserError("cannot create output folder '" + opt.out + "': " + ec.message());

  const nlohmann::json params = {{"order", opt.order}, {"what", opt.what}, {"format", opt.format}};
  const nlohmann::json generator = generator_record("shtool gen-tensors", params);
  if (what.count("rotation")) {
    const RotationHelpers h = compute_rotation_helpers(opt.order);
    const std::filesystem::path path = std::filesystem::path(opt.out) / ("rotation-helpers" + ext);
    write_or_throw(h.to_table(generator), path, encoding);
    std::cerr << "gen-tensors: wrote " << path.string() << " (order " << opt.order << ", X90 "
              << h.x90_val.size() << " non-zeros)\n";
  }
}

}  // namespace

void setup_gen_tensors(CLI::App& app) {
  auto opt = std::make_shared<GenTensorsOptions>();
  CLI::App* sub = app.add_subcommand("gen-tensors", "Generate tensor and rotation tables");
  sub->add_option("--order", opt->order, "SH order N (bands 0..N-1)")->capture_default_str();
  sub->add_option("--out", opt->out, "output folder")->capture_default_str();
  sub->add_option("--what", opt->what, "comma-separated tables: rotation")->capture_default_str();
  sub->add_option("--format", opt->format, "binary (.shtb) or json (.json)")->capture_default_str();
  sub->callback([opt]() { run_gen_tensors(*opt); });
}

}  // namespace shtool::cli
