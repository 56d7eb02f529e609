// shtool export-web: a mesh, its ZH fit and a lighting as a self-contained web page
// (three.js, the light turned on the GPU by the generated shaders; docs/web.md).
#include <iostream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "web/export_web_job.h"

namespace shtool::cli {

void setup_export_web(CLI::App* sub) {
  auto req = std::make_shared<web::ExportWebRequest>();
  auto camera = std::make_shared<std::string>();
  sub->add_option("mesh", req->mesh, "mesh, OBJ or glTF (the one the fit was baked on)")->required();
  sub->add_option("--fit", req->fit, "zh-fit table (fit-zh --out), per vertex")->required();
  sub->add_option("--light", req->light, "lighting JSON (project-env --json, light --json), radiance, RGB")
      ->required();
  sub->add_option("--pose", req->pose,
                  "posed mesh (the rest mesh's topology): the page shows it with the fit rotated into its frames");
  sub->add_option("--probes", req->probes,
                  "probe-grid table (bake-probes --out): a ground and spheres beside the mesh lit by it through "
                  "three's LightProbeGridWebGL");
  add_up_option(sub, req->up);
  sub->add_option("--camera", *camera,
                  "eye,target,up: nine numbers in shtool's frame, z up (default: render's framing of the mesh)");
  sub->add_option("--fov", req->fov, "vertical field of view, degrees")->capture_default_str();
  sub->add_option("--width", req->width, "canvas width, pixels")->capture_default_str();
  sub->add_option("--height", req->height, "canvas height, pixels")->capture_default_str();
  sub->add_option("--exposure", req->exposure, "scale by 2^E before tone mapping (as render's PNG)")
      ->capture_default_str();
  sub->add_option("--out", req->out, "the folder to write (created if missing, with its missing parents)")->required();
  sub->callback([req, camera]() {
    web::ExportWebRequest r = *req;
    r.camera = parse_camera(*camera);
    const web::ExportWebResult result = web::run_export_web(r);
    for (const std::string& w : result.warnings) std::cerr << "export-web: warning: " << w << '\n';
    std::cerr << "export-web: wrote " << result.files.size() << " files to " << r.out.string() << " (order "
              << result.order << ", " << result.lobes << " lobes, " << result.vertices << " vertices, "
              << result.triangles << " triangles); serve it with: python3 -m http.server -d " << r.out.string()
              << "\n";
  });
}

}  // namespace shtool::cli
