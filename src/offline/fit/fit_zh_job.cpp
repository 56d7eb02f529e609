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
#include "fit/mpi_job.h"
#include "fit/shard.h"
#include "fit/texture_bake.h"
#include "fit/zh_fit.h"
#include "fit/zh_fit_gltf.h"
#include "fit/zh_fit_merge.h"
#include "fit/zh_fit_table.h"
#include "shtool/sh.h"

namespace shtool::fit {
namespace {

// Transfer coefficients are O(1) (radiance transfer of a unit light); far larger inputs
// would overflow the squared norms of the fit (about 1e154).
constexpr double kMaxTransferMagnitude = 1e100;

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

// The --save-transfer output, in the --transfer format.
std::string transfer_json(const std::vector<double>& transfer, int order, UpAxis up) {
  const std::size_t n2 = sh_count(order);
  nlohmann::json doc = {{"order", order}, {kMeshUpKey, up_axis_name(up)}, {"vectors", nlohmann::json::array()}};
  for (std::size_t v = 0; v < transfer.size() / n2; ++v)
    doc["vectors"].push_back(std::vector<double>(transfer.begin() + v * n2, transfer.begin() + (v + 1) * n2));
  return doc.dump() + "\n";
}

void check_request(const FitZhRequest& r) {
  if (r.mesh.empty() == r.transfer.empty())
    throw InputError(r.mesh.empty() ? "give a mesh (MESH.obj) or --transfer FILE"
                                    : "give either a mesh or --transfer FILE, not both");
  if (!is_supported_order(r.order)) throw InputError("--order " + std::to_string(r.order) + " is not supported");
  if (r.lobes < 1 || r.lobes > 64) throw InputError("--lobes must be in 1..64, got " + std::to_string(r.lobes));
  if (r.rays < 1) throw InputError("--rays must be at least 1, got " + std::to_string(r.rays));
  if (r.effort < kMinEffort || r.effort > kMaxEffort)
    throw InputError("--effort must be in " + std::to_string(kMinEffort) + ".." + std::to_string(kMaxEffort) +
                     ", got " + std::to_string(r.effort));
  if (r.starts && *r.starts < 0) throw InputError("--starts must be >= 0, got " + std::to_string(*r.starts));
  if (r.restart_above && !(*r.restart_above >= 0)) throw InputError("--restart-above must be >= 0");
  if (r.threads < 0) throw InputError("--threads must be >= 0");
  if (r.mode == TransferMode::interreflected) {
    if (r.bounces < 1 || r.bounces > kMaxBounces)
      throw InputError("--bounces must be in 1.." + std::to_string(kMaxBounces) + ", got " + std::to_string(r.bounces));
    if (!(r.albedo >= 0 && r.albedo < 1)) throw InputError("--albedo must be in [0, 1)");
  }
  if (!r.transfer.empty() && !r.ply.empty()) throw InputError("--ply needs a mesh (not --transfer)");
  if (!r.transfer.empty() && !r.save_transfer.empty())
    throw InputError("--save-transfer needs a mesh (not --transfer)");
  if (!r.transfer.empty() && !r.gltf.empty()) throw InputError("--gltf needs a mesh (not --transfer)");
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

std::string fits_json(const ZhFitTable<double>& fits) {
  nlohmann::json doc = {{"order", fits.order}, {"lobes", fits.lobes}, {"fits", nlohmann::json::array()}};
  for (std::size_t v = 0; v < fits.vertices; ++v) {
    nlohmann::json jf = {{"lobes", nlohmann::json::array()}};
    const std::span<const double> coeffs = fits.coeffs_of(v);
    for (int k = 0; k < fits.lobes; ++k) {
      const Eigen::Vector3d& axis = fits.axes_of(v)[k];
      jf["lobes"].push_back({{"axis", {axis.x(), axis.y(), axis.z()}},
                             {"coeffs", coeffs.subspan(static_cast<std::size_t>(k) * fits.order, fits.order)}});
    }
    jf["residual"] = fits.residual[v];
    jf["norm"] = fits.norm[v];
    if (fits.direct_count) jf["direct"] = fits.direct_of(v);
    doc["fits"].push_back(std::move(jf));
  }
  return doc.dump() + "\n";
}


// {"order": n, "vectors": [[n^2 numbers], ...]}
std::vector<double> parse_transfer_json(std::string_view text, const std::filesystem::path& path_in, int& order,
                                        std::string* mesh_up) {
  const std::string path = path_in.string();
  const nlohmann::json doc = parse_json_input(text, path_in, "--transfer");
  if (!doc.is_object() || !doc.contains("order") || !doc.at("order").is_number_integer())
    throw InputError("--transfer '" + path + "': expected {\"order\": n, \"vectors\": [[n^2 numbers], ...]}");
  if (doc.contains(kMeshUpKey) && (!doc.at(kMeshUpKey).is_string() || (doc.at(kMeshUpKey) != "y" && doc.at(kMeshUpKey) != "z")))
    throw InputError("--transfer '" + path + "': \"" + kMeshUpKey + "\" must be \"y\" or \"z\"");
  if (mesh_up) *mesh_up = doc.contains(kMeshUpKey) ? doc.at(kMeshUpKey).get<std::string>() : std::string();
  const nlohmann::json& o = doc.at("order");
  const std::int64_t order64 = o.is_number_unsigned()
                                   ? (o.get<std::uint64_t>() > static_cast<std::uint64_t>(kMaxOrder) ? -1 : o.get<std::int64_t>())
                                   : o.get<std::int64_t>();
  if (order64 < 1 || order64 > kMaxOrder)
    throw InputError("--transfer '" + path + "': order " + o.dump() + " is not supported (1.." +
                     std::to_string(kMaxOrder) + ")");
  order = static_cast<int>(order64);
  if (!doc.contains("vectors") || !doc.at("vectors").is_array() || doc.at("vectors").empty())
    throw InputError("--transfer '" + path + "': \"vectors\" must be a non-empty array");
  const std::size_t n2 = sh_count(order);
  std::vector<double> values;
  std::size_t v = 0;
  for (const nlohmann::json& vec : doc.at("vectors")) {
    if (!vec.is_array() || vec.size() != n2)
      throw InputError("--transfer '" + path + "': vector " + std::to_string(v) + " must have " +
                      std::to_string(n2) + " numbers (order " + std::to_string(order) + ")");
    for (const nlohmann::json& x : vec) {
      if (!x.is_number()) throw InputError("--transfer '" + path + "': vector " + std::to_string(v) + " has a non-number");
      const double d = x.get<double>();
      if (!std::isfinite(d)) throw InputError("--transfer '" + path + "': vector " + std::to_string(v) + " is not finite");
      if (std::abs(d) > kMaxTransferMagnitude)
        throw InputError("--transfer '" + path + "': vector " + std::to_string(v) +
                         " has a coefficient beyond 1e100 in magnitude, more than the fit handles (its squared "
                         "norms would overflow)");
      values.push_back(d);
    }
    ++v;
  }
  return values;
}


const std::vector<std::pair<std::string, TransferMode>>& transfer_mode_names() {
  static const std::vector<std::pair<std::string, TransferMode>> names = {
      {"unshadowed", TransferMode::unshadowed},
      {"shadowed", TransferMode::shadowed},
      {"interreflected", TransferMode::interreflected}};
  return names;
}

const std::vector<std::pair<std::string, ZhFitMethod>>& fit_method_names() {
  static const std::vector<std::pair<std::string, ZhFitMethod>> names = {{"varpro", ZhFitMethod::varpro},
                                                                         {"joint", ZhFitMethod::joint}};
  return names;
}

const std::vector<std::pair<std::string, NormalSource>>& normal_source_names() {
  static const std::vector<std::pair<std::string, NormalSource>> names = {
      {"auto", NormalSource::automatic}, {"file", NormalSource::file}, {"computed", NormalSource::computed}};
  return names;
}

namespace {

FitZhReport run_fit_zh_on(const FitZhRequest& r, const FitZhCallbacks& cb, MpiJob* mpi) {
  check_request(r);
  std::optional<Shard> shard;  // --shard: a partial table
  if (!r.shard.empty()) shard = parse_shard(r.shard);
  // The rows this process fits: its shard, or its rank's share of an MPI job.
  std::optional<Shard> rows_of = shard;
  if (mpi) rows_of = Shard{static_cast<std::size_t>(mpi->rank()), static_cast<std::size_t>(mpi->size())};
  const int threads = resolve_threads(r.threads);
  const std::filesystem::path input_path = r.mesh.empty() ? r.transfer : r.mesh;
  const bool json_table = r.encoding == TableEncoding::json;
  const std::string part =
      shard ? ".part-" + std::to_string(shard->index) + "-of-" + std::to_string(shard->count) : std::string();
  const std::filesystem::path out =
      !r.out.empty() ? r.out
                     : std::filesystem::path(input_path.stem().string() + ".zh" + part +
                                             (json_table ? ".json" : ".shtb"));
  // Fail before a long bake, not after it: every output writable, none the input, no two
  // the same file.
  std::filesystem::path dc_linear_map, lobes_map;  // --texture: beside --out
  if (r.texture) {
    dc_linear_map = dc_linear_map_path(out);
    lobes_map = lobes_map_path(out);
  }
  JobOutputs io;
  io.input(input_path, r.mesh.empty() ? "the --transfer input" : "the mesh");
  // Every rank checks them, so that all stop alike (only rank 0 writes).
  io.output(out, "--out");
  io.output(r.json, "--json");
  io.output(r.ply, "--ply");
  io.output(r.save_transfer, "--save-transfer");
  io.output(r.gltf, "--gltf");
  io.output(dc_linear_map, "the DC and linear map");
  io.output(lobes_map, "the lobe map");

  FitZhReport report;
  report.threads = threads;
  report.lobes = r.lobes;
  report.out = out;
  report.from_mesh = !r.mesh.empty();

  // ---- transfer vectors
  int order = r.order;
  std::size_t total = 0;  // vertices or vectors of the whole input
  VertexRange range;      // the rows this run fits
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
  std::vector<double> transfer;
  Mesh mesh;
  TexelSamples texels;  // --texture
  nlohmann::json params;
  nlohmann::json meta = nlohmann::json::object();
  if (!r.transfer.empty()) {
    const std::string text = read_input_file(r.transfer, "--transfer");
    int file_order = 0;
    std::string transfer_up;
    transfer = parse_transfer_json(text, r.transfer, file_order, &transfer_up);
    // Vectors simulated on a mesh keep its frame record, so that render checks the fit.
    if (!transfer_up.empty()) meta[kMeshUpKey] = transfer_up;
    if (r.order_given && file_order != r.order)
      throw InputError("--order " + std::to_string(r.order) + " but --transfer '" + r.transfer.string() +
                       "' has order " + std::to_string(file_order));
    order = file_order;
    params = {{"transfer", r.transfer.filename().string()}, {"input_crc32", input_crc32(text)}};
    const std::size_t n2 = sh_count(order);
    total = transfer.size() / n2;
    range = rows_of ? shard_range_of(*rows_of, total) : VertexRange{0, total};
    transfer.erase(transfer.begin() + range.end * n2, transfer.end());
    transfer.erase(transfer.begin(), transfer.begin() + range.begin * n2);
  } else {
    mesh = load_mesh(r.mesh, r.normals, r.up);
    io.inputs(mesh.files, "a file of the mesh");
    if (cb.warning) {
      if (mesh.unreferenced_vertices)
        cb.warning("skipped " + std::to_string(mesh.unreferenced_vertices) + " unreferenced vertices");
      if (mesh.degenerate_faces) cb.warning("skipped " + std::to_string(mesh.degenerate_faces) + " degenerate faces");
      if (mesh.zero_normals)
        cb.warning(std::to_string(mesh.zero_normals) + " vertices have no defined normal (+z used)");
    }
    TransferOptions to;
    to.order = order;
    to.rays = r.rays;
    to.seed = r.seed;
    to.mode = r.mode;
    to.bounces = r.bounces;
    to.albedo = r.albedo;
    to.threads = threads;
    to.progress = cb.simulate_progress;
    if (r.texture) {
      const auto t0 = std::chrono::steady_clock::now();
      texels = rasterize_texels(mesh, *r.texture, r.mesh);
      total = texels.texel.size();
      range = VertexRange{0, total};
      transfer = compute_transfer_at(mesh, texels.positions, texels.normals, texels.texel, to);
      report.simulate_seconds = seconds_since(t0);
    } else {
      total = mesh.positions.size();
      range = rows_of ? shard_range_of(*rows_of, total) : VertexRange{0, total};
      to.first_vertex = range.begin;
      to.end_vertex = range.end;
      // Each rank simulates its rows of every bounce and reads the others' between bounces.
      if (mpi) to.gather_bounce = [mpi](std::vector<double> rows) { return mpi->allgather(std::move(rows)); };
      const auto t0 = std::chrono::steady_clock::now();
      transfer = compute_transfer(mesh, to);
      report.simulate_seconds = seconds_since(t0);
    }
    params = {{"mesh", r.mesh.filename().string()},
              {"input_crc32", mesh.input_crc32},
              {"mesh_crc32", loaded_mesh_crc32(mesh)},
              {"mode", name_of(r.mode, transfer_mode_names())},
              {"rays", r.rays},
              {"normals", name_of(r.normals, normal_source_names())},
              {"up", up_axis_name(mesh.up)}};
    if (r.mode == TransferMode::interreflected) {
      params["bounces"] = r.bounces;
      params["albedo"] = r.albedo;
    }
    meta["obj_vertices"] = mesh.obj_vertices;
    meta["unreferenced_vertices"] = mesh.unreferenced_vertices;
    meta["degenerate_faces"] = mesh.degenerate_faces;
    meta["triangles"] = mesh.triangles.size();
    meta["normals_from_file"] = mesh.normals_from_file;
    meta[kMeshUpKey] = up_axis_name(mesh.up);
    if (r.texture) {
      params["texture"] = *r.texture;
      // What render reads to find and sample the maps; vertex_index holds texel indices.
      meta["texture"] = {{"resolution", *r.texture},
                         {"texels", texels.texel.size()},
                         {"gutter", kGutterTexels},
                         {"uv_crc32", uv_layout_crc32(mesh)},
                         {"rows", "texel index y * resolution + x, row 0 at v = 1 (UV origin bottom left)"},
                         {"dc_linear_map", dc_linear_map.filename().string()},
                         {"lobes_map", lobes_map.filename().string()}};
    }
  }
  report.order = order;
  report.count = transfer.size() / sh_count(order);

  // ---- fit
  ZhFitOptions fo;
  fo.order = order;
  fo.lobes = r.lobes;
  fo.direct = r.direct;
  fo.method = r.fit_method;
  apply_effort(fo, r.effort);
  if (r.starts) fo.starts = *r.starts;
  if (r.restart_above) fo.restart_above = *r.restart_above;
  fo.seed = r.seed;
  const auto t1 = std::chrono::steady_clock::now();
  ZhFitTable<double> fits = fit_zh_all(transfer, fo, threads, cb.fit_progress, range.begin);
  report.fit_seconds = seconds_since(t1);
  std::vector<double> transfer_dc;  // --gltf colours each vertex by its transfer's t_00
  if (!r.gltf.empty())
    for (std::size_t v = 0; v < report.count; ++v) transfer_dc.push_back(transfer[v * sh_count(order)]);
  // The table and its encoding come next, at the peak of memory: 288 bytes a vertex at
  // order 6 go back unless an output still reads the vectors.
  if (r.ply.empty() && r.save_transfer.empty()) std::vector<double>().swap(transfer);

  params["order"] = order;
  params["lobes"] = r.lobes;
  params["seed"] = r.seed;
  params["fit_method"] = name_of(r.fit_method, fit_method_names());
  params["effort"] = r.effort;
  params["starts"] = fo.starts;
  params["restart_above"] = fo.restart_above;
  params["direct"] = r.direct;

  // [4] Fig. 3: RMS error normalised by the total L2 length over all vertices.
  report.normalized_rms = normalized_rms(fits);
  nlohmann::json generator = generator_record("shtool fit-zh", params);
  if (report.from_mesh && r.mode != TransferMode::unshadowed) {
    const EmbreeIdentity embree = embree_identity();
    generator["embree"] = {{"version", embree.version}, {"isa", embree.isa}};
  }
  if (r.texture) {
    fits.vertex_index.assign(texels.texel.begin(), texels.texel.end());
  } else if (!mesh.source_index.empty()) {
    fits.vertex_index.assign(mesh.source_index.begin() + range.begin, mesh.source_index.begin() + range.end);
  }
  if (rows_of) {
    meta["shard"] = {{"index", rows_of->index}, {"count", rows_of->count}, {"first_vertex", range.begin},
                     {"end_vertex", range.end}, {"vertices", total}};
    report.sharded = shard.has_value();
    report.shard_index = rows_of->index;
    report.shard_count = rows_of->count;
    report.first_vertex = range.begin;
    report.end_vertex = range.end;
    report.total = total;
  }
  Table table = zh_fit_table(fits, meta, generator);
  std::optional<TextureMaps> maps;
  if (r.texture) {
    maps = texture_maps(texels, fits);
    report.texture_resolution = *r.texture;
    report.dc_linear_map = dc_linear_map;
    report.lobes_map = lobes_map;
  }
  // The table holds the fits now; the other outputs made from them keep them.
  if (r.json.empty() && r.ply.empty() && r.gltf.empty()) fits = ZhFitTable<double>{};
  if (mpi) {
    // Every rank's rows reach rank 0 as a partial table and are joined by merge's code:
    // the same checks (a rank on another Embree, ISA or input is refused) and the same
    // bytes as shards merged.
    const std::string mine = encode_table(table);
    if (!mpi->all_ok(true)) throw InputError("rank " + std::to_string(mpi->rank()) + ": stopped, another rank failed");
    const std::vector<std::string> parts = mpi->gather(mine);
    // Only the rank that simulated a vertex has its transfer DC: they reach rank 0 beside
    // the rows, in rank order as the rows are.
    if (!r.gltf.empty()) {
      const std::vector<std::string> dc_parts = mpi->gather(
          std::string_view(reinterpret_cast<const char*>(transfer_dc.data()), transfer_dc.size() * sizeof(double)));
      transfer_dc.clear();
      for (const std::string& part : dc_parts) {
        const std::size_t at = transfer_dc.size();
        transfer_dc.resize(at + part.size() / sizeof(double));
        std::memcpy(transfer_dc.data() + at, part.data(), part.size() / sizeof(double) * sizeof(double));
      }
    }
    report.mpi_rank = mpi->rank();
    report.mpi_ranks = mpi->size();
    if (mpi->rank() != 0) return report;
    std::vector<NamedTable> tables;
    for (std::size_t k = 0; k < parts.size(); ++k) {
      const std::string name = "rank " + std::to_string(k);
      Result<Table> t = read_table_bytes(std::as_bytes(std::span(parts[k])), name, {"zh-fit", 1});
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
    report.count = fits.vertices;
    report.normalized_rms = normalized_rms(fits);
  }

  // ---- outputs: everything is computed, then written as one set.
  io.set("--out", encode_table(table, r.encoding));
  table = Table{};  // encoded: its arrays go back before the next output is made
  if (io.requested("--json")) io.set("--json", fits_json(fits));
  if (io.requested("--ply")) io.set("--ply", ply_text(mesh, transfer, order, fits));
  if (io.requested("--save-transfer")) io.set("--save-transfer", transfer_json(transfer, order, mesh.up));
  if (io.requested("--gltf"))
    io.set("--gltf",
           zh_fit_glb(mesh, fits, transfer_dc, "shtool " + generator["version"].get<std::string>() + " fit-zh"));
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
