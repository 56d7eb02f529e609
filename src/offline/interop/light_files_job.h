// shtool export-light and import-light as jobs: the conversions of interop/engine_light.h
// between files, with the job frame's checks (common/job_outputs.h).
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "interop/engine_light.h"

namespace shtool::interop {

struct ExportLightRequest {
  std::filesystem::path in;   // lighting JSON (project-env / light --json)
  std::filesystem::path out;  // the engine's file
  LightFormat format = LightFormat::threejs;
  FrameMap frame;
  double intensity = 1;
  RawOptions raw;
};

// Returns the notes to tell the user (truncation, folded intensity, ...).
std::vector<std::string> run_export_light(const ExportLightRequest& request);

struct ImportLightRequest {
  std::filesystem::path in;    // the engine's file
  std::filesystem::path json;  // lighting JSON written
  LightFormat format = LightFormat::threejs;
  FrameMap frame;
  lighting::Quantity quantity = lighting::Quantity::radiance;
};

lighting::Lighting run_import_light(const ImportLightRequest& request);

}  // namespace shtool::interop
