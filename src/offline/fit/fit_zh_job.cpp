#include "fit/fit_zh_job.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <numbers>
#include <optional>
#include <span>
#include <sstream>

#include <nlohmann/json.hpp>

#include "common/job_outputs.h"
#include "common/enum_names.h"
#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "common/parallel_for.h"
#include "common/stopwatch.h"
#include "common/table_writer.h"
#include "fit/embree_scene.h"
#include "fit/mpi_world.h"
#include "fit/shard.h"
#include "fit/texture_bake.h"
#include "fit/zh_fit.h"
#include "fit/zh_fit_gltf.h"
#include "fit/zh_fit_merge.h"
#include "fit/transfer_file.h"
#include "fit/zh_fit_table.h"
#include "shtool/sh.h"

namespace shtool::fit {

void check_fit_options(const FitZhRequest& r) {
  if (r.lobes < 1 || r.lobes > 64) throw InputError("--lobes must be in 1..64, got " + std::to_string(r.lobes));
  if (r.effort < kMinEffort || r.effort > kMaxEffort)
    throw InputError("--effort must be in " + std::to_string(kMinEffort) + ".." + std::to_string(kMaxEffort) +
                     ", got " + std::to_string(r.effort));
  if (r.starts && *r.starts < 0) throw InputError("--starts must be >= 0, got " + std::to_string(*r.starts));
  // Recorded in the table's generator record, which holds finite numbers only.
  if (r.restart_above && !(*r.restart_above >= 0 && std::isfinite(*r.restart_above)))
    throw InputError("--restart-above must be a finite number >= 0");
  if (r.threads < 0) throw InputError("--threads must be >= 0");
}

ZhFitOptions fit_zh_options(const FitZhRequest& r, int order) {
  check_fit_options(r);
  ZhFitOptions fo;
  fo.order = order;
  fo.lobes = r.lobes;
  fo.direct = r.direct;
  fo.method = r.fit_method;
  apply_effort(fo, r.effort);
  if (r.starts) fo.starts = *r.starts;
  if (r.restart_above) fo.restart_above = *r.restart_above;
  fo.seed = r.seed;
  return fo;
}

namespace {

std::string ply_text(const Mesh& mesh, const std::vector<double>& transfer, int order,
                     const ZhFitTable<double>& fits) {
  std::ostringstream s;
  s.precision(9);
  s << "ply\nformat ascii 1.0\ncomment shtool fit-zh: colour = transfer DC (grey, 1 = unshadowed), "
       "red where the fit error is high\n"
    << "comment frame: shtool's, right-handed, z up"
    << (mesh.up == UpAxis::y ? " (read from a y-up file: shtool = (X, -Z, Y) of its coordinates)"
                               : " (read from a z-up file: its coordinates as written)")
    << "\nelement vertex " << mesh.positions.size() << "\nproperty float x\nproperty float y\nproperty float z\n"
    << "property float nx\nproperty float ny\nproperty float nz\n"
    << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    << "property float transfer_dc\nproperty float fit_error\n"
    << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  const std::size_t n2 = sh_count(order);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const double dc = transfer_dc_grey(transfer[v * n2]);
    const double err = fits.norm[v] > 0 ? fits.residual[v] / fits.norm[v] : 0.0;
    const double e = std::clamp(4.0 * err, 0.0, 1.0);  // 25% relative error is full red
    auto byte = [](double x) { return static_cast<int>(std::lround(255.0 * x)); };
    const Eigen::Vector3d& p = mesh.positions[v];
    const Eigen::Vector3d& n = mesh.normals[v];
    s << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << n.x() << ' ' << n.y() << ' ' << n.z() << ' '
      << byte(dc * (1 - e) + e) << ' ' << byte(dc * (1 - e)) << ' ' << byte(dc * (1 - e)) << ' '
      << transfer[v * n2] << ' ' << err << '\n';
  }
  for (const Eigen::Vector3i& t : mesh.triangles) s << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  return s.str();
}

void check_request(const FitZhRequest& r) {
  if (r.mesh.empty() == r.transfer.empty())
    throw InputError(r.mesh.empty() ? "give a mesh (MESH.obj) or --transfer FILE"
                                    : "give either a mesh or --transfer FILE, not both");
  if (!is_supported_order(r.order)) throw InputError("--order " + std::to_string(r.order) + " is not supported");
  if (r.rays < 1) throw InputError("--rays must be at least 1, got " + std::to_string(r.rays));
  check_fit_options(r);
  if (r.mode == TransferMode::interreflected) {
    if (r.bounces < 1 || r.bounces > kMaxBounces)
      throw InputError("--bounces must be in 1.." + std::to_string(kMaxBounces) + ", got " + std::to_string(r.bounces));
    if (!(r.albedo >= 0 && r.albedo < 1)) throw InputError("--albedo must be in [0, 1)");
  }
  if (!r.transfer.empty() && !r.ply.empty()) throw InputError("--ply needs a mesh (not --transfer)");
  if (!r.transfer.empty() && !r.save_transfer.empty())
    throw InputError("--save-transfer needs a mesh (not --transfer)");
  if (!r.transfer.empty() && !r.gltf.empty()) throw InputError("--gltf needs a mesh (not --transfer)");
  // Binary glTF under another name would be read as JSON by loaders that go by the name.
  if (!r.gltf.empty() && lowercase_extension(r.gltf) != ".glb")
    throw InputError("--gltf " + r.gltf.string() + ": the output is binary glTF, so its name must end in .glb");
  if (r.mpi) {
    if (!r.shard.empty()) throw InputError("--mpi and --shard both split the vertices: give one of them");
    if (!r.ply.empty() || !r.save_transfer.empty())
      throw InputError(std::string(r.ply.empty() ? "--save-transfer" : "--ply") +
                       " is not written with --mpi: rank 0 gathers the fits, not the transfer vectors");
  }
  if (r.texture) {
    if (*r.texture < 1 || *r.texture > kMaxTextureResolution)
      throw InputError("--texture " + std::to_string(*r.texture) + ": the resolution must be in 1.." +
                       std::to_string(kMaxTextureResolution));
    if (!r.transfer.empty()) throw InputError("--texture needs a mesh with texture coordinates (not --transfer)");
    // The rows are texels: the per-vertex outputs and the vertex splits have nothing to hold.
    const std::pair<bool, const char*> vertex_only[] = {
        {!r.ply.empty(), "--ply"}, {!r.gltf.empty(), "--gltf"}, {!r.shard.empty(), "--shard"}, {r.mpi, "--mpi"}};
    for (const auto& [given, what] : vertex_only)
      if (given) throw InputError(std::string(what) + " is per vertex: it does not combine with --texture");
  }
  if (!r.shard.empty()) {
    if (r.mode == TransferMode::interreflected && !r.mesh.empty())
      throw InputError("--shard cannot split an interreflected bake: each bounce needs the previous bounce of "
                       "every vertex; run it in one process or under MPI (--mpi)");
    // A shard writes one table; the other outputs describe the whole mesh and come from
    // the merged run.
    const std::pair<const std::filesystem::path*, const char*> whole_mesh_outputs[] = {
        {&r.json, "--json"}, {&r.ply, "--ply"}, {&r.save_transfer, "--save-transfer"}, {&r.gltf, "--gltf"}};
    for (const auto& [path, what] : whole_mesh_outputs)
      if (!path->empty())
        throw InputError(std::string(what) + " is not written with --shard: a shard writes its partial table only "
                         "(shtool merge joins them)");
  }
}

}  // namespace



