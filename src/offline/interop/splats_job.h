// shtool transform-splats: converts a 3D Gaussian Splatting scene between PLY, spz and
// glTF (KHR_gaussian_splatting), optionally under a similarity transform given in the
// input file's coordinates (docs/interop.md, docs/splats.md). Positions p -> s R p + t;
// orientations q -> q_R q (Hamilton product, unit q_R; the stored quaternion keeps its
// length, which 3DGS normalises on load); log-scales + log s; normals R n; and the
// view-dependent colour's SH of every splat rotated, g(w) = f(R^-1 w), so that a splat
// seen along d before looks the same along R d after. Between formats the frames change
// too (each format's frame, through shtool's). A map that reflects (a --matrix of det -1,
// a frame change between right- and left-handed axes) turns the orientation by its proper
// part and the SH by the orthogonal map.
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "interop/splat_scene.h"

namespace shtool::interop {

struct TransformSplatsRequest {
  std::filesystem::path in, out;
  std::optional<std::array<double, 4>> quaternion;  // w, x, y, z
  std::optional<std::array<double, 9>> matrix;      // row-major, orthogonal (det +1 or -1)
  std::array<double, 3> translate{0, 0, 0};
  double scale = 1;
  std::string ply_frame = "RDF";  // the axes of PLY files (COLMAP's, 3DGS's)
  std::string spz_frame = "RUB";  // of spz files (the specification's) that do not record theirs
  std::string gltf_frame = "RUB"; // of glTF files (+Y up, the asset's front +Z toward the viewer)
  std::optional<int> sh_degree;   // the output's SH degree, 0..3
  int spz_version = 4;
  std::array<int, 2> sh_bits{5, 4};  // spz: band 1, bands 2..3
  int threads = 0;
};

struct TransformSplatsReport {
  std::size_t splats = 0;
  int degree = 0;      // the output's
  int degree_in = -1;  // the input's when it was decoded into a scene
  bool reflects = false;
  int threads = 1;
  double seconds = 0;
  // spz output: the colour error bounds of its quantisation (one channel, any
  // direction): the SH bands' from the bucket sizes and for this scene's coefficients,
  // the DC's from the byte step and for this scene's (clipping included).
  double spz_sh_bound = 0, spz_sh_scene = 0, spz_dc_bound = 0, spz_dc_scene = 0;
  // What the job did that the user may not expect, one line each (the CLI prints them as
  // warnings): extension records skipped, a frame taken from the file.
  std::vector<std::string> warnings;
};

// The orthogonal map of a request: the unit quaternion's rotation (normalised; zero
// refused), the matrix (orthonormal to 1e-6; det -1, a reflection, allowed), or the
// identity when neither is given.
Eigen::Matrix3d splat_rotation(const TransformSplatsRequest& request);

// A frame by letters, one per file axis (x, y, z): R/L, U/D, F/B (right, up, forward
// away from the viewer, and their opposites). Returns Q with shtool = Q * file
// (shtool's frame is RFU). InputError on anything else.
Eigen::Matrix3d splat_frame(std::string_view letters);

TransformSplatsReport run_transform_splats(const TransformSplatsRequest& request);

}  // namespace shtool::interop
