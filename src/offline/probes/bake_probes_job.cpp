#include "probes/bake_probes_job.h"

#include <chrono>
#include <cmath>
#include <algorithm>
#include <cstdlib>
#include <limits>
#include <optional>
#include <span>
#include <sstream>

#include "common/finite.h"
#include "common/generator_record.h"
#include "common/input_file.h"
#include "common/input_error.h"
#include "common/job_outputs.h"
#include "common/parallel_for.h"
#include "common/table_writer.h"
#include "fit/embree_scene.h"
#include "fit/mpi_world.h"
#include "interop/three_probe_grid.h"
#include "lighting/lighting_output.h"
#include "probes/probe_grid_table.h"
#include "shtool/probe_grid.h"

namespace shtool::probes {
namespace {

// Comma-separated fields, each a whole number or a finite decimal as `what` says.
std::vector<std::string> fields(const std::string& text) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, ',')) out.push_back(item);
  if (!text.empty() && text.back() == ',') out.push_back("");
  return out;
}

double parse_double(const std::string& s, const std::string& option) {
  const char* begin = s.c_str();
  char* end = nullptr;
  const double v = std::strtod(begin, &end);
  if (s.empty() || end == begin || *end != '\0' || !std::isfinite(v))
    throw InputError(option + ": '" + s + "' is not a finite number");
  return v;
}

// --encoding with --zh3-fit and --zh3-axis, which mean something for zh3 only.
GridEncoding parse_encoding(const BakeProbesRequest& r) {
  const std::optional<ProbeEncoding> e = parse_probe_encoding(r.encoding);
  if (!e) throw InputError("--encoding: '" + r.encoding + "' is not one of l2, l1, zh3");
  GridEncoding g;
  g.encoding = *e;
  for (const auto& [option, value] : {std::pair<const char*, const std::string*>{"--zh3-fit", &r.zh3_fit},
                                      std::pair<const char*, const std::string*>{"--zh3-axis", &r.zh3_axis}})
    if (!value->empty() && g.encoding != ProbeEncoding::zh3)
      throw InputError(std::string(option) + " applies to --encoding zh3 only (the grid's encoding is " + r.encoding +
                       ", which has no zonal coefficient)");
  if (!r.zh3_fit.empty()) {
    const std::optional<Zh3Fit> f = parse_zh3_fit(r.zh3_fit);
    if (!f) throw InputError("--zh3-fit: '" + r.zh3_fit + "' is not one of explicit, hallucinated");
    g.zh3_fit = *f;
  }
  if (!r.zh3_axis.empty()) {
    const std::optional<Zh3Axis> a = parse_zh3_axis(r.zh3_axis);
    if (!a) throw InputError("--zh3-axis: '" + r.zh3_axis + "' is not one of luminance, per-channel");
    g.zh3_axis = *a;
  }
  return g;
}

// Why three.js cannot take an l1 grid (checked before the bake and by three_coefficients).
const std::string kThreeL1 = std::string("--threejs with --encoding l1: ") + interop::kThreeCannotShowL1;

}  // namespace

std::array<int, 3> parse_grid(const std::string& text) {
  const std::vector<std::string> f = fields(text);
  if (f.size() != 3) throw InputError("--grid must be NX,NY,NZ (three whole numbers), got '" + text + "'");
  std::array<int, 3> n{};
  std::size_t total = 1;
  for (int a = 0; a < 3; ++a) {
    const char* begin = f[a].c_str();
    char* end = nullptr;
    const long long v = std::strtoll(begin, &end, 10);
    if (f[a].empty() || end == begin || *end != '\0')
      throw InputError("--grid: '" + f[a] + "' is not a whole number");
    if (v < 1 || v > kMaxAxisProbes)
      throw InputError("--grid: each count must be in 1.." + std::to_string(kMaxAxisProbes) + ", got " + f[a]);
    n[a] = static_cast<int>(v);
    total *= static_cast<std::size_t>(v);
  }
  if (total > kMaxProbes)
    throw InputError("--grid: " + std::to_string(total) + " probes, more than " + std::to_string(kMaxProbes));
  return n;
}

std::pair<Eigen::Vector3d, Eigen::Vector3d> parse_bounds(const std::string& text) {
  const std::vector<std::string> f = fields(text);
  if (f.size() != 6) throw InputError("--bounds must be X0,Y0,Z0,X1,Y1,Z1 (six numbers), got '" + text + "'");
  Eigen::Vector3d lo, hi;
  for (int a = 0; a < 3; ++a) {
    lo[a] = parse_double(f[a], "--bounds");
    hi[a] = parse_double(f[3 + a], "--bounds");
    if (std::max(std::abs(lo[a]), std::abs(hi[a])) > fit::kMaxCoordinate)
      throw InputError("--bounds: " + f[std::abs(lo[a]) > fit::kMaxCoordinate ? a : 3 + a] +
                       " lies beyond +-1e15, which single-precision ray tracing cannot reach");
  }
  for (int a = 0; a < 3; ++a)
    if (!(lo[a] < hi[a]))
      throw InputError(std::string("--bounds: min ") + "xyz"[a] + " (" + f[a] + ") must be below max " + "xyz"[a] +
                       " (" + f[3 + a] + ")");
  return {lo, hi};
}

