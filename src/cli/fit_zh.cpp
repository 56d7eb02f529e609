// shtool fit-zh: PRT transfer simulation on a mesh (or given SH vectors), then a
// multi-lobe ZH fit per vertex ([4] Sec. 4.1). See docs/fit-zh.md. The job is
// fit::run_fit_zh (src/offline/fit/fit_zh_job.h); this file parses and prints.
#include <cstdio>
#include <iostream>
#include <memory>
#include <sstream>
#include <string>

#include <unistd.h>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "fit/fit_zh_job.h"

namespace shtool::cli {
namespace {

// A progress bar on stderr, only when stderr is a terminal (quiet otherwise).
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

}  // namespace

void setup_fit_zh(CLI::App* sub) {
  auto opt = std::make_shared<fit::FitZhRequest>();
  sub->add_option("mesh", opt->mesh, "OBJ or glTF mesh (OBJ polygons are triangulated)");
  sub->add_option("--transfer", opt->transfer, "fit SH vectors from JSON {\"order\": n, \"vectors\": [[n^2], ...]}");
  sub->add_option("--out", opt->out, "output table (default: <input stem>.zh.shtb in the current folder)");
  add_table_format_option(sub, opt->encoding);
  sub->add_option("--json", opt->json, "also write the fits as JSON to this file");
  sub->add_option("--ply", opt->ply, "also write the mesh with per-vertex colours (transfer DC, fit error)");
  sub->add_option("--save-transfer", opt->save_transfer, "also write the simulated transfer vectors (--transfer format)");
  sub->add_option("--gltf", opt->gltf, "also write the mesh with the fits as vertex attributes (binary glTF, .glb)");
  CLI::Option* order = sub->add_option("--order", opt->order, "SH order n (bands 0..n-1)")->capture_default_str();
  sub->add_option("--lobes", opt->lobes, "ZH lobes N per vertex")->capture_default_str();
  sub->add_option("--rays", opt->rays, "directions per vertex")->capture_default_str();
  add_enum_option(sub, "--mode", opt->mode, fit::transfer_mode_names(), "unshadowed, shadowed or interreflected",
                  "shadowed");
  sub->add_option("--bounces", opt->bounces, "interreflected: diffuse bounces")->capture_default_str();
  sub->add_option("--albedo", opt->albedo, "interreflected: surface albedo in [0, 1)")->capture_default_str();
  add_up_option(sub, opt->up);
  add_enum_option(sub, "--normals", opt->normals, fit::normal_source_names(),
                  "auto (file if complete, else computed), file or computed", "auto");
  add_seed_option(sub, opt->seed, "seed of the ray rotations and multi-start axes");
  sub->add_option("--effort", opt->effort,
                  "fit effort 1..4: sets --starts and --restart-above, with L = --lobes (1: 0, 0.05; 2: 5 L^2, 0.05; "
                  "3: 12 L^2, 0; 4: 40 L^2, 0)")
      ->capture_default_str();
  // Plain values here; the request holds them only when given.
  auto starts = std::make_shared<int>(0);
  auto restart_above = std::make_shared<double>(0.0);
  CLI::Option* starts_option =
      sub->add_option("--starts", *starts, "random multi-start axis sets per vertex (overrides --effort's)");
  CLI::Option* restart_option =
      sub->add_option("--restart-above", *restart_above,
                      "multi-start only where residual > this fraction of ||t|| (0: always; overrides --effort's)");
  add_enum_option(sub, "--fit-method", opt->fit_method, fit::fit_method_names(),
                  "varpro (search the axes, coefficients solved) or joint (the reference: axes and coefficients "
                  "together)",
                  "varpro");
  sub->add_flag("--direct", opt->direct, "store DC (and linear when N >= 3) directly; lobes fit the rest");
  auto texture = std::make_shared<int>(0);
  CLI::Option* texture_option = sub->add_option(
      "--texture", *texture,
      "RES: bake per texel of the mesh's RES x RES UV atlas (OBJ vt, glTF TEXCOORD_0) instead of per vertex; "
      "writes <out stem>.dc_linear.exr and <out stem>.lobes.exr beside the table");
  add_threads_option(sub, opt->threads);
  sub->add_flag("--mpi", opt->mpi, "under mpirun: ranks split the vertices, rank 0 writes the table");
  sub->add_option("--shard", opt->shard,
                  "K/N: fit the K-th (0-based) of N vertex ranges into a partial table for shtool merge");
  sub->callback([opt, order, starts, restart_above, starts_option, restart_option, texture, texture_option]() {
    opt->order_given = order->count() > 0;
    if (texture_option->count() > 0) opt->texture = *texture;
    if (starts_option->count() > 0) opt->starts = *starts;
    if (restart_option->count() > 0) opt->restart_above = *restart_above;
    fit::FitZhCallbacks cb;
    cb.simulate_progress = progress_bar("simulate");
    cb.fit_progress = progress_bar("fit");
    cb.warning = [](const std::string& w) { std::cerr << "fit-zh: warning: " << w << '\n'; };
    const fit::FitZhReport r = fit::run_fit_zh(*opt, cb);
    if (r.mpi_rank != 0) return;  // rank 0 reports the job
    std::ostringstream summary;
    summary.precision(4);
    summary << "fit-zh: " << r.count << (r.texture_resolution ? " texels" : r.from_mesh ? " vertices" : " vectors");
    if (r.texture_resolution)
      summary << " of a " << r.texture_resolution << " x " << r.texture_resolution << " atlas";
    if (r.sharded)
      summary << " (shard " << r.shard_index << "/" << r.shard_count << ": [" << r.first_vertex << ", "
              << r.end_vertex << ") of " << r.total << ")";
    if (r.from_mesh) summary << ", simulation " << r.simulate_seconds << " s";
    summary << ", fit " << r.fit_seconds << " s (" << r.threads << " threads";
    if (r.mpi_ranks) summary << " on each of " << r.mpi_ranks << " MPI ranks";
    summary << "), order " << r.order << ", " << r.lobes
            << " lobes, normalized RMS " << r.normalized_rms << ", wrote " << r.out.string();
    if (r.texture_resolution) summary << ", " << r.dc_linear_map.string() << ", " << r.lobes_map.string();
    for (const std::filesystem::path* written : {&opt->json, &opt->ply, &opt->save_transfer, &opt->gltf})
      if (!written->empty()) summary << ", " << written->string();
    summary << '\n';
    std::cerr << summary.str();
  });
}

}  // namespace shtool::cli
