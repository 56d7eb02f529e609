// glTF scenes of Gaussian splats by the KHR_gaussian_splatting extension
// (docs/splats.md): POINTS primitives whose attributes are POSITION and
// KHR_gaussian_splatting:ROTATION (x y z w), :SCALE (linear), :OPACITY (linear),
// :SH_DEGREE_l_COEF_n (n = 0..2l for m = -l..l; degree 0 the DC coefficient).
#pragma once

#include <filesystem>
#include <string>

#include "interop/splat_scene.h"

namespace shtool::interop {

// Every splat primitive of the default scene, in node order, all of one SH degree,
// placed by the transforms of its node and the node's ancestors (translation, rotation,
// scale or matrix, composed down the hierarchy) as transform_splat_scene moves a scene:
// positions, orientations, scales and SH colours together. A transform that is not a
// similarity (non-uniform scale, shear) is refused: its SH colours have no exact image.
// Linear scales
// of 0 and opacities of 0 or 1 get the nearest finite log / logit (1e-30; 1e-7 from
// the ends). The extension object's colorSpace becomes the scene's colour_space (absent:
// srgb_rec709_display); a kernel other than "ellipse" is refused. InputError naming
// `path` on anything malformed.
SplatScene read_gltf_splats(const std::string& bytes, const std::filesystem::path& path, int threads = 1);

// One node, one mesh, one POINTS primitive, float attributes, the scene's colour space;
// binary (.glb) or text with the buffer embedded (.gltf). InputError naming the splat
// when a linear scale exp(log-scale) overflows float (glTF allows no infinity).
std::string write_gltf_splats(const SplatScene& scene, bool binary);

}  // namespace shtool::interop
