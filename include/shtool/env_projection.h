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
// 1e-12 of its solid angle for the orders accepted. Every face is the same square seen
// through a signed permutation of axes, and the square is symmetric under the eight
// maps (s, t) -> (+-s, +-t), (+-t, +-s): the rule runs once per class of eight texels,
// in a frame with the face normal as polar axis where those maps only permute and negate
// the pairs (cos m p, sin m p). The antipodal map carries each face onto the opposite
// one and multiplies y_lm by (-1)^l: the 48 texels of a class (8 per face) are added
// (even bands) and subtracted (odd bands) across opposite faces and folded into eight
// sums per face pair, band parity and channel, and the coefficients of +X, +Y and +Z are
// carried to shtool's frame by the orthogonal maps of their axes (docs/lighting.md).
// project_cubemap_reference runs the rule on every texel in shtool's frame instead (the
// same integrals, another rounding).
//
// Both accumulate in double, in a fixed order of fixed blocks of rows: the result does
// not depend on how the blocks are shared among threads (Projector::block_count and
// accumulate_block let a caller run them in parallel; project_* runs them in order).
// Allocation happens when a projector is made, never per texel. Non-finite texels are
// reported by position.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "shtool/lighting.h"
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
  // Blocks of texel classes: each is a band of kRowsPerBand rows of the face's eighth
  // s >= t >= 0 with the texels of its classes on all six faces. Rows near the face's
  // centre are long, near its edge short: the blocks take the bands from both ends in
  // turn, so that any contiguous run of blocks holds about its share of the work.
  int block_count() const;
  std::size_t partial_size(int channels) const;
  // faces[f] is face f (CubeFace order), each face_size square with the same channels.
  // A block with a non-finite texel reports the first one of the whole cubemap (face,
  // then row, then column), so that the message does not depend on the block.
  Result<Ok> accumulate_block(std::span<const FloatImageView, 6> faces, int block, std::span<double> partial) const;

  // Unit direction (shtool's frame) at face coordinates (s, t).
  Eigen::Vector3d direction(CubeFace face, double s, double t) const;
  // The integrals of every y_i over texel (x, y) of `face`, in shtool's frame: out[i],
  // i < N^2 (the reference rule, one texel at a time).
  void texel_integrals(CubeFace face, int x, int y, std::span<double> out) const;

  static constexpr int kRowsPerBand = 16;

 private:
  Eigen::Vector3d cube_vector(CubeFace face, double s, double t) const;

  int size_ = 0, order_ = 0, nodes_ = 0;
  bool mirror_x_ = false;
  std::vector<double> nodes_unit_;    // Gauss nodes on [-1, 1]
  std::vector<double> weights_unit_;  // their weights
  // For +X, +Y, +Z, the orthogonal map of SH coefficients from the face's frame (s, t, 1)
  // to shtool's, band blocks (2l+1)^2 row-major, bands in order.
  std::vector<double> face_maps_;
  // For the pairs (+X, -X), (+Y, -Y), (+Z, -Z): the antipode of image g of a class of
  // texels on the first face is image antipode_[pair][g] of that class on the second
  // (the images as accumulate_block orders them).
  int antipode_[3][8] = {};
};

Result<EnvCoefficients> project_cubemap(std::span<const FloatImageView, 6> faces, int order, bool mirror_x = false);
// The same projection texel by texel: every texel's own rule in shtool's frame
// (texel_integrals), face by face. Slow; the fast path is tested against it.
Result<EnvCoefficients> project_cubemap_reference(std::span<const FloatImageView, 6> faces, int order,
                                                  bool mirror_x = false);

// Gauss-Legendre nodes per texel side for a face of `face_size` texels at `order`: the
// fewest whose error bound on one texel is below 1e-13 of its solid angle.
int cubemap_nodes_per_side(int face_size, int order);

}  // namespace shtool
