// shtool export-light / import-light: the lighting JSON of project-env and light in an
// engine's convention, and back (docs/interop.md). The conversions are
// src/offline/interop/engine_light.h; the jobs
// src/offline/interop/light_files_job.h; this file parses and prints.
#include <iostream>
#include <memory>

#include <CLI/CLI.hpp>

#include "cli_common.h"
#include "interop/light_files_job.h"

namespace shtool::cli {
namespace {

struct LightOptions {
  interop::LightFormat format = interop::LightFormat::threejs;
  std::string frame;  // empty: the format's default
  interop::RawOptions raw;
  std::string cs = "on";
};

void add_common(CLI::App* sub, LightOptions& o, bool exporting) {
  add_enum_option(sub, "--format", o.format, exporting ? interop::export_format_names() : interop::light_format_names(),
                  exporting ? "threejs, filament, filament-radiance, unity, gltf, gltf-khr, babylon, godot, raw, or a "
                              "probe encoding: l1 (Geomerics non-linear L1) or zh3"
                            : "threejs, filament, filament-radiance, unity, gltf, gltf-khr, babylon, godot or raw",
                  "threejs")
      ->required();
  sub->add_option("--frame", o.frame, "engine axes in shtool's, e.g. x,z,-y (default: the format's)");
  sub->add_option("--cs", o.cs, "raw: Condon-Shortley phase on or off")->check(CLI::IsMember({"on", "off"}))->default_str("on");
  add_enum_option(sub, "--norm", o.raw.normalization, interop::raw_normalization_names(),
                  "raw: orthonormal, 4pi or schmidt (semi-normalised)", "orthonormal");
}

interop::FrameMap frame_of(const LightOptions& o) {
  return o.frame.empty() ? interop::default_frame(o.format) : interop::parse_frame_map(o.frame);
}

}  // namespace

void setup_export_light(CLI::App* sub) {
  auto o = std::make_shared<LightOptions>();
  auto in = std::make_shared<std::filesystem::path>();
  auto out = std::make_shared<std::filesystem::path>();
  auto intensity = std::make_shared<double>(1);
  sub->add_option("light", *in, "lighting JSON (shtool project-env / light)")->required();
  sub->add_option("--out", *out, "output file")->required();
  sub->add_option("--intensity", *intensity, "scale (the format's intensity field where it has one)")->capture_default_str();
  add_common(sub, *o, true);
  auto axis = std::make_shared<std::string>();
  sub->add_option("--axis", *axis, "zh3: the zonal axis, luminance (shared, the default) or per-channel")
      ->check(CLI::IsMember({"luminance", "per-channel"}));
  sub->callback([=]() {
    o->raw.condon_shortley = o->cs == "on";
    if (o->format != interop::LightFormat::raw && (sub->count("--cs") || sub->count("--norm")))
      throw InputError("--cs and --norm apply to --format raw only (the other formats fix their own)");
    if (!axis->empty()) {
      if (o->format != interop::LightFormat::zh3) throw InputError("--axis applies to --format zh3 only");
      o->raw.zh3_axis = *axis == "luminance" ? Zh3Axis::luminance : Zh3Axis::per_channel;
    }
    const std::vector<std::string> notes =
        interop::run_export_light({*in, *out, o->format, frame_of(*o), *intensity, o->raw});
    for (const std::string& n : notes) std::cerr << "export-light: note: " << n << '\n';
    std::cerr << "export-light: wrote " << out->string() << '\n';
  });
}

void setup_import_light(CLI::App* sub) {
  auto o = std::make_shared<LightOptions>();
  auto in = std::make_shared<std::filesystem::path>();
  auto json = std::make_shared<std::filesystem::path>();
  auto quantity = std::make_shared<lighting::Quantity>(lighting::Quantity::radiance);
  sub->add_option("file", *in, "the engine's file (as export-light writes it)")->required();
  sub->add_option("--json", *json, "output lighting JSON")->required();
  add_enum_option(sub, "--quantity", *quantity, lighting::quantity_names(),
                  "radiance or irradiance", "radiance");
  add_common(sub, *o, false);
  sub->callback([=]() {
    if (sub->count("--cs") || sub->count("--norm"))
      throw InputError(
          "import-light takes no --cs or --norm: a raw file says its own (condon_shortley, normalization)");
    const lighting::Lighting l = interop::run_import_light({*in, *json, o->format, frame_of(*o), *quantity});
    std::cerr << "import-light: order " << l.order << ", " << lighting::quantity_name(l.quantity) << ", wrote "
              << json->string() << '\n';
  });
}

}  // namespace shtool::cli