BakeProbesReport run_bake_probes(const BakeProbesRequest& r) {
  const auto t0 = std::chrono::steady_clock::now();
  if (r.scene.empty()) throw InputError("a scene file (glTF or OBJ) is required");
  if (r.out.empty()) throw InputError("--out is required");
  check_option_range("--order", r.order, 1, kMaxOrder);
  check_option_range("--samples", r.samples, 1, kMaxSamples);
  check_option_range("--bounces", r.bounces, 0, kMaxBounces);
  const GridEncoding encoding = parse_encoding(r);
  if (r.order < lowest_bake_order(encoding))
    throw InputError("--encoding " + r.encoding + " needs --order " + std::to_string(lowest_bake_order(encoding)) +
                     " or more (" +
                     (encoding.stores_zonal() ? "its zonal coefficient is fitted to band 2" : "it stores bands 0 and 1") +
                     "), got --order " + std::to_string(r.order));
  if (encoding.encoding == ProbeEncoding::l1 && !r.threejs.empty()) throw InputError(kThreeL1);
  ProbeGridSpec spec;
  spec.resolution = parse_grid(r.grid);
  std::optional<std::pair<Eigen::Vector3d, Eigen::Vector3d>> bounds;
  if (!r.bounds.empty()) bounds = parse_bounds(r.bounds);
  spec.order = r.order;
  spec.samples = r.samples;
  spec.bounces = r.bounces;
  spec.seed = r.seed;
  spec.threads = resolve_threads(r.threads);
  std::optional<fit::Shard> shard;
  if (!r.shard.empty()) {
    if (r.mpi) throw InputError("--mpi and --shard both split the probes: give one of them");
    shard = fit::parse_shard(r.shard);
    if (!r.json.empty())
      throw InputError("--json needs the whole grid: not with --shard (shtool merge --json writes it from the parts)");
    if (!r.threejs.empty())
      throw InputError("--threejs needs the whole grid: not with --shard (shtool merge --threejs writes it from the parts)");
    if (shard->count > spec.probe_count())
      throw InputError("--shard " + r.shard + ": more shards than the grid's " + std::to_string(spec.probe_count()) +
                       " probes");
  }
  // Under MPI, rank R of S bakes shard R/S; rank 0 gathers the parts and joins them as
  // merge does, so the bytes are a one-process run's.
  std::optional<fit::MpiJob> mpi;
  if (r.mpi) {
    mpi.emplace();
    if (static_cast<std::size_t>(mpi->size()) > spec.probe_count())
      throw InputError("--mpi: " + std::to_string(mpi->size()) + " ranks for the grid's " +
                       std::to_string(spec.probe_count()) + " probes");
    shard = fit::Shard{static_cast<std::size_t>(mpi->rank()), static_cast<std::size_t>(mpi->size())};
  }

  JobOutputs io;
  io.input(r.scene, "the scene");
  io.input(r.env, "--env");
  io.output(r.out, "--out");
  io.output(r.json, "--json");
  if (!r.threejs.empty()) interop::declare_three_probe_grid(io, r.threejs, "--threejs");

  Environment env;
  nlohmann::json params = {{"scene", r.scene.filename().string()}};
  if (!r.env.empty()) {
    const lighting::Lighting l = lighting::read_lighting_json(r.env, "--env");
    if (l.quantity != lighting::Quantity::radiance)
      throw InputError(r.env.string() + ": --env needs radiance coefficients (this file holds irradiance)");
    env.order = l.order;
    env.coefficients = l.coefficients;
  }
  scene::Scene s = scene::load_scene(r.scene, r.up);
  io.inputs(s.mesh.files, "a file of the scene");
  if (bounds) {
    spec.lower = bounds->first;
    spec.upper = bounds->second;
  } else {
    spec.lower = s.lower();
    spec.upper = s.upper();
    for (int a = 0; a < 3; ++a)
      if (!(spec.lower[a] < spec.upper[a]))
        throw InputError(r.scene.string() + ": the scene's bounding box is flat along " + std::string(1, "xyz"[a]) +
                         ": give --bounds");
  }

  const fit::VertexRange range = shard ? fit::shard_range(spec.probe_count(), *shard)
                                       : fit::VertexRange{0, spec.probe_count()};
  const ProbeBake bake = shard ? bake_probe_range(s, spec, env, range.begin, range.end) : bake_probe_grid(s, spec, env);
  check_finite(std::span<const double>(bake.coefficients), "probe coefficient");

  params["input_crc32"] = s.mesh.input_crc32;
  params["mesh_crc32"] = fit::loaded_mesh_crc32(s.mesh);
  params["up"] = up_axis_name(s.mesh.up);
  params["grid"] = {spec.resolution[0], spec.resolution[1], spec.resolution[2]};
  params["bounds"] = {{"min", {spec.lower.x(), spec.lower.y(), spec.lower.z()}},
                      {"max", {spec.upper.x(), spec.upper.y(), spec.upper.z()}}};
  params["bounds_from"] = bounds ? "option" : "scene";
  params["order"] = r.order;
  params["samples"] = r.samples;
  params["bounces"] = r.bounces;
  params["seed"] = r.seed;
  params["encoding"] = probe_encoding_name(encoding.encoding);
  if (encoding.encoding == ProbeEncoding::zh3) {
    params["zh3_axis"] = zh3_axis_name(encoding.zh3_axis);
    params["zh3_fit"] = zh3_fit_name(encoding.zh3_fit);
  }
  if (!r.env.empty()) {
    params["env"] = r.env.filename().string();
    params["env_crc32"] = input_crc32(read_input_file(r.env, "--env"));
  }
  nlohmann::json generator = generator_record("shtool bake-probes", params);
  const fit::EmbreeIdentity embree = fit::embree_identity();
  generator["embree"] = {{"version", embree.version}, {"isa", embree.isa}};

  std::size_t invalid = 0;
  for (const std::uint8_t v : bake.valid) invalid += v ? 0 : 1;
  nlohmann::json meta;
  meta[kMeshUpKey] = up_axis_name(s.mesh.up);
  meta["triangles"] = s.mesh.triangles.size();
  meta["lights"] = s.lights.size();

  // The whole grid's outputs (docs/probe-encodings.md for three.js's atlas).
  const auto set_whole = [&](const EncodedProbes& probes, const Table& table) {
    io.set("--out", encode_table(table));
    if (io.requested("--json")) io.set("--json", dump_finite(probe_grid_json(spec, probes), "--json") + "\n");
    if (r.threejs.empty()) return;
    interop::ThreeProbeGridInput three;
    three.resolution = spec.resolution;
    three.min = spec.lower;
    three.max = spec.upper;
    three.coefficients = three_coefficients(probes, three.order, "--threejs");
    interop::set_three_probe_grid(io, "--threejs", interop::three_probe_grid_files(three));
  };

  BakeProbesReport report;
  if (mpi) {
    report.mpi_rank = mpi->rank();
    report.mpi_ranks = mpi->size();
    const std::string mine = encode_table(probe_grid_part_table(spec, bake, *shard, range, generator, meta));
    if (!mpi->all_ok(true)) throw InputError("rank " + std::to_string(mpi->rank()) + ": stopped, another rank failed");
    const std::vector<std::string> parts = mpi->gather(mine);
    if (mpi->rank() == 0) {
      std::vector<std::pair<std::string, Table>> tables;
      for (std::size_t k = 0; k < parts.size(); ++k) {
        const std::string name = "rank " + std::to_string(k);
        Result<Table> t = read_table_bytes(std::as_bytes(std::span(parts[k])), name, {std::string(kProbeGridKind), 1});
        if (!t) throw InputError("--mpi: " + t.error().message);
        tables.emplace_back(name, std::move(t).value());
      }
      const MergedProbeGrid merged = merge_probe_grid(tables);
      set_whole(merged.probes, merged.table);
      io.commit();
    }
  } else {
    if (shard) {
      io.set("--out", encode_table(probe_grid_part_table(spec, bake, *shard, range, generator, meta)));
    } else {
      const EncodedProbes probes = encode_probes(bake, spec.order, encoding);
      set_whole(probes, probe_grid_table(spec, probes, generator, meta));
    }
    io.commit();
  }

  report.probes = range.end - range.begin;
  report.invalid = invalid;
  report.unfilled = bake.unfilled;
  report.resolution = spec.resolution;
  report.lower = spec.lower;
  report.upper = spec.upper;
  report.triangles = s.mesh.triangles.size();
  report.lights = s.lights.size();
  report.unsupported_lights = s.unsupported_lights;
  report.rays = bake.rays;
  report.sharded = shard.has_value() && !mpi;
  report.first_probe = range.begin;
  report.end_probe = range.end;
  report.encoding = std::string(probe_encoding_name(encoding.encoding));
  if (encoding.encoding == ProbeEncoding::zh3)
    report.encoding += " " + std::string(zh3_fit_name(encoding.zh3_fit)) + ", " +
                       std::string(zh3_axis_name(encoding.zh3_axis)) + " axis";
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace shtool::probes
