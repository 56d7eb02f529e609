// shtool transform-splats: converts a 3D Gaussian Splatting scene between PLY, spz and
// glTF by extension, optionally rotated, scaled and moved with its SH colours
// (docs/interop.md, docs/splats.md). The job is interop::run_transform_splats.
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "interop/splats_job.h"

namespace shtool::cli {

void setup_transform_splats(CLI::App* sub) {
  auto opt = std::make_shared<interop::TransformSplatsRequest>();
  auto text = std::make_shared<std::array<std::string, 4>>();  // quat, matrix, translate, sh bits
  auto degree = std::make_shared<int>(-1);
  sub->add_option("in", opt->in, "input scene: .ply (binary or ASCII), .spz (versions 2..4), .gltf/.glb "
                                 "(KHR_gaussian_splatting)")->required();
  CLI::Option* quat = sub->add_option("--quat", (*text)[0], "rotation as a unit quaternion w,x,y,z (input coordinates)");
  CLI::Option* matrix =
      sub->add_option("--matrix", (*text)[1], "rotation or reflection as an orthogonal matrix r00,r01,...,r22 "
                                              "(row-major, input coordinates)");
  CLI::Option* translate = sub->add_option("--translate", (*text)[2], "translation x,y,z (after rotation and scale)");
  sub->add_option("--scale", opt->scale, "uniform scale s > 0")->capture_default_str();
  sub->add_option("--out", opt->out, "output scene, format by extension (.ply: PLY in keeps its layout)")->required();
  sub->add_option("--frame", opt->ply_frame,
                  "axes of PLY files, one letter per x, y, z from R/L, U/D, F/B (3DGS, COLMAP: RDF)")
      ->capture_default_str();
  sub->add_option("--spz-frame", opt->spz_frame,
                  "axes of spz files without a coordinate-system record (the specification: RUB); "
                  "spz written in another frame record it")
      ->capture_default_str();
  sub->add_option("--gltf-frame", opt->gltf_frame,
                  "axes of glTF files (RUB: +Y up, the asset's front +Z; splat-transform's .glb: LUF)")
      ->capture_default_str();
  sub->add_option("--sh-degree", *degree, "output SH degree 0..3 (bands above it dropped, missing ones zero)");
  CLI::Option* bits = sub->add_option("--sh-bits", (*text)[3], "spz output: bits per SH byte, band 1 and bands 2..3 "
                                                                "(B or B1,B2; 1..8; default 5,4)");
  sub->add_option("--spz-version", opt->spz_version, "spz output version, 3 (gzip) or 4 (zstd)")->capture_default_str();
  add_threads_option(sub, opt->threads);
  sub->callback([=]() {
    if (quat->count()) {
      const std::vector<double> q = parse_number_list((*text)[0], "--quat");
      if (q.size() != 4) throw InputError("--quat needs four numbers w,x,y,z");
      opt->quaternion = std::array<double, 4>{q[0], q[1], q[2], q[3]};
    }
    if (matrix->count()) {
      const std::vector<double> m = parse_number_list((*text)[1], "--matrix");
      if (m.size() != 9) throw InputError("--matrix needs nine numbers");
      std::array<double, 9> a{};
      std::copy(m.begin(), m.end(), a.begin());
      opt->matrix = a;
    }
    if (translate->count()) {
      const std::vector<double> t = parse_number_list((*text)[2], "--translate");
      if (t.size() != 3) throw InputError("--translate needs three numbers");
      opt->translate = {t[0], t[1], t[2]};
    }
    if (bits->count()) {
      const std::vector<double> b = parse_number_list((*text)[3], "--sh-bits");
      if (b.empty() || b.size() > 2) throw InputError("--sh-bits needs one or two numbers");
      for (double x : b)
        if (x != static_cast<int>(x)) throw InputError("--sh-bits must be whole numbers");
      opt->sh_bits = {static_cast<int>(b[0]), static_cast<int>(b.back())};
    }
    if (*degree >= 0 || sub->get_option("--sh-degree")->count()) opt->sh_degree = *degree;
    const interop::TransformSplatsReport r = interop::run_transform_splats(*opt);
    for (const std::string& w : r.warnings) std::cerr << "transform-splats: warning: " << w << '\n';
    std::cerr << "transform-splats: " << r.splats << " splats, SH degree " << r.degree;
    if (r.degree_in >= 0 && r.degree_in != r.degree) std::cerr << " (from " << r.degree_in << ")";
    if (r.reflects) std::cerr << ", the map reflects";
    std::cerr << ", " << r.seconds << " s (" << r.threads << " threads), wrote " << opt->out.string() << '\n';
    if (r.spz_sh_bound > 0 || r.spz_dc_bound > 0)
      std::cerr << "transform-splats: spz quantisation, largest colour change over the sphere (one channel): SH bands "
                << r.spz_sh_bound << " from the bucket sizes (coefficients in [-1, 1]), " << r.spz_sh_scene
                << " for this scene's coefficients; DC " << r.spz_dc_bound
                << " from the byte step (coefficients in [-3.33, 3.33]), " << r.spz_dc_scene << " for this scene's\n";
  });
}

}  // namespace shtool::cli
