#include "deform/deform_job.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <Eigen/Dense>

#include "common/job_outputs.h"
#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/table_writer.h"
#include "fit/deformation.h"
#include "fit/zh_fit_table.h"
#include "shtool/rotation.h"

namespace shtool::deform {

using fit::deform_fit;
using fit::fit_for_mesh;

DeformReport run_deform(const DeformRequest& r) {
  if (r.out.empty()) throw InputError("--out is required");
  JobOutputs io;
  io.input(r.fit, "the fit");
  io.input(r.rest, "the rest mesh");
  io.input(r.pose, "the posed mesh");
  io.output(r.out, "--out");
  io.output(r.json, "--json");
  if (r.pose.empty()) throw InputError("--pose is required");
  Result<Table> input = read_table(r.fit, TableExpectation{std::string(kZhFitKind), 1, 0});
  if (!input) throw InputError(input.error().message);
  const fit::PosedMesh meshes = fit::load_posed_mesh(io, r.rest, r.pose, r.up, fit::recorded_normals(input.value()));
  const fit::Mesh& rest = meshes.rest;
  const fit::Mesh& posed = *meshes.posed;
  // A texture-space bake's rows are texels, not vertices.
  const nlohmann::json input_meta = table_meta(input.value());
  if (input_meta.is_object() && input_meta.contains("texture"))
    throw InputError(r.fit.string() + ": a texture-space bake (fit-zh --texture); deform takes per-vertex bakes");
  check_same_up(input.value(), rest.up, r.fit.string(), r.rest.string());
  fit::check_same_mesh(input.value(), rest, r.rest, r.fit.string());
  Result<ZhFitTable<double>> loaded = ZhFitTable<double>::from_table(input.value());
  if (!loaded) throw InputError(r.fit.string() + ": " + loaded.error().message);
  const ZhFitTable<double> fit = fit_for_mesh(std::move(loaded).value(), rest, r.fit.string());
  const std::vector<Eigen::Matrix3d>& rotations = meshes.rotations;
  const ZhFitTable<double> moved = deform_fit(fit, rotations);

  DeformReport report;
  report.vertices = moved.vertices;
  for (const Eigen::Matrix3d& m : rotations)
    report.largest_angle = std::max(report.largest_angle, std::acos(std::clamp((m.trace() - 1) / 2, -1.0, 1.0)));
  const nlohmann::json params = {{"fit", r.fit.filename().string()},
                                 {"rest", r.rest.filename().string()},
                                 {"rest_crc32", rest.input_crc32},
                                 {"pose", r.pose.filename().string()},
                                 {"pose_crc32", posed.input_crc32},
                                 // The table belongs to the posed mesh: render and deform
                                 // check it against the mesh they are given, as any bake.
                                 {"mesh_crc32", fit::loaded_mesh_crc32(posed)},
                                 {"normals", posed.normals_from_file ? "file" : "computed"},
                                 {"up", up_axis_name(rest.up)}};
  const nlohmann::json meta = {{"mode", "deformed"}, {"direct", moved.direct_count}, {kMeshUpKey, up_axis_name(rest.up)}};
  const Table table = fit::zh_fit_table(moved, meta, generator_record("shtool deform", params));
  io.set("--out", encode_table(table));
  if (io.requested("--json")) io.set("--json", fit::fits_json(moved));
  io.commit();
  return report;
}

}  // namespace shtool::deform
