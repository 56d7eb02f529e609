#include "glossy/glossy_job.h"

#include <cmath>
#include <string>

#include "common/finite.h"
#include "common/job_outputs.h"
#include "common/enum_names.h"
#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/stopwatch.h"
#include "common/table_writer.h"
#include "fit/deformation.h"
#include "fit/embree_scene.h"
#include "fit/mesh.h"
#include "fit/zh_fit_table.h"
#include "glossy/glossy_transfer.h"
#include "shtool/glossy.h"
#include "shtool/sh.h"

namespace shtool::glossy {
namespace {

nlohmann::json parameters(const GlossyRequest& r) {
  return {{"mesh", r.mesh.filename().string()},
          {"brdf", name_of(r.brdf.model, brdf_model_names())},
          {"roughness", r.brdf.roughness},
          {"f0", r.brdf.f0},
          {"order", r.order},
          {"terms", r.terms},
          {"lobes", r.lobes},
          {"view_resolution", r.view_resolution},
          {"rays", r.rays},
          {"mode", r.shadowed ? "shadowed" : "unshadowed"},
          {"seed", r.seed},
          {"effort", r.effort},
          {"normals", name_of(r.normals, fit::normal_source_names())}};
}

}  // namespace

void check_request(const GlossyRequest& r) {
  if (r.mesh.empty()) throw InputError("a mesh is required");
  check_option_range("--order", r.order, 2, 8);
  check_option_range("--view-resolution", r.view_resolution, 2, 256);
  // B has G^2 rows and n^2 columns: its SVD has min(G^2, n^2) singular values to keep.
  check_option_range("--terms", r.terms, 1,
                     std::min({kMaxGlossyTerms, r.order * r.order, r.view_resolution * r.view_resolution}));
  check_option_range("--lobes", r.lobes, 1, 16);
  check_option_range("--rays", r.rays, 1, 1 << 20);
  check_option_range("--effort", r.effort, fit::kMinEffort, fit::kMaxEffort);
  // Below 0.05 the lobe is narrower than the BRDF quadrature resolves (and than an order-8
  // expansion could show); above 1 the Phong exponent would be negative.
  if (!(r.brdf.roughness >= 0.05 && r.brdf.roughness <= 1))
    throw InputError("--roughness must be in [0.05, 1], got " + std::to_string(r.brdf.roughness));
  if (!(r.brdf.f0 >= 0 && r.brdf.f0 <= 1)) throw InputError("--f0 must be in [0, 1], got " + std::to_string(r.brdf.f0));
  resolve_threads(r.threads);
  if (r.out.empty()) throw InputError("--out is required");
}

GlossyReport run_fit_glossy(const GlossyRequest& r) {
  check_request(r);
  JobOutputs io;
  io.input(r.mesh, "the mesh");
  io.output(r.out, "--out");
  io.output(r.json, "--json");
  const int threads = resolve_threads(r.threads);
  const fit::Mesh mesh = fit::load_mesh(r.mesh, r.normals, r.up);
  io.inputs(mesh.files, "a file of the mesh");
  const std::vector<Eigen::Matrix3d> frames = fit::vertex_frames(mesh, mesh);
  GlossyReport report;
  report.vertices = mesh.positions.size();

  PhaseTimer timer;
  const Eigen::MatrixXd b = brdf_matrix(r.brdf, r.order, r.view_resolution, threads);
  const BrdfFactors factors = factor_brdf(b, r.terms);
  const Eigen::MatrixXd gram = b.transpose() * b;
  report.brdf_seconds = timer.lap();
  report.singular_values.assign(factors.singular_values.data(),
                                factors.singular_values.data() + factors.singular_values.size());

  GlossyTransferOptions to;
  to.order = r.order;
  to.rays = r.rays;
  to.seed = r.seed;
  to.shadowed = r.shadowed;
  to.threads = threads;
  GlossyTransfer transfer = glossy_transfer(mesh, frames, factors.rows, gram, to);
  report.simulate_seconds = timer.lap();

  fit::ZhFitOptions fo;
  fo.order = r.order;
  fo.lobes = r.lobes;
  fo.direct = true;  // [4] Sec. 3.3: DC (and, from 3 lobes, the linear band) stored directly
  fit::apply_effort(fo, r.effort);
  fo.seed = r.seed;
  const ZhFitTable<double> fits = fit::fit_zh_all(transfer.rows, fo, threads);
  report.fit_seconds = timer.lap();
  std::vector<double>().swap(transfer.rows);

  double residual2 = 0;
  for (const double e : fits.residual) residual2 += e * e;
  const double exit2 = transfer.exit_norm2;
  report.svd_nrms = exit2 > 0 ? std::sqrt(std::max(0.0, exit2 - transfer.rows_norm2) / exit2) : 0.0;
  report.zh_nrms = exit2 > 0 ? std::sqrt(residual2 / exit2) : 0.0;
  report.total_nrms = std::hypot(report.svd_nrms, report.zh_nrms);
  report.rows_nrms = fit::normalized_rms(fits);

  nlohmann::json params = parameters(r);
  params["input_crc32"] = mesh.input_crc32;
  params["mesh_crc32"] = fit::loaded_mesh_crc32(mesh);
  params["up"] = up_axis_name(mesh.up);
  nlohmann::json generator = generator_record("shtool fit-glossy", params);
  if (r.shadowed) {
    const fit::EmbreeIdentity embree = fit::embree_identity();
    generator["embree"] = {{"version", embree.version}, {"isa", embree.isa}};
  }
  nlohmann::json meta = {{"vertices", report.vertices},
                         {"terms", r.terms},
                         {"view_resolution", r.view_resolution},
                         {"brdf", {{"model", name_of(r.brdf.model, brdf_model_names())},
                                   {"roughness", r.brdf.roughness},
                                   {"f0", r.brdf.f0}}},
                         {"svd_normalized_rms", report.svd_nrms},
                         {"zh_normalized_rms", report.zh_nrms},
                         {"total_normalized_rms", report.total_nrms},
                         {"singular_values", report.singular_values},
                         {kMeshUpKey, up_axis_name(mesh.up)}};
  Table table = fit::zh_fit_table(fits, meta, generator);
  table.kind = std::string(kGlossyZhKind);
  table.kind_version = "1.0";
  nlohmann::json full_meta = table_meta(table);
  full_meta["layout"] =
      "rows v * n_b + j: the ZH fit of row j of vertex v's M' (axes, coeffs, direct as in zh-fit; residual and "
      "norm of the row); view_factors[b][a][j] = u_j(v) at the centre of texel (a, b) of the concentric map; "
      "vertex_index[v] = OBJ vertex";
  table.meta = full_meta.dump();
  const auto g = static_cast<std::int64_t>(r.view_resolution);
  std::vector<double> u(static_cast<std::size_t>(g * g) * r.terms);
  for (std::int64_t i = 0; i < g * g; ++i)
    for (int j = 0; j < r.terms; ++j) u[i * r.terms + j] = factors.view_factors(i, j);
  table.arrays.push_back(TableArray::from<double>("view_factors", {g, g, r.terms}, u));
  table.arrays.push_back(TableArray::from<std::uint32_t>(
      "vertex_index", {static_cast<std::int64_t>(report.vertices)}, mesh.source_index));

  io.set("--out", encode_table(table));
  if (io.requested("--json")) {
    nlohmann::json summary = {{"parameters", parameters(r)},
                                    {"vertices", report.vertices},
                                    {"singular_values", report.singular_values},
                                    {"normalized_rms",
                                     {{"svd", report.svd_nrms},
                                      {"zh", report.zh_nrms},
                                      {"total", report.total_nrms},
                                      {"zh_of_rows", report.rows_nrms}}}};
    summary["parameters"]["up"] = up_axis_name(mesh.up);
    io.set("--json", dump_finite(summary, "--json", 2) + "\n");
  }
  io.commit();
  return report;
}

}  // namespace shtool::glossy
