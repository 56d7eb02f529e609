// The pinhole camera of `render` and `export-web`: one framing rule, so that a page and a
// rendered image of the same options show the same view.
#pragma once

#include <array>
#include <optional>

#include <Eigen/Core>

#include "fit/mesh.h"

namespace shtool::view {

// In shtool's frame (z up), like the meshes once loaded and the lighting.
struct Camera {
  std::array<double, 3> eye{}, target{}, up{0, 0, 1};
};

// A camera point or direction as a vector.
inline Eigen::Vector3d as_vector(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }

// The default view: the mesh's bounding sphere (centred on its bounding box) filling the
// narrower field of view, seen in three-quarters from the side the model faces
// (Mesh::front) and a little above, z up. fov_degrees is vertical; aspect is width / height.
Camera frame_mesh(const fit::Mesh& mesh, double fov_degrees, double aspect);

// The view options of both commands, in range: --width and --height 1..16384, --fov
// 0.01..179 degrees, --exposure -64..64. Throws InputError naming the option.
void check_view_options(int width, int height, double fov_degrees, double exposure);

// --camera, when given: finite coordinates of magnitude at most 1e30, eye and target
// apart, up not along the view. Throws InputError.
void check_camera(const std::optional<Camera>& camera);

// The mesh's bounding box (lo, hi) and the sphere round the box's centre that holds every
// vertex: what frame_mesh fits into the view.
struct MeshBounds {
  Eigen::Vector3d lo, hi, centre;
  double radius;
};
MeshBounds mesh_bounds(const fit::Mesh& mesh);

}  // namespace shtool::view
