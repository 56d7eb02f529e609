// render --shading glossy: a glossy-zh bake ([4] Sec. 3.2) shaded per pixel with Eq. 16.
// Each vertex's rows r_j (Eq. 13 per row of M') are computed once per lighting channel;
// a pixel takes, for each corner of the hit triangle, the view direction from the hit
// point to the eye in that corner's frame, its view factors u(v), and sum_j u_j r_j, and
// blends the three with the hit's barycentric weights. Each vertex is shaded in its own
// frame, so the tangents need not agree from vertex to vertex.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "fit/mesh.h"
#include "lighting/image_io.h"
#include "lighting/lighting_output.h"
#include "shtool/glossy.h"

namespace shtool::render {

// The fit's rows for `mesh` (rows in its kept-vertex order: the table's vertex_index must
// be the mesh's, or absent with as many vertices). Throws InputError naming `what`.
GlossyFit<double> glossy_fit_for_mesh(GlossyFit<double> fit, const fit::Mesh& mesh, const std::string& what);

// The fit carried to a pose: every row's axes (and direct linear band) turned by its
// vertex's rest-to-pose rotation (fit/deformation.h).
GlossyFit<double> deform_glossy_fit(const GlossyFit<double>& fit, const std::vector<Eigen::Matrix3d>& rotations);

// What the primary rays hit, pixel by pixel (triangle -1: nothing).
struct PixelHits {
  int width = 0, height = 0;
  std::span<const int> triangle;
  std::span<const double> w1, w2;
};

// RGBA image: radiance of Eq. 16, alpha coverage. `frames` are the vertex frames of
// `mesh` (the pose's when posed), `eye` the camera position.
lighting::Image glossy_panel(const PixelHits& hits, const fit::Mesh& mesh, const std::vector<Eigen::Matrix3d>& frames,
                             const GlossyFit<double>& fit, const lighting::Lighting& light, const Eigen::Vector3d& eye,
                             int threads);

}  // namespace shtool::render
