// Glossy transfer per vertex ([4] Sec. 3.2): the transfer matrix T from source lighting
// (SH in the scene frame) to the transferred incident radiance at the vertex (SH in its
// local frame), and the BRDF-specialised matrix M' = Sigma~ V~ T of Eq. 15.
//
//   T_jk = integral over S^2 of y_j(F^T s) V'(s) y_k(s) ds,
//
// F the vertex frame (columns tangent, bitangent, normal), V' the visibility of the
// distant lighting from the vertex above its tangent plane and 1 below it. B integrates
// over the upper hemisphere only (Eq. 14), so what lies below never reaches the eye
// except through the order-n truncation of the incident radiance; leaving it unoccluded
// makes T the SH rotation into the local frame wherever nothing is in the way, so a convex
// or flat surface is shaded exactly as B applied to the lighting seen from its frame, with
// no ringing from a step at the horizon. The occluded part is
// estimated from uniformly distributed hemisphere rays (spherical Fibonacci in the vertex
// frame, turned and shifted by a hash of (seed, vertex) as the diffuse rays are):
//
//   T = D(F) - (2 pi / rays) sum over blocked rays k of y(F^T s_k) y(s_k)^T,
//
// D(F) the SH rotation matrix with y(F^T s) = D(F) y(s).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "fit/embree_scene.h"
#include "fit/mesh.h"

namespace shtool::glossy {

struct GlossyTransferOptions {
  int order = 4;
  int rays = 1024;
  std::uint64_t seed = 1;
  bool shadowed = true;  // false: T = D(F) (unshadowed; no rays)
  int threads = 0;
  double offset_scale = 1e-4;  // ray origins move off the surface by this x bounding-box diagonal
};

struct GlossyTransfer {
  // M' per vertex: rows[(v * n_b + j) * order^2 + k], the input fit-zh's fit takes.
  std::vector<double> rows;
  // Sum over vertices of ||B T||_F^2 and of ||M'||_F^2. With U~'s orthonormal columns the
  // SVD's error is ||B T - U~ M'||^2 = ||B T||^2 - ||M'||^2 (Eq. 15).
  double exit_norm2 = 0, rows_norm2 = 0;
};

// T for vertex v: n^2 x n^2, row j local, column k scene. `frame` is the vertex's frame;
// `offset` how far ray origins move along the normal; scene null: unshadowed (T = D(F)).
Eigen::MatrixXd transfer_matrix(const fit::Mesh& mesh, std::size_t v, const Eigen::Matrix3d& frame,
                                const GlossyTransferOptions& options, double offset, const fit::EmbreeScene* scene);

// M' = factors_rows * T for every vertex, with the norms above. `frames` one per vertex;
// `brdf_gram` = B^T B. Bytes do not depend on the thread count.
GlossyTransfer glossy_transfer(const fit::Mesh& mesh, const std::vector<Eigen::Matrix3d>& frames,
                               const Eigen::MatrixXd& factors_rows, const Eigen::MatrixXd& brdf_gram,
                               const GlossyTransferOptions& options);

}  // namespace shtool::glossy
