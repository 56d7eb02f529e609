#include "wrinkles/wrinkle_job.h"

#include <cmath>
#include <string>

#include "common/job_outputs.h"
#include "common/finite.h"
#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/stopwatch.h"
#include "common/table_writer.h"
#include "fit/embree_scene.h"
#include "shtool/wrinkle_map.h"

namespace shtool::wrinkles {

namespace {

nlohmann::json parameters(const WrinkleRequest& r) {
  return {{"order", r.order},         {"lobes", r.lobes}, {"grid", r.grid},
          {"samples", r.samples},     {"max_depth", r.max_depth}, {"rays", r.rays},
          {"seed", r.seed},           {"max_evaluations", r.max_evaluations},
          {"optimizer", r.optimizer == WrinkleOptimizer::cg ? "cg" : "lbfgs"}};
}

}  // namespace

void check_request(const WrinkleRequest& r) {
  // Order 3 is the least that leaves a band for the lobes once DC and linear are direct.
  check_option_range("--order", r.order, 3, kMaxWrinkleOrder);
  check_option_range("--lobes", r.lobes, 1, kMaxWrinkleLobes);
  check_option_range("--grid", r.grid, 2, 256);
  check_option_range("--samples", r.samples, 1, 16);
  check_option_range("--rays", r.rays, 1, 1 << 20);
  check_option_range("--max-evaluations", r.max_evaluations, 1, 1000000);
  // Each sample holds a transfer vector and is simulated and fitted: the product of the two
  // ranges (16.7 million samples, 5 GB and hours at --grid 256 --samples 16) is bounded.
  const std::size_t samples = WrinkleGrid{r.grid, r.samples, 1.0}.sample_count();
  if (samples > kMaxWrinkleSamples)
    throw InputError("--grid " + std::to_string(r.grid) + " with --samples " + std::to_string(r.samples) + " makes " +
                     std::to_string(samples) + " samples ((G S) x ((G - 1) S + 1)); at most " +
                     std::to_string(kMaxWrinkleSamples) + " are simulated: lower --samples");
  if (!std::isfinite(r.max_depth) || r.max_depth <= 0 || r.max_depth > 4)
    throw InputError("--max-depth must be in (0, 4] periods, got " + std::to_string(r.max_depth));
  resolve_threads(r.threads);
  if (r.out.empty()) throw InputError("--out is required");
}

Table wrinkle_table(const WrinkleFit& fit, const WrinkleRequest& r) {
  const WrinkleModel& m = fit.model;
  const std::int64_t g = m.grid.grid, nl = m.lobes, n = m.order;
  nlohmann::json generator = generator_record("shtool fit-wrinkles", parameters(r));
  const fit::EmbreeIdentity embree = fit::embree_identity();
  generator["embree"] = {{"version", embree.version}, {"isa", embree.isa}};
  const nlohmann::json meta = {
      {"lobes", m.lobes},
      {"grid", m.grid.grid},
      {"max_depth", m.grid.max_depth},
      {"normalized_rms", fit.errors.global},
      {"per_point_normalized_rms", fit.errors.per_point},
      {"evaluations", fit.evaluations},
      {"layout",
       "node (k, j) at depth[k], x[j]; at (x, d) blend the 4 surrounding nodes bilinearly (x periodic with period 1), "
       "normalise each blended axis; lobe i adds coeffs[i][l] y_l^m(axis) to SH (l, m); direct = DC, then band 1"}};
  Table t = new_table(kWrinkleZhKind, m.order, generator, meta);
  std::vector<double> xs(g), ds(g);
  for (int j = 0; j < g; ++j) xs[j] = m.grid.node_x(j);
  for (int k = 0; k < g; ++k) ds[k] = m.grid.node_depth(k);
  t.arrays.push_back(TableArray::from<double>("x", {g}, xs));
  t.arrays.push_back(TableArray::from<double>("depth", {g}, ds));
  t.arrays.push_back(TableArray::from<double>("axes", {g, g, nl, 3}, m.axes));
  t.arrays.push_back(TableArray::from<double>("coeffs", {g, g, nl, n}, m.coeffs));
  t.arrays.push_back(TableArray::from<double>("direct", {g, g, kDirectCoefficients}, m.direct));
  return t;
}

nlohmann::json wrinkle_summary(const WrinkleFit& fit, const WrinkleRequest& r) {
  const WrinkleGrid& grid = fit.model.grid;
  nlohmann::json rows = nlohmann::json::array();
  for (int k = 0; k < grid.sample_rows(); ++k) {
    double g = 0, p = 0, t = 0;
    for (int i = 0; i < grid.sample_columns(); ++i) {
      const std::size_t s = grid.sample_index(i, k);
      g += fit.global_residual2[s];
      p += fit.per_point_residual2[s];
      t += fit.norm2[s];
    }
    rows.push_back({{"depth", grid.sample_depth(k)}, {"global", std::sqrt(g / t)}, {"per_point", std::sqrt(p / t)}});
  }
  return {{"parameters", parameters(r)},
          {"samples", grid.sample_count()},
          {"evaluations", fit.evaluations},
          {"normalized_rms",
           {{"global", fit.errors.global},
            {"per_point", fit.errors.per_point},
            {"node_fits_interpolated", fit.errors.node_fits},
            {"start", fit.errors.start}}},
          {"by_depth", rows}};
}

WrinkleReport run_fit_wrinkles(const WrinkleRequest& r) {
  check_request(r);
  JobOutputs io;
  io.output(r.out, "--out");
  io.output(r.json, "--json");
  const WrinkleGrid grid{r.grid, r.samples, r.max_depth};
  WrinkleReport report;
  PhaseTimer timer;
  const std::vector<double> transfer = simulate_transfer(grid, {r.order, r.rays, r.seed, r.threads});
  report.simulation_seconds = timer.lap();
  const WrinkleFitOptions options{.order = r.order, .lobes = r.lobes, .seed = r.seed, .threads = r.threads,
                                  .max_evaluations = r.max_evaluations, .optimizer = r.optimizer};
  const WrinkleFit fit = fit_wrinkles(grid, transfer, options);
  report.fit_seconds = timer.lap();
  report.errors = fit.errors;
  report.evaluations = fit.evaluations;
  report.samples = grid.sample_count();
  report.parameters = static_cast<std::size_t>(grid.nodes()) * r.lobes * (3 + r.order - 2);

  const Table table = wrinkle_table(fit, r);
  // The map as an engine loads it: a fit the runtime would refuse is an error, not a file.
  if (const Result<WrinkleMap<double>> loads = WrinkleMap<double>::from_table(table); !loads)
    throw InputError("fit-wrinkles: the fitted map would not load: " + loads.error().message +
                     " (nothing written; another --grid, --samples or --lobes may fit)");
  io.set("--out", encode_table(table));
  if (io.requested("--json")) io.set("--json", dump_finite(wrinkle_summary(fit, r), "--json", 2) + "\n");
  io.commit();
  return report;
}

}  // namespace shtool::wrinkles
