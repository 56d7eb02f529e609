#include "interop/light_files_job.h"

#include "common/input_file.h"
#include "common/job_outputs.h"

namespace shtool::interop {

std::vector<std::string> run_export_light(const ExportLightRequest& r) {
  JobOutputs io;
  io.input(r.in, "the lighting");
  io.output(r.out, "--out");
  const lighting::Lighting l = lighting::read_lighting_json(r.in, "light");
  ExportedLight e = export_light(l, r.format, r.frame, r.intensity, r.raw);
  io.set("--out", std::move(e.text));
  io.commit();
  return e.notes;
}

lighting::Lighting run_import_light(const ImportLightRequest& r) {
  JobOutputs io;
  io.input(r.in, "the engine's file");
  io.output(r.json, "--json");
  const std::string text = read_input_file(r.in, "file");
  const lighting::Lighting l = import_light(text, r.in, r.format, r.frame, r.quantity);
  io.set("--json", lighting::lighting_json(l));
  io.commit();
  return l;
}

}  // namespace shtool::interop
