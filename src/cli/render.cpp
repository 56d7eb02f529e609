// shtool render: a mesh shaded by its baked transfer under SH lighting (docs/ldprt.md).
#include <algorithm>
#include <iostream>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "render/render_job.h"

namespace shtool::cli {

void setup_render(CLI::App* sub) {
  auto req = std::make_shared<render::RenderRequest>();
  auto camera = std::make_shared<std::string>();
  sub->add_option("mesh", req->mesh, "mesh, OBJ or glTF (the one the transfer or fit was baked on)")->required();
  sub->add_option("--pose", req->pose, "posed mesh (OBJ or glTF, the rest mesh's topology): render it with the fit or "
                                       "transfer rotated into its frames, without re-simulation");
  sub->add_option("--fit", req->fit,
                  "zh-fit table (fit-zh --out; a --texture bake: its maps beside it are sampled per pixel), or "
                  "glossy-zh table (fit-glossy --out)");
  sub->add_option("--transfer", req->transfer, "transfer vectors JSON (fit-zh --save-transfer)");
  sub->add_option("--light", req->light, "lighting JSON (project-env --json, light --json), radiance, RGB");
  add_up_option(sub, req->up);
  sub->add_option("--camera", *camera, "eye,target,up: nine numbers in shtool's frame, z up (default: the mesh framed in three-quarters "
                  "from the side the model faces (glTF: -y; OBJ: +y), a little above)");
  sub->add_option("--fov", req->fov, "vertical field of view, degrees")->capture_default_str();
  sub->add_option("--width", req->width, "image width")->capture_default_str();
  sub->add_option("--height", req->height, "image height")->capture_default_str();
  EnumNames<render::Shading> names = render::shading_names();
  add_enum_option(sub, "--shading", req->shading, names,
                  "transfer (t . e), zh (Eq. 13), zh-table (Eq. 24-25), error (|zh - transfer|), normals, "
                  "membrane (thin-membrane model, Eq. 22-23), wrinkle (wrinkle map, Sec. 4.2), glossy (Eq. 16)",
                  "transfer with --transfer, else glossy for a glossy-zh --fit, else zh");
  CLI::Option* alpha =
      sub->add_option("--alpha", req->alpha, "membrane: transparency in [0, 1]")->capture_default_str();
  sub->add_option("--alpha-map", req->alpha_map, "membrane: JSON {\"alpha\": [one per vertex]}")->excludes(alpha);
  sub->add_option("--wrinkle", req->wrinkle, "wrinkle: the map, a wrinkle-zh table (fit-wrinkles --out)");
  sub->add_option("--wrinkle-map", req->wrinkle_map,
                  "wrinkle: JSON {\"x\": [...], \"d\": [...]}, groove position (period 1) and depth per vertex");
  sub->add_option("--exposure", req->exposure, "PNG: scale by 2^E before tone mapping")->capture_default_str();
  sub->add_flag("--compare", req->compare,
                "one strip: transfer, ZH fits with 1..4 lobes (fitted here), the N = 4 error; normalized RMS under each");
  sub->add_option("--reference", req->reference,
                  "EXR of the same size: print the image's normalized RMS difference from it");
  add_threads_option(sub, req->threads);
  sub->add_option("--out", req->out, "image: .exr (linear RGB, coverage alpha) or .png (tone-mapped sRGB)")
      ->required();
  sub->callback([req, camera]() {
    render::RenderRequest r = *req;
    r.camera = parse_camera(*camera);
    const render::RenderResult result = render::run_render(r);
    for (const std::string& note : result.notes) std::cerr << "render: note: " << note << "\n";
    std::cerr << "render: wrote " << r.out.string() << " (" << result.width << " x " << result.height << ", "
              << result.covered_pixels << " pixels covered, " << result.seconds << " s)\n";
    if (result.negative_pixels)
      std::cerr << "render: " << result.negative_pixels << " pixels below zero ("
                << 100.0 * result.negative_pixels / std::max<std::size_t>(result.covered_pixels, 1)
                << " % of those covered), lowest " << result.minimum << "\n";
    if (result.reference_nrms)
      std::cerr << "render: normalized RMS against " << r.reference.string() << ": " << *result.reference_nrms << "\n";
    for (std::size_t k = 0; k < result.compare_nrms.size(); ++k)
      std::cerr << "render: ZH N = " << k + 1 << ", normalized RMS " << result.compare_nrms[k] << "\n";
  });
}

}  // namespace shtool::cli
