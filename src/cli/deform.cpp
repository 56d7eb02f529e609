// shtool deform: a ZH fit carried from its rest mesh onto a pose (docs/ldprt.md).
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "deform/deform_job.h"

namespace shtool::cli {

void setup_deform(CLI::App* sub) {
  auto req = std::make_shared<deform::DeformRequest>();
  sub->add_option("fit", req->fit, "zh-fit table baked on the rest mesh (fit-zh --out)")->required();
  sub->add_option("--rest", req->rest, "the rest mesh (OBJ or glTF) the fit was baked on")->required();
  sub->add_option("--pose", req->pose, "the posed mesh (OBJ or glTF, the rest mesh's topology)")->required();
  sub->add_option("--out", req->out, "zh-fit table of the posed mesh")->required();
  sub->add_option("--json", req->json, "also the posed fits in fit-zh's JSON layout");
  add_up_option(sub, req->up);
  sub->callback([req]() {
    const deform::DeformReport report = deform::run_deform(*req);
    std::cerr << "deform: " << report.vertices << " vertices, largest frame rotation " << report.largest_angle
              << " rad, wrote " << req->out.string() << (req->json.empty() ? "" : ", " + req->json.string()) << "\n";
  });
}

}  // namespace shtool::cli
