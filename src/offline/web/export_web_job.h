// export-web as a library job: a mesh, its ZH fit and an SH lighting as a folder that any
// static web server serves (docs/web.md). three.js draws the mesh with the GLSL that
// gen-shader generates: the light rotated on the GPU by the zxzxz rotation (once per frame
// into a float texture, or per vertex where WebGL has no float render targets), each vertex
// shaded by [4] Eq. 13 with its lobes, the exit radiance interpolated across the triangles
// and tone-mapped as render's PNG, seen through render's camera for the same options.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "common/mesh_frame.h"
#include "view/camera.h"

namespace shtool::web {

struct ExportWebRequest {
  std::filesystem::path mesh;     // OBJ or glTF, the one the fit was baked on
  UpAxis up = UpAxis::y;          // the OBJ's up axis (mesh and pose)
  std::filesystem::path pose;     // optional: a posed mesh of mesh's topology (the fit turned into its frames)
  std::filesystem::path fit;      // zh-fit table (fit-zh --out), per vertex
  std::filesystem::path light;    // lighting JSON (project-env --json, light --json): radiance, RGB
  std::filesystem::path probes;   // optional: probe-grid table (bake-probes --out)
  std::filesystem::path out;      // the folder to write (created if missing, with its missing parents)
  std::optional<view::Camera> camera;  // none: render's framing of the (posed) mesh
  double fov = 40;                // vertical, degrees
  int width = 512, height = 512;
  double exposure = 0;            // radiance scaled by 2^exposure before tone mapping
};

struct ExportWebResult {
  std::vector<std::filesystem::path> files;  // written, relative to out
  int order = 0, lobes = 0;                   // of the shader
  std::size_t vertices = 0, triangles = 0;
  std::vector<std::string> warnings;         // what the page may draw wrong (a probe box ending at the ground)
};

// Checks everything before writing (InputError naming the problem: a fit of another mesh
// or a texture-space bake, a fit or light order the generated shaders cannot take, too
// many vertex attributes for WebGL2, an irradiance light, a missing three.js, an
// unwritable folder), then writes every file at once or none; a folder it created is
// removed again on failure.
ExportWebResult run_export_web(const ExportWebRequest& request);

}  // namespace shtool::web
