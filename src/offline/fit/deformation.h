// Meshes that move: the local frame of every vertex, the rotation that carries each from
// a rest mesh to a pose of it, and a ZH fit carried along ([4] Sec. 6 and "LDPRT
// rendering": rotate each vertex's lobe axes by the rotation R_p from its rest frame to
// its deformed frame, then shade with Eq. 13 as before). docs/ldprt.md, "Deforming
// meshes". Used by deform, render and the glossy bake.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fit/mesh.h"
#include "shtool/zh_fit_table.h"

namespace shtool {
class JobOutputs;
}

namespace shtool::fit {

// The local frame of vertex v: its unit normal n, and a tangent t from the edge to a corner
// of the first triangle that uses v (step 1 or 2 around it), made orthogonal to n
// (Gram-Schmidt); b = n x t. Returns the columns (t, b, n). Throws InputError if the edge
// is parallel to n.
Eigen::Matrix3d vertex_frame(const Mesh& mesh, std::size_t v, int first_triangle, int step);

// R_p = F_posed F_rest^T for every kept vertex (a proper rotation), both frames from the
// same edge: of the two edges of the vertex's first triangle, the one making the larger
// angle with the rest normal (refused below 1e-3 rad). Throws InputError when the meshes
// differ in topology (kept vertices, their file indices, triangles).
std::vector<Eigen::Matrix3d> rest_to_pose_rotations(const Mesh& rest, const Mesh& posed);

// The frame of every vertex of `mesh` (the rest mesh itself, or a pose of it already
// checked by rest_to_pose_rotations), each from the edge that function chooses on `rest`:
// R_p = vertex_frames(rest, posed)[p] vertex_frames(rest, rest)[p]^T. The glossy bake's
// local frames (docs/ldprt.md). Throws InputError as vertex_frame does.
std::vector<Eigen::Matrix3d> vertex_frames(const Mesh& rest, const Mesh& mesh);

// A mesh and, with a --pose mesh, that pose of it and the rotations from the one to the
// other: what render and export-web draw.
struct PosedMesh {
  Mesh rest;
  std::optional<Mesh> posed;               // none without --pose
  std::vector<Eigen::Matrix3d> rotations;  // rest frame -> posed frame, per vertex (--pose)
  // The surface drawn: the pose when there is one.
  const Mesh& shown() const { return posed ? *posed : rest; }
};

// Reads `mesh` and, unless `pose` is empty, `pose`, both with `normals` (the bake's:
// recorded_normals; a pose of a `file` bake with automatic ones) and OBJ up axis `up`, declaring their files inputs of
// `io` ("a file of the mesh", "a file of the --pose mesh"). Where one of the two has normals of its own and the other
// not, the rotations come from computed normals on both: a pose written without normals (scripts/pose_mesh.py --bend)
// would otherwise turn every frame by the gap between the file's normals and computed ones. Throws InputError as
// load_mesh and rest_to_pose_rotations do.
PosedMesh load_posed_mesh(JobOutputs& io, const std::filesystem::path& mesh, const std::filesystem::path& pose,
                          UpAxis up, NormalSource normals);

// The fit carried to the pose: axes s_i -> R_p s_i; lobe coefficients unchanged (a ZH lobe
// is rotation invariant about its axis); a directly stored linear band rotated as band 1
// (the DC is invariant). Rows must already be in the mesh's kept-vertex order.
ZhFitTable<double> deform_fit(const ZhFitTable<double>& fit, const std::vector<Eigen::Matrix3d>& rotations);

// The fit's rows in the mesh's kept-vertex order (they name their OBJ vertices, or are in
// that order already). Throws InputError, naming `what`, when the fit is not of this mesh.
ZhFitTable<double> fit_for_mesh(ZhFitTable<double> fit, const Mesh& mesh, const std::string& what);

}  // namespace shtool::fit
