// fit-zh --gltf: the baked mesh as a binary glTF 2.0 file (.glb) carrying every vertex's
// ZH fit as custom vertex attributes, so that an engine loads mesh and fit in one file.
// The attribute names, the packing and the colour mapping are a contract
// (docs/fit-zh.md, "glTF output"):
// Every direction is in glTF's frame, +Y up: engine = (x, z, -y) of shtool's (the inverse
// of the map the loaders apply), so a .glb read back by fit-zh gives the same mesh,
// rounded to float, and a glTF input's positions come back exactly.
//   POSITION, NORMAL    VEC3 float, the mesh as loaded
//   COLOR_0             VEC3 float, grey = clamp(t_00 / y00, 0, 1), linear
//   _ZH_AXIS_k          VEC3 float, unit axis s_k of lobe k (y >= 0), k = 0..lobes-1
//   _ZH_COEFFS_k_j      VEC4 float, g*_l of lobe k for l = 4j..4j+3 (zero past order-1)
//   _ZH_DIRECT          VEC4 float, with --direct only: the stored coefficients in SH
//                       index order (DC, then y_1^-1, y_1^0, y_1^1), zero-padded: the
//                       basis formula of docs/conventions.md applied to glTF coordinates
// indices: the smallest unsigned type below its primitive-restart value; one TRIANGLES
// primitive, one mesh, one node, one scene.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "fit/mesh.h"
#include "shtool/zh_fit_table.h"

namespace shtool::fit {

// The grey of a vertex in COLOR_0 and the PLY: its transfer's DC t_00 relative to that of
// an open plane (unshadowed, 1/(2 sqrt(pi))), clamped to [0, 1].
double transfer_dc_grey(double t00);

// The .glb bytes. `fits` and `transfer_dc` (the transfer's DC coefficient t_00) have one
// row per mesh vertex; `generator` goes to asset.generator. Throws InputError when the
// sizes disagree or the file would pass the 4 GB (32-bit lengths) of a .glb.
std::string zh_fit_glb(const Mesh& mesh, const ZhFitTable<double>& fits, std::span<const double> transfer_dc,
                       const std::string& generator);

}  // namespace shtool::fit
