// fit-wrinkles as a library job: simulate the wrinkle model's transfer over its (x, d)
// samples, fit it globally and per point, write the map table (kind "wrinkle-zh") and,
// optionally, a JSON summary. docs/ldprt.md, "Wrinkles".
#pragma once

#include <cstdint>
#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "shtool/table.h"
#include "wrinkles/wrinkle_fit.h"

namespace shtool::wrinkles {

struct WrinkleRequest {
  int order = 6;           // [4] Sec. 7: n = 6 for the diffuse textures
  int lobes = 3;           // [4] Sec. 4.2
  int grid = 32;           // [4] Sec. 4.2: a 32 x 32 map
  int samples = 2;         // samples per cell and axis
  double max_depth = 1.0;  // in periods
  int rays = 1024;
  std::uint64_t seed = 1;
  int threads = 0;
  int max_evaluations = 1000;
  WrinkleOptimizer optimizer = WrinkleOptimizer::lbfgs;
  std::filesystem::path out;   // the wrinkle-zh table
  std::filesystem::path json;  // optional summary
};

struct WrinkleReport {
  FitErrors errors;
  int evaluations = 0;
  std::size_t samples = 0;
  std::size_t parameters = 0;
  double simulation_seconds = 0, fit_seconds = 0;
};

// Throws InputError naming the option when a value is out of range.
void check_request(const WrinkleRequest& request);

// The table of a fit (kind "wrinkle-zh", docs/table-format.md).
Table wrinkle_table(const WrinkleFit& fit, const WrinkleRequest& request);
// The JSON summary: settings, the four normalised RMS figures, and per sample row of
// depth the global and per-point figures.
nlohmann::json wrinkle_summary(const WrinkleFit& fit, const WrinkleRequest& request);

// Checks, runs, writes (both outputs or neither).
WrinkleReport run_fit_wrinkles(const WrinkleRequest& request);

}  // namespace shtool::wrinkles
