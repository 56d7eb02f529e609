// fit-zh as a library job: PRT transfer simulated on a mesh (or SH vectors read from
// JSON), a multi-lobe ZH fit per vertex ([4] Sec. 4.1), and the outputs (zh-fit table,
// JSON fits, coloured PLY, the transfer vectors, a glTF mesh with the fits) written all
// together or not at all.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "fit/mesh.h"
#include "fit/transfer.h"
#include "fit/zh_fit.h"
#include "shtool/table.h"

namespace shtool::fit {

struct FitZhRequest {
  std::filesystem::path mesh;      // OBJ mesh, or empty with `transfer`
  std::filesystem::path transfer;  // JSON {"order": n, "vectors": [[n^2 numbers], ...]}
  // Outputs. `out` empty: <input stem>.zh.shtb (or .zh.json) in the current folder.
  std::filesystem::path out, json, ply, save_transfer;
  // The mesh with its fits as vertex attributes, binary glTF (fit/zh_fit_gltf.h).
  std::filesystem::path gltf;
  TableEncoding encoding = TableEncoding::binary;
  TransferMode mode = TransferMode::shadowed;
  NormalSource normals = NormalSource::automatic;
  UpAxis up = UpAxis::y;  // an OBJ's up axis (a glTF is +Y up); the table records it
  int order = 6;
  bool order_given = false;  // with `transfer`: the file's order must match
  int lobes = 4;
  int rays = 1024;
  int bounces = 2;
  double albedo = 0.8;
  std::uint64_t seed = 1;
  // --effort sets the multi-start (fit/zh_fit.h apply_effort); --starts and
  // --restart-above, when given, override its values.
  int effort = kDefaultEffort;
  std::optional<int> starts;
  std::optional<double> restart_above;
  ZhFitMethod fit_method = ZhFitMethod::varpro;
  bool direct = false;
  int threads = 0;  // 0: all cores
  // "K/N" (fit/shard.h): fit only the K-th of N vertex ranges and write a partial table
  // for `shtool merge`. Empty: the whole mesh.
  std::string shard;
  // --texture RES: bake per texel of the mesh's RES x RES UV atlas (fit/texture_bake.h)
  // instead of per vertex; the table's rows are the covered texels and the maps are
  // written beside `out`.
  std::optional<int> texture;
  // Under mpirun: rank R of S fits shard R/S, rank 0 gathers the rows and writes every
  // output (the other ranks write nothing). Needs a build with MPI.
  bool mpi = false;
};

struct FitZhCallbacks {
  std::function<void(std::size_t, std::size_t)> simulate_progress, fit_progress;
  std::function<void(const std::string&)> warning;  // e.g. skipped degenerate faces
};

struct FitZhReport {
  std::size_t count = 0;  // vertices or vectors fitted
  bool from_mesh = false;
  double simulate_seconds = 0, fit_seconds = 0;
  int threads = 1;
  int order = 0, lobes = 0;
  double normalized_rms = 0;
  std::filesystem::path out;
  // With a shard: its rows [first_vertex, end_vertex) of `total` vertices or vectors.
  bool sharded = false;
  std::size_t shard_index = 0, shard_count = 1, first_vertex = 0, end_vertex = 0, total = 0;
  // With --texture: the atlas resolution and the maps written (count is the texels baked).
  int texture_resolution = 0;
  std::filesystem::path dc_linear_map, lobes_map;
  // With --mpi: this process's rank and the rank count; only rank 0 wrote.
  int mpi_rank = 0, mpi_ranks = 0;
};

// The fit options of a request (lobes, effort, starts, restart_above, seed, method,
// direct) for vectors of `order`, checked as run_fit_zh checks them (InputError): the
// per-vector fits of fit_zh_all are then the ones fit-zh makes.
void check_fit_options(const FitZhRequest& request);
ZhFitOptions fit_zh_options(const FitZhRequest& request, int order);

// Checks the request and every output path before any work (InputError), runs the job,
// writes the outputs.
FitZhReport run_fit_zh(const FitZhRequest& request, const FitZhCallbacks& callbacks = {});

}  // namespace shtool::fit