namespace {

// Where the job runs: its outputs' paths and the rows it fits (its shard, or its rank's
// share of an MPI job).
struct FitZhPlan {
  std::optional<Shard> shard;    // --shard: a partial table
  std::optional<Shard> rows_of;  // --shard, or this rank of --mpi
  int threads = 1;
  std::filesystem::path out, dc_linear_map, lobes_map;
};

// Step 1, the inputs: the transfer vectors of the rows this run fits, read from
// --transfer or simulated on the mesh, with their provenance.
struct FitZhInputs {
  Mesh mesh;             // empty with --transfer
  TexelSamples texels;   // --texture
  std::vector<double> transfer;
  int order = 0;
  std::size_t total = 0;  // vertices, texels or vectors of the whole input
  VertexRange range;      // the rows this run fits
  nlohmann::json params, meta = nlohmann::json::object();
  double simulate_seconds = 0;
};

FitZhInputs read_inputs(const FitZhRequest& r, const FitZhCallbacks& cb, MpiJob* mpi, const FitZhPlan& plan,
                        JobOutputs& io) {
  FitZhInputs in;
  in.order = r.order;
  // A shard past the input's last vertex would write an empty table merge cannot check.
  auto shard_range_of = [&](const Shard& s, std::size_t count) {
    const std::string items = std::to_string(count) + (r.mesh.empty() ? " vectors" : " vertices");
    if (s.count > count && mpi)
      throw InputError("--mpi: " + std::to_string(s.count) + " ranks for " + items +
                       " would leave some without work (run at most " + std::to_string(count) + " ranks)");
    if (s.count > count)
      throw InputError("--shard " + r.shard + ": " + std::to_string(s.count) + " shards of " + items +
                       " would leave some empty (N must be at most " + std::to_string(count) + ")");
    return shard_range(count, s);
  };
  if (!r.transfer.empty()) {
    // The simulation's options do nothing to given vectors: said, not refused, since a
    // script may pass one set of options to both kinds of run.
    if (cb.warning) {
      const FitZhRequest defaults;
      std::string unused;
      auto note = [&](bool changed, const char* option) {
        if (changed) unused += (unused.empty() ? "" : ", ") + std::string(option);
      };
      note(r.rays != defaults.rays, "--rays");
      note(r.mode != defaults.mode, "--mode");
      note(r.bounces != defaults.bounces, "--bounces");
      note(r.albedo != defaults.albedo, "--albedo");
      note(r.normals != defaults.normals, "--normals");
      note(r.up != defaults.up, "--up");
      if (!unused.empty())
        cb.warning(unused +
                   ": nothing to do with --transfer (these set how transfer is simulated on a mesh; the "
                   "vectors are given)");
    }
    const std::string text = read_input_file(r.transfer, "--transfer");
    int file_order = 0;
    TransferMeshRecord record;
    in.transfer = parse_transfer_json(text, r.transfer, file_order, &record);
    // Vectors simulated on a mesh keep its frame record, so that render checks the fit.
    if (!record.mesh_up.empty()) in.meta[kMeshUpKey] = record.mesh_up;
    if (r.order_given && file_order != r.order)
      throw InputError("--order " + std::to_string(r.order) + " but --transfer '" + r.transfer.string() +
                       "' has order " + std::to_string(file_order));
    in.order = file_order;
    in.params = {{"transfer", r.transfer.filename().string()}, {"input_crc32", input_crc32(text)}};
    // And its mesh's checksum, so that render and deform refuse the fit on another mesh
    // as they refuse the table of the bake itself.
    if (record.mesh_crc32) in.params["mesh_crc32"] = *record.mesh_crc32;
    if (!record.normals.empty()) in.params["normals"] = record.normals;
    const std::size_t n2 = sh_count(in.order);
    in.total = in.transfer.size() / n2;
    in.range = plan.rows_of ? shard_range_of(*plan.rows_of, in.total) : VertexRange{0, in.total};
    in.transfer.erase(in.transfer.begin() + in.range.end * n2, in.transfer.end());
    in.transfer.erase(in.transfer.begin(), in.transfer.begin() + in.range.begin * n2);
    return in;
  }
  in.mesh = load_mesh(r.mesh, r.normals, r.up);
  const Mesh& mesh = in.mesh;
  io.inputs(mesh.files, "a file of the mesh");
  if (cb.warning) {
    if (mesh.unreferenced_vertices)
      cb.warning("skipped " + std::to_string(mesh.unreferenced_vertices) + " unreferenced vertices");
    if (mesh.degenerate_faces) cb.warning("skipped " + std::to_string(mesh.degenerate_faces) + " degenerate faces");
    if (mesh.zero_normals) cb.warning(std::to_string(mesh.zero_normals) + " vertices have no defined normal (+z used)");
  }
  if (mpi) {
    // Before the simulation: an interreflected bake's ranks exchange every bounce, and
    // ranks that disagree would exchange rows of other sizes or wait for ever.
    const nlohmann::json job = {{"order", in.order},
                                {"rays", r.rays},
                                {"seed", r.seed},
                                {"mode", name_of(r.mode, transfer_mode_names())},
                                {"bounces", r.mode == TransferMode::interreflected ? r.bounces : 0},
                                {"albedo", r.mode == TransferMode::interreflected ? r.albedo : 0.0},
                                {"vertices", mesh.positions.size()},
                                {"mesh_crc32", loaded_mesh_crc32(mesh)}};
    mpi->check_same_job(job.dump(), "settings and mesh");
  }
  TransferOptions to{.order = in.order, .rays = r.rays, .seed = r.seed, .mode = r.mode, .bounces = r.bounces,
                     .albedo = r.albedo, .threads = plan.threads, .progress = cb.simulate_progress};
  const auto t0 = std::chrono::steady_clock::now();
  if (r.texture) {
    in.texels = rasterize_texels(mesh, *r.texture, r.mesh);
    in.total = in.texels.texel.size();
    in.range = VertexRange{0, in.total};
    in.transfer = compute_transfer_at(mesh, in.texels.positions, in.texels.normals, in.texels.texel, to);
  } else {
    in.total = mesh.positions.size();
    in.range = plan.rows_of ? shard_range_of(*plan.rows_of, in.total) : VertexRange{0, in.total};
    to.first_vertex = in.range.begin;
    to.end_vertex = in.range.end;
    // Each rank simulates its rows of every bounce and reads the others' between bounces.
    if (mpi) to.gather_bounce = [mpi](std::vector<double> rows) { return mpi->allgather(std::move(rows)); };
    in.transfer = compute_transfer(mesh, to);
  }
  in.simulate_seconds = seconds_since(t0);
  in.params = {{"mesh", r.mesh.filename().string()},
               {"input_crc32", mesh.input_crc32},
               {"mesh_crc32", loaded_mesh_crc32(mesh)},
               {"mode", name_of(r.mode, transfer_mode_names())},
               {"rays", r.rays},
               {"normals", name_of(r.normals, normal_source_names())},
               {"up", up_axis_name(mesh.up)}};
  if (r.mode == TransferMode::interreflected) {
    in.params["bounces"] = r.bounces;
    in.params["albedo"] = r.albedo;
  }
  in.meta["obj_vertices"] = mesh.obj_vertices;
  in.meta["unreferenced_vertices"] = mesh.unreferenced_vertices;
  in.meta["degenerate_faces"] = mesh.degenerate_faces;
  in.meta["triangles"] = mesh.triangles.size();
  in.meta["normals_from_file"] = mesh.normals_from_file;
  in.meta[kMeshUpKey] = up_axis_name(mesh.up);
  if (r.texture) {
    in.params["texture"] = *r.texture;
    // What render reads to find and sample the maps; vertex_index holds texel indices.
    in.meta["texture"] = {{"resolution", *r.texture},
                          {"texels", in.texels.texel.size()},
                          {"gutter", kGutterTexels},
                          {"uv_crc32", uv_layout_crc32(mesh)},
                          {"rows", "texel index y * resolution + x, row 0 at v = 1 (UV origin bottom left)"},
                          {"dc_linear_map", plan.dc_linear_map.filename().string()},
                          {"lobes_map", plan.lobes_map.filename().string()}};
  }
  return in;
}

// Step 2, the fit of every row ([4] Sec. 4), its options recorded in the parameters.
ZhFitTable<double> fit_rows(const FitZhRequest& r, const FitZhCallbacks& cb, const FitZhPlan& plan,
                            FitZhInputs& in, FitZhReport& report) {
  const ZhFitOptions fo = fit_zh_options(r, in.order);
  const auto t1 = std::chrono::steady_clock::now();
  ZhFitTable<double> fits = fit_zh_all(in.transfer, fo, plan.threads, cb.fit_progress, in.range.begin);
  report.fit_seconds = seconds_since(t1);
  in.params["order"] = in.order;
  in.params["lobes"] = r.lobes;
  in.params["seed"] = r.seed;
  in.params["fit_method"] = name_of(r.fit_method, fit_method_names());
  in.params["effort"] = r.effort;
  in.params["starts"] = fo.starts;
  in.params["restart_above"] = fo.restart_above;
  in.params["direct"] = r.direct;
  if (r.texture) {
    fits.vertex_index.assign(in.texels.texel.begin(), in.texels.texel.end());
  } else if (!in.mesh.source_index.empty()) {
    fits.vertex_index.assign(in.mesh.source_index.begin() + in.range.begin,
                             in.mesh.source_index.begin() + in.range.end);
  }
  return fits;
}

// Under MPI: every rank's rows reach rank 0 as a partial table and are joined by merge's
// code (the same checks, a rank on another Embree, ISA or input refused, and the same
// bytes as shards merged); only the rank that simulated a vertex has its transfer DC,
// which reaches rank 0 beside the rows, in rank order as the rows are. Returns false on
// the ranks that write nothing.
bool gather_ranks(MpiJob& mpi, bool with_dc, Table& table, ZhFitTable<double>& fits,
                  std::vector<double>& transfer_dc) {
  const std::string mine = encode_table(table);
  if (!mpi.all_ok(true)) throw InputError("rank " + std::to_string(mpi.rank()) + ": stopped, another rank failed");
  const std::vector<std::string> parts = mpi.gather(mine);
  if (with_dc) {
    const std::vector<std::string> dc_parts = mpi.gather(
        std::string_view(reinterpret_cast<const char*>(transfer_dc.data()), transfer_dc.size() * sizeof(double)));
    transfer_dc.clear();
    for (const std::string& part : dc_parts) {
      const std::size_t at = transfer_dc.size();
      transfer_dc.resize(at + part.size() / sizeof(double));
      std::memcpy(transfer_dc.data() + at, part.data(), part.size() / sizeof(double) * sizeof(double));
    }
  }
  if (mpi.rank() != 0) return false;
  std::vector<NamedTable> tables;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    const std::string name = "rank " + std::to_string(k);
    Result<Table> t = read_table_bytes(std::as_bytes(std::span(parts[k])), name, {std::string(kZhFitKind), 1});
    if (!t) throw InputError("--mpi: " + t.error().message);
    tables.push_back({name, std::move(t).value()});
  }
  try {
    MergedFits merged = merge_zh_fit_tables(std::move(tables));
    table = std::move(merged.table);
    fits = std::move(merged.fits);
  } catch (const InputError& e) {
    throw InputError(std::string("--mpi: ") + e.what());
  }
  return true;
}

