// shtool fit-zh: PRT transfer simulation on a mesh (or given SH vectors), then a
// multi-lobe ZH fit per vertex (paper 004, Sec. 4.1). See docs/fit-zh.md.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "fit/mesh.h"
#include "fit/transfer.h"
#include "fit/zh_fit.h"
#include "fit/zh_fit_table.h"
#include "offline_version.h"
#include "shtool/sh.h"
#include "shtool/table.h"

namespace shtool::cli {
namespace {

struct FitZhOptions {
  std::string mesh;
  std::string transfer;
  std::string save_transfer;
  std::string out;
  std::string json;
  std::string ply;
  std::string format = "binary";
  std::string mode = "shadowed";
  std::string normals = "auto";
  int order = 6;
  int lobes = 4;
  int rays = 1024;
  int bounces = 2;
  double albedo = 0.8;
  std::uint64_t seed = 1;
  int starts = 4;
  double restart_above = 0.05;
  bool direct = false;
  int threads = 0;
  bool order_given = false;
};

// A progress bar on stderr, only when stderr is a terminal (DESIGN.md: quiet otherwise).
std::function<void(std::size_t, std::size_t)> progress_bar(const std::string& label) {
  if (!isatty(STDERR_FILENO)) return {};
  return [label](std::size_t done, std::size_t total) {
    const int width = 40;
    const int filled = total ? static_cast<int>(width * done / total) : width;
    std::fprintf(stderr, "\r%-9s [%s%s] %3d%%", label.c_str(), std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), total ? static_cast<int>(100 * done / total) : 100);
    if (done >= total) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  };
}

std::string read_file(const std::string& path, const std::string& what) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw UserError(what + " '" + path + "': cannot open file");
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::uint32_t crc_of(const std::string& bytes) {
  return table_crc32(std::span<const std::byte>(reinterpret_cast<const std::byte*>(bytes.data()), bytes.size()));
}

// {"order": n, "vectors": [[n^2 numbers], ...]}
std::vector<double> parse_transfer_file(const std::string& path, const std::string& text, int& order) {
  nlohmann::json doc;
  try {
    doc = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw UserError("--transfer '" + path + "': not valid JSON: " + e.what());
  }
  if (!doc.is_object() || !doc.contains("order") || !doc["order"].is_number_integer())
    throw UserError("--transfer '" + path + "': expected {\"order\": n, \"vectors\": [[n^2 numbers], ...]}");
  order = doc["order"].get<int>();
  if (!is_supported_order(order))
    throw UserError("--transfer '" + path + "': order " + std::to_string(order) + " is not supported");
  if (!doc.contains("vectors") || !doc["vectors"].is_array() || doc["vectors"].empty())
    throw UserError("--transfer '" + path + "': \"vectors\" must be a non-empty array");
  const std::size_t n2 = sh_count(order);
  std::vector<double> values;
  std::size_t v = 0;
  for (const nlohmann::json& vec : doc["vectors"]) {
    if (!vec.is_array() || vec.size() != n2)
      throw UserError("--transfer '" + path + "': vector " + std::to_string(v) + " must have " +
                      std::to_string(n2) + " numbers (order " + std::to_string(order) + ")");
    for (const nlohmann::json& x : vec) {
      if (!x.is_number()) throw UserError("--transfer '" + path + "': vector " + std::to_string(v) + " has a non-number");
      const double d = x.get<double>();
      if (!std::isfinite(d)) throw UserError("--transfer '" + path + "': vector " + std::to_string(v) + " is not finite");
      values.push_back(d);
    }
    ++v;
  }
  return values;
}

// Writes through a temporary file and a rename, so a failure leaves nothing behind.
void write_text_atomically(const std::filesystem::path& path, const std::string& text, const std::string& what) {
  std::filesystem::path tmp = path;
  tmp += ".tmp-" + std::to_string(getpid());
  {
    std::ofstream out(tmp, std::ios::binary);
    out << text;
    out.flush();
    if (!out) {
      std::error_code ec;
      std::filesystem::remove(tmp, ec);
      throw UserError(what + " '" + path.string() + "': cannot write");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw UserError(what + " '" + path.string() + "': cannot write: " + ec.message());
  }
}

std::string ply_text(const fit::Mesh& mesh, const std::vector<double>& transfer, int order,
                     const std::vector<fit::ZhFit>& fits) {
  std::ostringstream s;
  s.precision(9);
  s << "ply\nformat ascii 1.0\ncomment shtool fit-zh: colour = transfer DC (grey, 1 = unshadowed), "
       "red where the fit error is high\n"
    << "element vertex " << mesh.positions.size() << "\nproperty float x\nproperty float y\nproperty float z\n"
    << "property float nx\nproperty float ny\nproperty float nz\n"
    << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    << "property float transfer_dc\nproperty float fit_error\n"
    << "element face " << mesh.triangles.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
  const double y00 = 0.5 / std::sqrt(std::numbers::pi);  // DC of the unshadowed transfer
  const std::size_t n2 = sh_count(order);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const double dc = std::clamp(transfer[v * n2] / y00, 0.0, 1.0);
    const double err = fits[v].norm > 0 ? fits[v].residual / fits[v].norm : 0.0;
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

double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

void run_fit_zh(const FitZhOptions& opt) {
  // ---- options
  if (opt.mesh.empty() == opt.transfer.empty())
    throw UserError(opt.mesh.empty() ? "give a mesh (MESH.obj) or --transfer FILE"
                                     : "give either a mesh or --transfer FILE, not both");
  if (!is_supported_order(opt.order)) throw UserError("--order " + std::to_string(opt.order) + " is not supported");
  if (opt.lobes < 1 || opt.lobes > 64) throw UserError("--lobes must be in 1..64, got " + std::to_string(opt.lobes));
  if (opt.rays < 1) throw UserError("--rays must be at least 1, got " + std::to_string(opt.rays));
  if (opt.starts < 0) throw UserError("--starts must be >= 0, got " + std::to_string(opt.starts));
  if (!(opt.restart_above >= 0)) throw UserError("--restart-above must be >= 0");
  if (opt.threads < 0) throw UserError("--threads must be >= 0");
  if (opt.format != "binary" && opt.format != "json")
    throw UserError("--format must be 'binary' or 'json', got '" + opt.format + "'");
  fit::TransferMode mode;
  if (opt.mode == "unshadowed") mode = fit::TransferMode::unshadowed;
  else if (opt.mode == "shadowed") mode = fit::TransferMode::shadowed;
  else if (opt.mode == "interreflected") mode = fit::TransferMode::interreflected;
  else throw UserError("--mode must be unshadowed, shadowed or interreflected, got '" + opt.mode + "'");
  if (mode == fit::TransferMode::interreflected) {
    if (opt.bounces < 1) throw UserError("--bounces must be at least 1");
    if (!(opt.albedo >= 0 && opt.albedo < 1)) throw UserError("--albedo must be in [0, 1)");
  }
  fit::NormalSource normals;
  if (opt.normals == "auto") normals = fit::NormalSource::automatic;
  else if (opt.normals == "file") normals = fit::NormalSource::file;
  else if (opt.normals == "computed") normals = fit::NormalSource::computed;
  else throw UserError("--normals must be auto, file or computed, got '" + opt.normals + "'");
  if (!opt.transfer.empty() && !opt.ply.empty()) throw UserError("--ply needs a mesh (not --transfer)");
  if (!opt.transfer.empty() && !opt.save_transfer.empty())
    throw UserError("--save-transfer needs a mesh (not --transfer)");
  const int threads = opt.threads > 0 ? opt.threads : std::max(1u, std::thread::hardware_concurrency());

  // ---- transfer vectors
  int order = opt.order;
  std::vector<double> transfer;
  fit::Mesh mesh;
  nlohmann::json params;
  double simulate_seconds = 0;
  const std::string input_path = opt.mesh.empty() ? opt.transfer : opt.mesh;
  nlohmann::json meta = nlohmann::json::object();
  if (!opt.transfer.empty()) {
    const std::string text = read_file(opt.transfer, "--transfer");
    int file_order = 0;
    transfer = parse_transfer_file(opt.transfer, text, file_order);
    if (opt.order_given && file_order != opt.order)
      throw UserError("--order " + std::to_string(opt.order) + " but --transfer '" + opt.transfer + "' has order " +
                      std::to_string(file_order));
    order = file_order;
    params = {{"transfer", std::filesystem::path(opt.transfer).filename().string()},
              {"input_crc32", crc_of(text)}};
  } else {
    try {
      mesh = fit::load_obj(opt.mesh, normals);
    } catch (const fit::MeshError& e) {
      throw UserError(e.what());
    }
    if (mesh.unreferenced_vertices)
      std::cerr << "fit-zh: warning: skipped " << mesh.unreferenced_vertices << " unreferenced vertices\n";
    if (mesh.degenerate_faces)
      std::cerr << "fit-zh: warning: skipped " << mesh.degenerate_faces << " degenerate faces\n";
    if (mesh.zero_normals)
      std::cerr << "fit-zh: warning: " << mesh.zero_normals << " vertices have no defined normal (+z used)\n";
    fit::TransferOptions to;
    to.order = order;
    to.rays = opt.rays;
    to.seed = opt.seed;
    to.mode = mode;
    to.bounces = opt.bounces;
    to.albedo = opt.albedo;
    to.threads = threads;
    to.progress = progress_bar("simulate");
    const auto t0 = std::chrono::steady_clock::now();
    transfer = fit::compute_transfer(mesh, to);
    simulate_seconds = seconds_since(t0);
    params = {{"mesh", std::filesystem::path(opt.mesh).filename().string()},
              {"input_crc32", crc_of(read_file(opt.mesh, "mesh"))},
              {"mode", opt.mode},
              {"rays", opt.rays},
              {"normals", opt.normals}};
    if (mode == fit::TransferMode::interreflected) {
      params["bounces"] = opt.bounces;
      params["albedo"] = opt.albedo;
    }
    meta["obj_vertices"] = mesh.obj_vertices;
    meta["unreferenced_vertices"] = mesh.unreferenced_vertices;
    meta["degenerate_faces"] = mesh.degenerate_faces;
    meta["triangles"] = mesh.triangles.size();
    meta["normals_from_file"] = mesh.normals_from_file;
  }
  const std::size_t n2 = sh_count(order);
  const std::size_t count = transfer.size() / n2;

  // ---- fit
  fit::ZhFitOptions fo;
  fo.order = order;
  fo.lobes = opt.lobes;
  fo.direct = opt.direct;
  fo.starts = opt.starts;
  fo.restart_above = opt.restart_above;
  fo.seed = opt.seed;
  const auto t1 = std::chrono::steady_clock::now();
  const std::vector<fit::ZhFit> fits = fit::fit_zh_all(transfer, fo, threads, progress_bar("fit"));
  const double fit_seconds = seconds_since(t1);

  params["order"] = order;
  params["lobes"] = opt.lobes;
  params["seed"] = opt.seed;
  params["starts"] = opt.starts;
  params["restart_above"] = opt.restart_above;
  params["direct"] = opt.direct;

  // Paper 004, Fig. 3: RMS error normalised by the total L2 length over all vertices.
  const double normalized_rms = fit::normalized_rms(fits);
  const Table table = fit::zh_fit_table(fits, order, opt.lobes, mesh.source_index, meta,
                                        generator_record("shtool fit-zh", params));

  std::string out = opt.out;
  if (out.empty())
    out = std::filesystem::path(input_path).stem().string() + (opt.format == "json" ? ".zh.json" : ".zh.shtb");

  // Everything is computed before anything is written; each file is written atomically.
  std::string json_text, ply;
  if (!opt.json.empty()) {
    nlohmann::json doc = {{"order", order}, {"lobes", opt.lobes}, {"fits", nlohmann::json::array()}};
    for (const fit::ZhFit& f : fits) {
      nlohmann::json jf = {{"lobes", nlohmann::json::array()}};
      for (const fit::ZhLobe& lobe : f.lobes)
        jf["lobes"].push_back({{"axis", {lobe.axis.x(), lobe.axis.y(), lobe.axis.z()}}, {"coeffs", lobe.coeffs}});
      jf["residual"] = f.residual;
      jf["norm"] = f.norm;
      if (opt.direct) jf["direct"] = f.direct;
      doc["fits"].push_back(std::move(jf));
    }
    json_text = doc.dump() + "\n";
  }
  if (!opt.ply.empty()) ply = ply_text(mesh, transfer, order, fits);
  std::string saved;
  if (!opt.save_transfer.empty()) {
    nlohmann::json doc = {{"order", order}, {"vectors", nlohmann::json::array()}};
    for (std::size_t v = 0; v < count; ++v)
      doc["vectors"].push_back(std::vector<double>(transfer.begin() + v * n2, transfer.begin() + (v + 1) * n2));
    saved = doc.dump() + "\n";
  }

  const TableResult<TableOk> written =
      write_table(table, out, opt.format == "json" ? TableEncoding::json : TableEncoding::binary);
  if (!written) throw UserError(written.error().message);
  if (!opt.json.empty()) write_text_atomically(opt.json, json_text, "--json");
  if (!opt.ply.empty()) write_text_atomically(opt.ply, ply, "--ply");
  if (!opt.save_transfer.empty()) write_text_atomically(opt.save_transfer, saved, "--save-transfer");

  std::ostringstream summary;
  summary.precision(4);
  summary << "fit-zh: " << count << (opt.transfer.empty() ? " vertices" : " vectors");
  if (opt.transfer.empty()) summary << ", simulation " << simulate_seconds << " s";
  summary << ", fit " << fit_seconds << " s (" << threads << " threads), order " << order << ", " << opt.lobes
          << " lobes, normalized RMS " << normalized_rms << ", wrote " << out << '\n';
  std::cerr << summary.str();
}

}  // namespace

void setup_fit_zh(CLI::App& app) {
  auto opt = std::make_shared<FitZhOptions>();
  CLI::App* sub = app.add_subcommand("fit-zh", "Simulate diffuse PRT transfer on a mesh and fit ZH lobes per vertex");
  sub->add_option("mesh", opt->mesh, "OBJ mesh (polygons are triangulated)");
  sub->add_option("--transfer", opt->transfer, "fit SH vectors from JSON {\"order\": n, \"vectors\": [[n^2], ...]}");
  sub->add_option("--out", opt->out, "output table (default: <input stem>.zh.shtb in the current folder)");
  sub->add_option("--format", opt->format, "table encoding: binary or json")->capture_default_str();
  sub->add_option("--json", opt->json, "also write the fits as JSON to this file");
  sub->add_option("--ply", opt->ply, "also write the mesh with per-vertex colours (transfer DC, fit error)");
  sub->add_option("--save-transfer", opt->save_transfer, "also write the simulated transfer vectors (--transfer format)");
  CLI::Option* order = sub->add_option("--order", opt->order, "SH order n (bands 0..n-1)")->capture_default_str();
  sub->add_option("--lobes", opt->lobes, "ZH lobes N per vertex")->capture_default_str();
  sub->add_option("--rays", opt->rays, "directions per vertex")->capture_default_str();
  sub->add_option("--mode", opt->mode, "unshadowed, shadowed or interreflected")->capture_default_str();
  sub->add_option("--bounces", opt->bounces, "interreflected: diffuse bounces")->capture_default_str();
  sub->add_option("--albedo", opt->albedo, "interreflected: surface albedo in [0, 1)")->capture_default_str();
  sub->add_option("--normals", opt->normals, "auto (file if complete, else computed), file or computed")
      ->capture_default_str();
  sub->add_option("--seed", opt->seed, "seed of the ray rotations and multi-start axes")->capture_default_str();
  sub->add_option("--starts", opt->starts, "random multi-start axis sets per vertex (effort/quality)")
      ->capture_default_str();
  sub->add_option("--restart-above", opt->restart_above,
                  "multi-start only where residual > this fraction of ||t|| (0: always)")
      ->capture_default_str();
  sub->add_flag("--direct", opt->direct, "store DC (and linear when N >= 3) directly; lobes fit the rest");
  sub->add_option("--threads", opt->threads, "worker threads (0: all cores)")->capture_default_str();
  sub->callback([opt, order]() {
    opt->order_given = order->count() > 0;
    run_fit_zh(*opt);
  });
}

}  // namespace shtool::cli
