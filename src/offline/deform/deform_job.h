// deform as a library job: ZH transfer baked on a rest mesh, carried onto a posed mesh of
// the same topology without re-simulation (fit/deformation.h). docs/ldprt.md, "Deforming
// meshes".
#pragma once

#include <filesystem>

#include "common/mesh_frame.h"

namespace shtool::deform {

struct DeformRequest {
  std::filesystem::path fit;   // zh-fit table baked on `rest`
  std::filesystem::path rest;  // OBJ or glTF
  std::filesystem::path pose;  // OBJ or glTF with the rest mesh's topology
  std::filesystem::path out;   // zh-fit table of the posed mesh
  std::filesystem::path json;  // optional: the posed fits in fit-zh's JSON layout
  UpAxis up = UpAxis::y;       // both meshes' up axis when OBJ; must be the fit's
};

struct DeformReport {
  std::size_t vertices = 0;
  double largest_angle = 0;  // radians: the largest rotation angle of any R_p
};

DeformReport run_deform(const DeformRequest& request);

}  // namespace shtool::deform
