// shtool light: analytic lights as SH, in project-env's lighting JSON (docs/lighting.md).
// The job is lighting::run_light (src/offline/lighting/light_job.h).
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "lighting/light_job.h"

namespace shtool::cli {
namespace {

std::array<double, 3> triple(const std::string& text, const std::string& what) {
  const std::vector<double> v = parse_number_list(text, what);
  if (v.size() != 3) throw InputError(what + " needs three numbers, got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

}  // namespace

void setup_light(CLI::App* sub) {
  auto opt = std::make_shared<lighting::LightRequest>();
  auto spec = std::make_shared<lighting::LightSpec>();
  auto text = std::make_shared<std::array<std::string, 3>>();  // dir, color, ground
  auto half = std::make_shared<double>(0);
  CLI::Option* type = add_enum_option(sub, "--type", spec->type, lighting::light_type_names(),
                                      "directional, cone, sphere, hemisphere or constant", "directional");
  CLI::Option* dir = sub->add_option("--dir", (*text)[0], "light direction x,y,z (shtool's z-up frame)");
  CLI::Option* angle = sub->add_option("--half-angle", *half, "cone, sphere: half-angle in degrees");
  CLI::Option* color = sub->add_option("--color", (*text)[1], "r,g,b radiance (directional: integral) [1,1,1]");
  CLI::Option* ground = sub->add_option("--ground", (*text)[2], "hemisphere: r,g,b below the horizon [0,0,0]");
  sub->add_option("--lights", opt->list, "several lights from a JSON list (instead of --type ...)");
  sub->add_option("--order", opt->order, "SH order N")->capture_default_str();
  add_enum_option(sub, "--quantity", opt->quantity, lighting::quantity_names(),
                  "radiance, or irradiance (clamped-cosine kernel)", "radiance");
  sub->add_option("--json", opt->json, "output lighting JSON")->required();
  sub->add_option("--out", opt->out, "also write the coefficients as a table (kind env-sh)");
  add_table_format_option(sub, opt->encoding);
  sub->callback([=]() {
    const bool any = type->count() || dir->count() || angle->count() || color->count() || ground->count();
    if (any) {
      if (!type->count()) throw InputError("--type is required with --dir, --half-angle, --color or --ground");
      if (dir->count()) spec->direction = triple((*text)[0], "--dir");
      if (angle->count()) spec->half_angle_degrees = *half;
      if (color->count()) spec->color = triple((*text)[1], "--color");
      if (ground->count()) {
        if (spec->type != lighting::LightType::hemisphere) throw InputError("--ground applies to --type hemisphere");
        spec->ground = triple((*text)[2], "--ground");
      }
      opt->lights = {*spec};
    }
    const lighting::Lighting l = lighting::run_light(*opt);
    std::cerr << "light: order " << l.order << ", " << lighting::quantity_name(l.quantity) << ", wrote "
              << opt->json.string() << '\n';
  });
}

}  // namespace shtool::cli
