// render as a library job: a mesh shaded by its baked transfer under SH lighting, seen
// through a pinhole camera (docs/ldprt.md). Embree primary rays; the exit radiance of
// each vertex (transfer . lighting, [4] Eq. 13 for ZH lobes, Eq. 24-25 for the tabulated
// form) is interpolated across the hit triangle with the hit's barycentric coordinates.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "common/enum_names.h"
#include "common/mesh_frame.h"
#include "view/camera.h"

namespace shtool::render {

enum class Shading { automatic, transfer, zh, zh_table, error, normals, membrane, wrinkle, glossy };
const EnumNames<Shading>& shading_names();

using Camera = view::Camera;  // in shtool's frame (z up)

struct RenderRequest {
  std::filesystem::path mesh;      // OBJ or glTF
  UpAxis up = UpAxis::y;           // the OBJ's up axis (mesh and pose); must be the bake's
  std::filesystem::path pose;      // optional: a posed mesh of mesh's topology, rendered with the
                                   // fit's lobes (or the transfer) rotated into its frames
  std::filesystem::path fit;       // zh-fit table (fit-zh --out), or glossy-zh (fit-glossy --out)
  std::filesystem::path transfer;  // transfer JSON (fit-zh --save-transfer)
  std::filesystem::path light;     // lighting JSON (project-env --json, light --json): radiance, RGB
  std::filesystem::path out;       // .exr (linear RGB + coverage alpha) or .png (tone-mapped sRGB)
  std::optional<Camera> camera;    // none: framed on the mesh's bounding sphere
  double fov = 40;                 // vertical field of view, degrees, in (0, 180)
  int width = 512, height = 512;
  // automatic: transfer with --transfer, else glossy for a glossy-zh --fit, else zh
  Shading shading = Shading::automatic;
  double exposure = 0;             // PNG: radiance scaled by 2^exposure before tone mapping
  int zh_table_resolution = 32;    // zh-table: ZhLightTable resolution
  int threads = 0;                 // 0: every core
  // membrane: [4]'s thin-membrane model (shtool/membrane.h), one lobe along the normal, with
  // transparency `alpha`, or per vertex from `alpha_map` (JSON {"alpha": [...]}, one value in
  // [0, 1] per vertex a triangle uses, in file order).
  double alpha = 0;
  std::filesystem::path alpha_map;
  // wrinkle: [4] Sec. 4.2's wrinkle map (a wrinkle-zh table, fit-wrinkles --out) placed by
  // per-vertex groove coordinates (JSON {"x": [...], "d": [...]}, one value each per vertex a
  // triangle uses, in file order); render/wrinkle_shading.h.
  std::filesystem::path wrinkle;
  std::filesystem::path wrinkle_map;
  // One strip instead: transfer, ZH fits of N = 1..4 lobes made from the transfer, and the
  // N = 4 error map, each labelled with its normalized RMS ([4] Fig. 3's layout).
  bool compare = false;
  // Optional: an EXR of the same size to measure the image against (e.g. a bake with more
  // lobes or SVD terms): sqrt(sum over pixels and RGB of (image - reference)^2 / sum of
  // reference^2).
  std::filesystem::path reference;
};

struct RenderResult {
  Shading shading = Shading::transfer;
  std::size_t covered_pixels = 0;
  // Pixels with a channel below zero (truncated lighting or transfer rings; PNG shows them
  // black) and the lowest value among them.
  std::size_t negative_pixels = 0;
  double minimum = 0;
  int width = 0, height = 0;  // of the image written (--compare: the whole strip)
  double seconds = 0;  // rays, shading (and the fits of --compare), not reading or writing files
  std::vector<double> compare_nrms;  // --compare: normalized RMS of the N = 1..4 fits
  std::optional<double> reference_nrms;  // --reference: the image's normalized RMS against it
  std::vector<std::string> notes;        // inputs given that this shading does not use
};

// Checks the request (InputError naming the option: missing inputs for the shading, a
// row count that does not match the mesh, an irradiance lighting, a bad size or field of
// view, an output that is neither .exr nor .png), renders, writes the image atomically.
RenderResult run_render(const RenderRequest& request);

}  // namespace shtool::render
