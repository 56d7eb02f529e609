// shtool gen-tensors: writes the precomputed tables the runtime needs.
#include <filesystem>
#include <fstream>
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
#include "tensors/fourier_tables.h"
#include "tensors/rotation_helpers_gen.h"
#include "tensors/rotation_kernels_gen.h"
#include "tensors/tripling_kernels_gen.h"
#include "tensors/tripling.h"

namespace shtool::cli {
namespace {

struct GenTensorsOptions {
  int order = 8;
  std::string out = "tables";
  std::string what = "rotation,tripling,fourier";
  int inputs = kFourierTableDefaultInputs;
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
      if (item != "rotation" && item != "tripling" && item != "fourier" && item != "rotation-kernels" &&
          item != "tripling-kernels")
        throw UserError("--what: unknown table '" + item +
                        "' (known: rotation, tripling, fourier, rotation-kernels, tripling-kernels)");
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

  if (opt.inputs < 2 || opt.inputs > 8)
    throw UserError("--inputs must be between 2 and 8, got " + std::to_string(opt.inputs));
  if (what.count("tripling") && opt.order > kMaxTriplingOrder)
    throw UserError("--what tripling supports orders up to " + std::to_string(kMaxTriplingOrder));
  nlohmann::json params = {{"order", opt.order}, {"what", opt.what}, {"format", opt.format}};
  if (what.count("fourier")) params["inputs"] = opt.inputs;
  const nlohmann::json generator = generator_record("shtool gen-tensors", params);
  if (what.count("rotation")) {
    const RotationHelpers h = compute_rotation_helpers(opt.order);
    const std::filesystem::path path = std::filesystem::path(opt.out) / ("rotation-helpers" + ext);
    write_or_throw(h.to_table(generator), path, encoding);
    std::cerr << "gen-tensors: wrote " << path.string() << " (order " << opt.order << ", X90 "
              << h.x90_val.size() << " non-zeros)\n";
  }
  // C++ sources of the runtime's generated kernels (src/runtime); independent of --order
  // and --format. Written to a temporary file, then renamed.
  auto write_source = [&](const char* file, const std::string& text, const char* label) {
    const std::filesystem::path path = std::filesystem::path(opt.out) / file;
    const std::filesystem::path tmp = path.string() + ".tmp";
    {
      std::ofstream f(tmp, std::ios::binary);
      f << text;
      f.close();
      if (!f) throw UserError("cannot write '" + tmp.string() + "'");
    }
    std::filesystem::rename(tmp, path, ec);
    if (ec) throw UserError("cannot write '" + path.string() + "': " + ec.message());
    std::cerr << "gen-tensors: wrote " << path.string() << " (" << label << ")\n";
  };
  if (what.count("rotation-kernels"))
    write_source(kRotationKernelsFile, rotation_kernels_source(), "rotation kernels");
  if (what.count("tripling-kernels"))
    write_source(kTriplingKernelsFile, tripling_kernels_source(), "tripling kernels");
  if (what.count("tripling")) {
    const Table t = tripling_tensor_table(opt.order, generator);
    const std::filesystem::path path = std::filesystem::path(opt.out) / ("tripling-tensor" + ext);
    write_or_throw(t, path, encoding);
    std::cerr << "gen-tensors: wrote " << path.string() << " (order " << opt.order << ", "
              << t.arrays.back().element_count() << " non-zeros)\n";
  }
  if (what.count("fourier")) {
    const Table t = sh_fourier_tensors_table(opt.order, opt.inputs, generator);
    const std::filesystem::path path = std::filesystem::path(opt.out) / ("sh-fourier-tensors" + ext);
    write_or_throw(t, path, encoding);
    std::cerr << "gen-tensors: wrote " << path.string() << " (order " << opt.order << ", products of up to "
              << opt.inputs << " inputs)\n";
  }
}

}  // namespace

void setup_gen_tensors(CLI::App& app) {
  auto opt = std::make_shared<GenTensorsOptions>();
  CLI::App* sub = app.add_subcommand("gen-tensors", "Generate tensor and rotation tables");
  sub->add_option("--order", opt->order, "SH order N (bands 0..N-1)")->capture_default_str();
  sub->add_option("--out", opt->out, "output folder")->capture_default_str();
  sub->add_option("--what", opt->what,
                  "comma-separated tables: rotation (zxzxz/Taylor helpers), tripling (tripling "
                  "tensor), fourier (SH<->Fourier tensors); rotation-kernels and tripling-kernels "
                  "write the C++ source of the runtime's fixed-order rotation and tripling kernels "
                  "(for src/runtime)")
      ->capture_default_str();
  sub->add_option("--inputs", opt->inputs, "fourier: largest number of product inputs covered (2..8)")
      ->capture_default_str();
  sub->add_option("--format", opt->format, "binary (.shtb) or json (.json)")->capture_default_str();
  sub->callback([opt]() { run_gen_tensors(*opt); });
}

}  // namespace shtool::cli
