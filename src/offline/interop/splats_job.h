// shtool transform-splats: a similarity transform of a 3D Gaussian Splatting scene
// (docs/interop.md). Positions p -> s R p + t; orientations q -> q_R q (Hamilton
// product, unit q_R; the stored quaternion keeps its length, which 3DGS normalises on
// load); log-scales + log s; normals R n; and the view-dependent colour's SH of every
// splat rotated, g(w) = f(R^-1 w), so that a splat seen along d before looks the same
// along R d after.
#pragma once

#include <array>
#include <filesystem>
#include <optional>

#include <Eigen/Core>

namespace shtool::interop {

struct TransformSplatsRequest {
  std::filesystem::path in, out;
  std::optional<std::array<double, 4>> quaternion;  // w, x, y, z
  std::optional<std::array<double, 9>> matrix;      // row-major
  std::array<double, 3> translate{0, 0, 0};
  double scale = 1;
  int threads = 0;
};

struct TransformSplatsReport {
  std::size_t splats = 0;
  int degree = 0;
  int threads = 1;
  double seconds = 0;
};

// The rotation of a request: the unit quaternion (normalised; zero refused) or the
// matrix (orthonormal to 1e-6, det +1; a reflection is refused: its SH transform is no
// rotation and 3DGS orientations cannot hold it).
Eigen::Matrix3d splat_rotation(const TransformSplatsRequest& request);

TransformSplatsReport run_transform_splats(const TransformSplatsRequest& request);

}  // namespace shtool::interop
