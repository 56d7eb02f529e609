// 3D Gaussian Splatting PLY files (graphdeco-inria's layout) and SplatScene: the
// properties found by name, read into a scene, and a scene written in the reference
// layout (docs/splats.md).
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "interop/ply.h"
#include "interop/splat_scene.h"

namespace shtool::interop {

// The splat properties of a vertex element (indices into its properties), found by
// name: x y z, nx ny nz, rot_0..3 (w x y z), scale_0..2 (log), f_dc_0..2, f_rest_*
// (channel-major: all of R, then G, then B), opacity (logit).
struct SplatLayout {
  std::array<std::size_t, 3> position{};
  std::optional<std::array<std::size_t, 3>> normal;
  std::optional<std::array<std::size_t, 4>> rotation;
  std::optional<std::array<std::size_t, 3>> scale;
  std::optional<std::array<std::size_t, 3>> dc;
  std::optional<std::size_t> opacity;
  std::vector<std::size_t> rest;  // f_rest_0 .. f_rest_{K-1}
  int degree = 0;
};

// InputError naming `name` when a property is missing, not float, or the f_rest set is
// not that of degree 0..3.
SplatLayout find_splat_layout(const PlyElement& vertex, const std::filesystem::path& name);

// The whole scene (every splat property required but the normals); InputError naming
// `name` on a missing property or a value that is not finite.
SplatScene read_ply_splats(const PlyFile& ply, const std::filesystem::path& name, int threads);

// The reference layout, binary little endian float: x y z nx ny nz (zeros) f_dc_0..2
// f_rest_* opacity scale_0..2 rot_0..3.
std::string write_ply_splats(const SplatScene& scene);

}  // namespace shtool::interop
