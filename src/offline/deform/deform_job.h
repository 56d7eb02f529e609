// deform as a library job: ZH transfer baked on a rest mesh, carried onto a posed mesh of
// the same topology without re-simulation ([4] Sec. 6 and "LDPRT rendering": rotate each
// vertex's lobe axes by the rotation R_p from its rest frame to its deformed frame, then
// shade with Eq. 13 as before). docs/ldprt.md, "Deforming meshes".
#pragma once

#include <filesystem>
#include <vector>

#include <Eigen/Core>

#include "fit/mesh.h"
#include "shtool/zh_fit_table.h"

namespace shtool::deform {

// The local frame of vertex v: its unit normal n, and a tangent t from the edge to a corner
// of the first triangle that uses v (step 1 or 2 around it), made orthogonal to n
// (Gram-Schmidt); b = n x t. Returns the columns (t, b, n). Throws InputError if the edge
// is parallel to n.
Eigen::Matrix3d vertex_frame(const fit::Mesh& mesh, std::size_t v, int first_triangle, int step);

// R_p = F_posed F_rest^T for every kept vertex (a proper rotation), both frames from the
// same edge: of the two edges of the vertex's first triangle, the one making the larger
// angle with the rest normal (refused below 1e-3 rad). Throws InputError when the meshes
// differ in topology (kept vertices, their file indices, triangles).
std::vector<Eigen::Matrix3d> rest_to_pose_rotations(const fit::Mesh& rest, const fit::Mesh& posed);

// The frame of every vertex of `mesh` (the rest mesh itself, or a pose of it already
// checked by rest_to_pose_rotations), each from the edge that function chooses on `rest`:
// R_p = vertex_frames(rest, posed)[p] vertex_frames(rest, rest)[p]^T. The glossy bake's
// local frames (docs/ldprt.md). Throws InputError as vertex_frame does.
std::vector<Eigen::Matrix3d> vertex_frames(const fit::Mesh& rest, const fit::Mesh& mesh);

// The fit carried to the pose: axes s_i -> R_p s_i; lobe coefficients unchanged (a ZH lobe
// is rotation invariant about its axis); a directly stored linear band rotated as band 1
// (the DC is invariant). Rows must already be in the mesh's kept-vertex order.
ZhFitTable<double> deform_fit(const ZhFitTable<double>& fit, const std::vector<Eigen::Matrix3d>& rotations);

// The fit's rows in the mesh's kept-vertex order (they name their OBJ vertices, or are in
// that order already). Throws InputError, naming `what`, when the fit is not of this mesh.
ZhFitTable<double> fit_for_mesh(ZhFitTable<double> fit, const fit::Mesh& mesh, const std::string& what);

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
