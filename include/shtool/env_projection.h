// Projection of an environment image onto SH: the exact integral of each y_i over each
// texel, the image being constant over the texel (docs/lighting.md).
//
// Equirect (2:1, rows top first): texel (x, y) of W x H covers polar t in
// [pi y / H, pi (y+1) / H] and azimuth p in [pi - 2 pi (x+1) / W, pi - 2 pi x / W] (row 0
// at +z, the image centre facing +x, the azimuth growing to the left). The integral is
// separable: per column a closed form in p, per row a closed form in t (K_l^m P_l^m(cos t)
// sin t is a trigonometric polynomial of degree l+1, integrated term by term), so a
// projection costs O(W H N) for the azimuthal sums plus O(H N^3) for the rows.
//
// Cubemaps: six R x R faces in the order +X -X +Y -Y +Z -Z of the y-up cube frame, with
// (s, t) in [-1, 1] at texel centres (s right, t down): +X (1, -t, -s), -X (-1, -t, s),
// +Y (s, 1, t), -Y (s, -1, -t), +Z (s, -t, 1), -Z (-s, -t, -1) (the OpenGL / Direct3D
// table). A cube direction (X, Y, Z) is shtool's w = (X, -Z, Y) (the y-up engine frame,
// engine = (x, z, -y)); `mirror_x` negates X first. Each texel is integrated by a
// Gauss-Legendre product rule in (s, t) of the solid-angle element
// ds dt / (1 + s^2 + t^2)^(3/2), with enough nodes that a texel's integral is within
// 1e-12 of its solid angle for the orders accepted.
//
// Both accumulate in double, in a fixed order of fixed blocks of rows: the result does
// not depend on how the blocks are shared among threads (Projector::block_count and
// accumulate_block let a caller run them in parallel; project_* runs them in order).
// Allocation happens when a projector is made, never per texel. Non-finite texels are
// reported by position.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "shtool/result.h"

namespace shtool {

// Highest order the projections accept.
inline constexpr int kMaxEnvOrder = 32;

// A float image in memory: `channels` interleaved values per texel, rows top first,
// `row_stride` floats from one row's start to the next (0: width * channels).
struct FloatImageView {
  const float* texels = nullptr;
  int width = 0;
  int height = 0;
  int channels = 0;
  std::size_t row_stride = 0;

  std::size_t stride() const { return row_stride ? row_stride : static_cast<std::size_t>(width) * channels; }
  const float* row(int y) const { return texels + static_cast<std::size_t>(y) * stride(); }
};

enum class CubeFace { px, nx, py, ny, pz, nz };

// Coefficients of a projection: coefficients[i * channels + c] for SH index i < N^2.
struct EnvCoefficients {
  int order = 0;
  int channels = 0;
  std::vector<double> coefficients;
};

// Exact equirect projection. Precomputes the column weights and the row integrals for
// one image size and order.
class EquirectProjector {
 public:
  static Result<EquirectProjector> create(int width, int height, int order);

  int order() const { return order_; }
  int width() const { return width_; }
  int height() const { return height_; }
  int block_count() const { return (height_ + kRowsPerBlock - 1) / kRowsPerBlock; }
  // Number of doubles accumulate_block writes: N^2 * channels.
  std::size_t partial_size(int channels) const;
  // Adds the integrals of block b's rows into partial (zeroed by the caller), or reports
  // the first non-finite texel of the block. image must have this projector's size.
  Result<Ok> accumulate_block(const FloatImageView& image, int block, std::span<double> partial) const;

  // Row integrals T_l^m(y) = integral over row y of K_l^m P_l^m(cos t) sin t dt, index
  // l (l+1) / 2 + m (m >= 0); exposed for the tests.
  std::span<const double> row_integrals(int y) const;

  static constexpr int kRowsPerBlock = 8;

 private:
  int width_ = 0, height_ = 0, order_ = 0;
  // column_weights_[k * W/2 + x] for the left half of the columns (x < W/2; column
  // W-1-x mirrors x): k = 0: the column's width in p; k = 2m-1: the integral of
  // sqrt2 cos(m p); k = 2m: of sqrt2 sin(m p), m = 1..N-1.
  std::vector<double> column_weights_;
  std::vector<double> row_integrals_;  // H x N (N+1) / 2
};

// Projects a whole equirect image (width = 2 height) in block order.
Result<EnvCoefficients> project_equirect(const FloatImageView& image, int order);

// Exact cubemap projection for one face size and order.
class CubemapProjector {
 public:
  static Result<CubemapProjector> create(int face_size, int order, bool mirror_x = false);

  int order() const { return order_; }
  int face_size() const { return size_; }
  // Gauss-Legendre nodes per texel side.
  int nodes_per_side() const { return nodes_; }
  // Blocks of rows of all six faces, face-major.
  int block_count() const;
  std::size_t partial_size(int channels) const;
  // faces[f] is face f (CubeFace order), each face_size square with the same channels.
  Result<Ok> accumulate_block(std::span<const FloatImageView, 6> faces, int block, std::span<double> partial) const;

  // Unit direction (shtool's frame) at face coordinates (s, t).
  Eigen::Vector3d direction(CubeFace face, double s, double t) const;
  // The integrals of every y_i over texel (x, y) of `face`: out[i], i < N^2.
  void texel_integrals(CubeFace face, int x, int y, std::span<double> out) const;

  static constexpr int kRowsPerBlock = 4;

 private:
  int size_ = 0, order_ = 0, nodes_ = 0;
  bool mirror_x_ = false;
  std::vector<double> nodes_unit_;    // Gauss nodes on [-1, 1]
  std::vector<double> weights_unit_;  // their weights
};

Result<EnvCoefficients> project_cubemap(std::span<const FloatImageView, 6> faces, int order, bool mirror_x = false);

// Gauss-Legendre nodes per texel side for a face of `face_size` texels at `order`: the
// fewest whose error bound on one texel is below 1e-13 of its solid angle.
int cubemap_nodes_per_side(int face_size, int order);

}  // namespace shtool
