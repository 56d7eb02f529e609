#include "tensors/gen_tensors_job.h"

#include <algorithm>
#include <string>
#include <system_error>

#include <nlohmann/json.hpp>

#include "common/job_outputs.h"
#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/table_writer.h"
#include "shtool/sh.h"
#include "shtool/tripling_product.h"
#include "tensors/fourier_tables.h"
#include "tensors/rotation_helpers_gen.h"
#include "tensors/rotation_kernels_gen.h"
#include "tensors/tripling.h"
#include "tensors/tripling_kernels_gen.h"

namespace shtool {

const std::vector<std::string>& gen_tensors_items() {
  static const std::vector<std::string> items = {"rotation", "tripling", "fourier", "rotation-kernels",
                                                 "tripling-kernels"};
  return items;
}

std::vector<GeneratedFile> run_gen_tensors(const GenTensorsRequest& r) {
  if (!is_supported_order(r.order))
    throw InputError("--order " + std::to_string(r.order) + " is not supported (1.." + std::to_string(kMaxOrder) +
                     ")");
  if (r.what.empty()) throw InputError("--what: nothing to generate");
  for (const std::string& item : r.what)
    if (std::find(gen_tensors_items().begin(), gen_tensors_items().end(), item) == gen_tensors_items().end())
      throw InputError("--what: unknown table '" + item +
                       "' (known: rotation, tripling, fourier, rotation-kernels, tripling-kernels)");
  auto wanted = [&](const char* item) { return std::find(r.what.begin(), r.what.end(), item) != r.what.end(); };
  if (r.inputs < 2 || r.inputs > 8)
    throw InputError("--inputs must be between 2 and 8, got " + std::to_string(r.inputs));
  if (wanted("tripling") && r.order > kMaxTriplingOrder)
    throw InputError("--what tripling supports orders up to " + std::to_string(kMaxTriplingOrder));
  const bool json = r.encoding == TableEncoding::json;
  const std::string ext = json ? ".json" : ".shtb";
  std::string what_text;
  for (const std::string& item : r.what) what_text += (what_text.empty() ? "" : ",") + item;
  nlohmann::json params = {{"order", r.order}, {"what", what_text}, {"format", json ? "json" : "binary"}};
  if (wanted("fourier")) params["inputs"] = r.inputs;
  const nlohmann::json generator = generator_record("shtool gen-tensors", params);

  // An existing folder: the outputs are declared (and checked) before the work, as every
  // job does. A missing one is made only once every file's bytes are ready, so that a
  // computation that fails (out of memory, say) leaves no folder behind.
  check_output_folder(r.out, "--out");
  std::error_code ec;
  const bool folder_exists = std::filesystem::is_directory(r.out, ec);
  const std::vector<std::string> names = [&] {
    std::vector<std::string> n;
    if (wanted("rotation")) n.push_back("rotation-helpers" + ext);
    if (wanted("rotation-kernels")) n.push_back(kRotationKernelsFile);
    if (wanted("tripling-kernels")) n.push_back(kTriplingKernelsFile);
    if (wanted("tripling")) n.push_back("tripling-tensor" + ext);
    if (wanted("fourier")) n.push_back("sh-fourier-tensors" + ext);
    return n;
  }();
  JobOutputs io;
  auto declare = [&] {
    for (const std::string& name : names) io.output(r.out / name, name);
  };
  if (folder_exists) declare();

  std::vector<GeneratedFile> files;
  std::vector<std::string> contents;  // in the order of `names`
  auto add = [&](const std::string& name, std::string bytes, std::string summary) {
    files.push_back({r.out / name, std::move(summary)});
    contents.push_back(std::move(bytes));
  };
  if (wanted("rotation")) {
    const RotationHelpers h = compute_rotation_helpers(r.order);
    add("rotation-helpers" + ext, encode_table(to_table(h, generator), r.encoding),
        "order " + std::to_string(r.order) + ", X90 " + std::to_string(h.x90_val.size()) + " non-zeros");
  }
  if (wanted("rotation-kernels")) add(kRotationKernelsFile, rotation_kernels_source(), "rotation kernels");
  if (wanted("tripling-kernels")) add(kTriplingKernelsFile, tripling_kernels_source(), "tripling kernels");
  if (wanted("tripling")) {
    const Table t = tripling_tensor_table(r.order, generator);
    add("tripling-tensor" + ext, encode_table(t, r.encoding),
        "order " + std::to_string(r.order) + ", " + std::to_string(t.arrays.back().element_count()) +
            " non-zeros");
  }
  if (wanted("fourier"))
    add("sh-fourier-tensors" + ext, encode_table(sh_fourier_tensors_table(r.order, r.inputs, generator), r.encoding),
        "order " + std::to_string(r.order) + ", products of up to " + std::to_string(r.inputs) + " inputs");

  // The missing folder (and its missing parents), removed again if the files cannot be
  // written.
  MadeFolders folders;
  if (!folder_exists) {
    folders.make(r.out, "--out");
    declare();
  }
  for (std::size_t i = 0; i < names.size(); ++i) io.set(names[i], std::move(contents[i]));
  io.commit();
  folders.keep();
  return files;
}

}  // namespace shtool
