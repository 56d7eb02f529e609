// shtool project-env: an environment image onto SH, exactly per texel (docs/lighting.md).
// The job is lighting::run_project_env (src/offline/lighting/project_env_job.h).
#include <iostream>
#include <memory>
#include <sstream>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "lighting/project_env_job.h"

namespace shtool::cli {

void setup_project_env(CLI::App* sub) {
  auto opt = std::make_shared<lighting::ProjectEnvRequest>();
  auto cutoff = std::make_shared<double>(0);
  sub->add_option("image", opt->image, "EXR, HDR, PNG or JPEG; for --layout faces a pattern with %s (px nx py ny pz nz)")
      ->required();
  sub->add_option("--order", opt->order, "SH order N (bands 0..N-1)")->capture_default_str();
  add_enum_option(sub, "--layout", opt->layout, lighting::layout_names(),
                  "auto (2:1 equirect, 4:3 / 3:4 cross, %s faces), equirect, cross or faces", "auto");
  add_enum_option(sub, "--equirect-preset", opt->preset, lighting::equirect_preset_names(),
                  "whose equirect mapping the image follows: shtool (= three), three, filament, google", "shtool");
  sub->add_flag("--mirror-x", opt->mirror_x, "cubemaps: negate x of the cube frame (as three's CubeTexture, filament)");
  add_enum_option(sub, "--quantity", opt->quantity, lighting::quantity_names(),
                  "radiance, or irradiance (clamped-cosine kernel)", "radiance");
  add_enum_option(sub, "--window", opt->window, lighting::window_names(),
                  "none, hann, lanczos, sinc4, or auto (largest sinc4 cutoff without negative values)", "none");
  CLI::Option* cut = sub->add_option("--cutoff", *cutoff, "window cutoff L (bands l >= L vanish; default: the order)");
  sub->add_option("--json", opt->json, "output lighting JSON")->required();
  sub->add_option("--out", opt->out, "also write the coefficients as a table (kind env-sh)");
  add_table_format_option(sub, opt->encoding);
  sub->add_option("--render-back", opt->render_back, "also write the reconstruction as an equirect .exr or .png");
  sub->add_option("--render-source", opt->render_source,
                  "also write the source image through the render-back's equirect (same size, mapping and tone "
                  "map), to set beside it");
  add_threads_option(sub, opt->threads);
  sub->callback([opt, cutoff, cut]() {
    if (cut->count()) opt->cutoff = *cutoff;
    const lighting::ProjectEnvReport r = lighting::run_project_env(*opt);
    std::ostringstream s;
    s.precision(4);
    s << "project-env: " << r.layout << ", order " << r.lighting.order << ", "
      << lighting::quantity_name(r.lighting.quantity) << ", window " << r.lighting.window["type"].get<std::string>();
    if (r.lighting.window.contains("cutoff") && r.lighting.window["cutoff"].is_number())
      s << " (cutoff " << r.lighting.window["cutoff"].get<double>() << ")";
    s << ", read " << r.read_seconds << " s, projection " << r.project_seconds << " s (" << r.threads
      << " threads), wrote " << opt->json.string() << '\n';
    std::cerr << s.str();
  });
}

}  // namespace shtool::cli
