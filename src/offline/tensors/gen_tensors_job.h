// gen-tensors as a library job: the tables the runtime needs and the C++ sources of its
// generated kernels, computed, then written all together or not at all.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "shtool/table.h"
#include "tensors/fourier_tables.h"

namespace shtool {

struct GenTensorsRequest {
  int order = 8;                      // SH order N of the tables (bands 0..N-1)
  std::filesystem::path out = "tables";  // output folder (created if missing)
  // Any of "rotation", "tripling", "fourier" (tables), "rotation-kernels",
  // "tripling-kernels" (C++ sources, independent of order and encoding).
  std::vector<std::string> what = {"rotation", "tripling", "fourier"};
  int inputs = kFourierTableDefaultInputs;  // fourier: largest number of product inputs covered (2..8)
  TableEncoding encoding = TableEncoding::binary;
};

// One written file and a one-line description of it.
struct GeneratedFile {
  std::filesystem::path path;
  std::string summary;  // e.g. "order 8, X90 342 non-zeros"
};

// The names of the items `what` may hold.
const std::vector<std::string>& gen_tensors_items();

// Checks the request (InputError naming the option), computes every item, then writes
// them atomically as one set. Returns the files in the order of gen_tensors_items().
std::vector<GeneratedFile> run_gen_tensors(const GenTensorsRequest& request);

}  // namespace shtool