FitZhReport run_fit_zh_on(const FitZhRequest& r, const FitZhCallbacks& cb, MpiJob* mpi) {
  check_request(r);
  FitZhPlan plan;
  if (!r.shard.empty()) plan.shard = parse_shard(r.shard);
  plan.rows_of = plan.shard;
  if (mpi) plan.rows_of = Shard{static_cast<std::size_t>(mpi->rank()), static_cast<std::size_t>(mpi->size())};
  plan.threads = resolve_threads(r.threads);
  const std::filesystem::path input_path = r.mesh.empty() ? r.transfer : r.mesh;
  const std::string part = plan.shard ? ".part-" + std::to_string(plan.shard->index) + "-of-" +
                                            std::to_string(plan.shard->count)
                                      : std::string();
  plan.out = !r.out.empty() ? r.out
                            : std::filesystem::path(input_path.stem().string() + ".zh" + part +
                                                    (r.encoding == TableEncoding::json ? ".json" : ".shtb"));
  if (r.texture) {  // beside --out
    plan.dc_linear_map = dc_linear_map_path(plan.out);
    plan.lobes_map = lobes_map_path(plan.out);
  }
  // Fail before a long bake, not after it. Every rank checks, so that all stop alike
  // (only rank 0 writes).
  JobOutputs io;
  io.input(input_path, r.mesh.empty() ? "the --transfer input" : "the mesh");
  io.output({{plan.out, "--out"}, {r.json, "--json"}, {r.ply, "--ply"}, {r.save_transfer, "--save-transfer"},
             {r.gltf, "--gltf"}, {plan.dc_linear_map, "the DC and linear map"}, {plan.lobes_map, "the lobe map"}});

  FitZhReport report;
  report.threads = plan.threads;
  report.lobes = r.lobes;
  report.out = plan.out;
  report.from_mesh = !r.mesh.empty();

  FitZhInputs in = read_inputs(r, cb, mpi, plan, io);
  report.simulate_seconds = in.simulate_seconds;
  report.order = in.order;
  report.count = in.transfer.size() / sh_count(in.order);
  ZhFitTable<double> fits = fit_rows(r, cb, plan, in, report);

  // ---- step 3, the outputs
  std::vector<double> transfer_dc;  // --gltf colours each vertex by its transfer's t_00
  if (!r.gltf.empty())
    for (std::size_t v = 0; v < report.count; ++v) transfer_dc.push_back(in.transfer[v * sh_count(in.order)]);
  // The table and its encoding come next, at the peak of memory: 288 bytes a vertex at
  // order 6 go back unless an output still reads the vectors.
  if (r.ply.empty() && r.save_transfer.empty()) std::vector<double>().swap(in.transfer);
  // [4] Fig. 3: RMS error normalised by the total L2 length over all vertices.
  report.normalized_rms = normalized_rms(fits);
  nlohmann::json generator = generator_record("shtool fit-zh", in.params);
  if (report.from_mesh && r.mode != TransferMode::unshadowed) {
    const EmbreeIdentity embree = embree_identity();
    generator["embree"] = {{"version", embree.version}, {"isa", embree.isa}};
  }
  if (plan.rows_of) {
    in.meta["shard"] = {{"index", plan.rows_of->index}, {"count", plan.rows_of->count},
                        {"first_vertex", in.range.begin}, {"end_vertex", in.range.end}, {"vertices", in.total}};
    report.sharded = plan.shard.has_value();
    report.shard_index = plan.rows_of->index;
    report.shard_count = plan.rows_of->count;
    report.first_vertex = in.range.begin;
    report.end_vertex = in.range.end;
    report.total = in.total;
  }
  Table table = zh_fit_table(fits, in.meta, generator);
  std::optional<TextureMaps> maps;
  if (r.texture) {
    maps = texture_maps(in.texels, fits);
    report.texture_resolution = *r.texture;
    report.dc_linear_map = plan.dc_linear_map;
    report.lobes_map = plan.lobes_map;
  }
  // The table holds the fits now; the other outputs made from them keep them.
  if (r.json.empty() && r.ply.empty() && r.gltf.empty()) fits = ZhFitTable<double>{};
  if (mpi) {
    report.mpi_rank = mpi->rank();
    report.mpi_ranks = mpi->size();
    if (!gather_ranks(*mpi, !r.gltf.empty(), table, fits, transfer_dc)) return report;
    report.count = fits.vertices;
    report.normalized_rms = normalized_rms(fits);
  }
  io.set("--out", encode_table(table, r.encoding));
  table = Table{};  // encoded: its arrays go back before the next output is made
  if (io.requested("--json")) io.set("--json", fits_json(fits));
  if (io.requested("--ply")) io.set("--ply", ply_text(in.mesh, in.transfer, in.order, fits));
  if (io.requested("--save-transfer"))
    io.set("--save-transfer", transfer_json(in.transfer, in.order, in.mesh.up, loaded_mesh_crc32(in.mesh),
                                            name_of(r.normals, normal_source_names())));
  if (io.requested("--gltf"))
    io.set("--gltf",
           zh_fit_glb(in.mesh, fits, transfer_dc, "shtool " + generator["version"].get<std::string>() + " fit-zh"));
  if (maps) {
    io.set("the DC and linear map", lighting::encode_exr_channels(maps->dc_linear));
    io.set("the lobe map", lighting::encode_exr_channels(maps->lobes));
  }
  io.commit();
  return report;
}

}  // namespace

FitZhReport run_fit_zh(const FitZhRequest& r, const FitZhCallbacks& cb) {
  if (!r.mpi) return run_fit_zh_on(r, cb, nullptr);
  MpiJob mpi;
  try {
    return run_fit_zh_on(r, cb, &mpi);
  } catch (...) {
    // The other ranks are waiting for this one's verdict before they gather.
    if (!mpi.synchronised()) mpi.all_ok(false);
    throw;
  }
}

}  // namespace shtool::fit
