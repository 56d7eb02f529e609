// shtool fit-glossy: glossy LDPRT on a mesh, [4] Sec. 3.2 (docs/ldprt.md, "Glossy transfer").
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "fit/fit_zh_job.h"
#include "glossy/glossy_job.h"

namespace shtool::cli {

void setup_fit_glossy(CLI::App* sub) {
  auto req = std::make_shared<glossy::GlossyRequest>();
  sub->add_option("mesh", req->mesh, "OBJ or glTF mesh")->required();
  add_enum_option(sub, "--brdf", req->brdf.model, glossy::brdf_model_names(), "phong or cook-torrance",
                  "cook-torrance");
  sub->add_option("--roughness", req->brdf.roughness,
                  "Beckmann roughness m (Cook-Torrance); Phong's exponent is 2/m^2 - 2")
      ->capture_default_str();
  sub->add_option("--f0", req->brdf.f0, "Schlick reflectance at normal incidence (Cook-Torrance; 1: no Fresnel)")
      ->capture_default_str();
  sub->add_option("--order", req->order, "SH order n of the lighting (2..8)")->capture_default_str();
  sub->add_option("--terms", req->terms, "rows n_b of the BRDF-specialised transfer matrix")->capture_default_str();
  sub->add_option("--lobes", req->lobes, "ZH lobes N per row")->capture_default_str();
  sub->add_option("--view-resolution", req->view_resolution, "side G of the u(v) view map")->capture_default_str();
  sub->add_option("--rays", req->rays, "hemisphere rays per vertex")->capture_default_str();
  add_enum_option(sub, "--mode", req->shadowed, {{"shadowed", true}, {"unshadowed", false}},
                  "shadowed or unshadowed", "shadowed");
  add_up_option(sub, req->up);
  add_enum_option(sub, "--normals", req->normals, fit::normal_source_names(),
                  "vertex normals: the file's when complete (auto), the file's, or computed", "auto");
  add_seed_option(sub, req->seed, "seed of the ray directions and of the fits' starts");
  sub->add_option("--effort", req->effort, "ZH fit effort, 1..4 (as fit-zh)")->capture_default_str();
  add_threads_option(sub, req->threads);
  sub->add_option("--out", req->out, "glossy-zh table to write")->required();
  sub->add_option("--json", req->json, "also a JSON summary (singular values, errors)");
  sub->callback([req]() {
    const glossy::GlossyReport r = glossy::run_fit_glossy(*req);
    std::cerr << "fit-glossy: " << r.vertices << " vertices; BRDF matrix " << r.brdf_seconds << " s, transfer "
              << r.simulate_seconds << " s, ZH fit " << r.fit_seconds << " s\n"
              << "normalized RMS: SVD " << r.svd_nrms << ", ZH fit " << r.zh_nrms << ", total " << r.total_nrms
              << "\nwrote " << req->out.string() << "\n";
  });
}

}  // namespace shtool::cli
