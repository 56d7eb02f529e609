// shtool transform-splats: a similarity transform of a 3D Gaussian Splatting PLY, its
// SH colours rotated (docs/interop.md). The job is interop::run_transform_splats.
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "interop/splats_job.h"

namespace shtool::cli {

void setup_transform_splats(CLI::App& app) {
  auto opt = std::make_shared<interop::TransformSplatsRequest>();
  auto text = std::make_shared<std::array<std::string, 3>>();  // quat, matrix, translate
  CLI::App* sub = app.add_subcommand("transform-splats",
                                     "Rotate, scale and move a 3D Gaussian Splatting PLY, its SH colours included");
  sub->add_option("in", opt->in, "input PLY (binary little or big endian, or ASCII)")->required();
  CLI::Option* quat = sub->add_option("--quat", (*text)[0], "rotation as a unit quaternion w,x,y,z");
  CLI::Option* matrix = sub->add_option("--matrix", (*text)[1], "rotation as a matrix r00,r01,...,r22 (row-major)");
  CLI::Option* translate = sub->add_option("--translate", (*text)[2], "translation x,y,z (after rotation and scale)");
  sub->add_option("--scale", opt->scale, "uniform scale s > 0")->capture_default_str();
  sub->add_option("--out", opt->out, "output PLY (same header and layout)")->required();
  sub->add_option("--threads", opt->threads, "worker threads (0: all cores)")->capture_default_str();
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
    const interop::TransformSplatsReport r = interop::run_transform_splats(*opt);
    std::cerr << "transform-splats: " << r.splats << " splats, SH degree " << r.degree << ", " << r.seconds << " s ("
              << r.threads << " threads), wrote " << opt->out.string() << '\n';
  });
}

}  // namespace shtool::cli
