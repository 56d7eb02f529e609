// Orthogonal maps of SH coefficients: rotations and reflections of the sphere, for frame
// changes at the boundaries (image mappings, engine frames; docs/conventions.md) and for
// scenes moved by a reflecting matrix (Gaussian splats, docs/splats.md).
//
// For an orthogonal Q (det +1 or -1) and the coefficients of f, the coefficients of
// g(w) = f(Q^-1 w): the function carried along by Q, as ShRotation does for rotations
// (a lobe along d ends up along Q d). A reflection is -1 times a rotation, and the
// inversion w -> -w multiplies band l by (-1)^l: so Q = -P gives the rotation by P of the
// coefficients with the odd bands negated. Uses the reference (Ivanic-Ruedenberg)
// rotation: exact to rounding at every angle, no tables.
#pragma once

#include <array>
#include <span>

#include <Eigen/Core>

#include "shtool/result.h"
#include "shtool/rotation.h"

namespace shtool {

// One map prepared for many coefficient vectors of one order N (every splat of a scene):
// apply_orthogonal_map's arithmetic without its set-up each time.
class OrthogonalMap {
 public:
  // An error if Q is not orthogonal to `tolerance` or N is not a supported order.
  static Result<OrthogonalMap> make(const Eigen::Matrix3d& q, int order, double tolerance = 1e-9);

  int order() const { return rotation_.order(); }
  bool reflects() const { return reflects_; }
  // P = det(Q) Q, the rotation whose map this is up to the inversion's signs.
  const Eigen::Matrix3d& proper() const { return proper_; }

  // out = the coefficients of g from those of f, N^2 each; in and out must not overlap.
  void apply(std::span<const double> in, std::span<double> out) const;
  // Several channels interleaved (coefficient i of channel c at i * channels + c, N^2 *
  // channels values each; ShRotation::apply(in, out, channels)), bit-identical to apply()
  // of each channel. Returns false and writes nothing if the sizes are not that.
  bool apply(std::span<const double> in, std::span<double> out, int channels) const;

 private:
  OrthogonalMap(const Eigen::Matrix3d& proper, bool reflects, int order);
  void invert_odd_bands(std::span<double> out, int channels = 1) const;

  Eigen::Matrix3d proper_;
  bool reflects_;
  ShRotation<double> rotation_;
};

// In place: coefficients[i * channels + c], N^2 = coefficients.size() / channels, float
// or double (the map is computed in double either way). An error if Q is not orthogonal
// to 1e-9 (float: 1e-6).
Result<Ok> apply_orthogonal_map(const Eigen::Matrix3d& q, int channels, std::span<double> coefficients);
Result<Ok> apply_orthogonal_map(const Eigen::Matrix3f& q, int channels, std::span<float> coefficients);

}  // namespace shtool
