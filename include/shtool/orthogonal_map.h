// Orthogonal maps of SH coefficients: rotations and reflections of the sphere, for frame
// changes at the boundaries (image mappings, engine frames; docs/conventions.md).
//
// For an orthogonal Q (det +1 or -1) and the coefficients of f, the coefficients of
// g(w) = f(Q^-1 w): the function carried along by Q, as ShRotation does for rotations
// (a lobe along d ends up along Q d). A reflection is -1 times a rotation, and the
// inversion w -> -w multiplies band l by (-1)^l: so Q = -P gives the rotation by P of the
// coefficients with the odd bands negated. Uses the reference (Ivanic-Ruedenberg)
// rotation: exact to rounding at every angle, no tables.
#pragma once

#include <span>

#include <Eigen/Core>

#include "shtool/result.h"

namespace shtool {

// In place: coefficients[i * channels + c], N^2 = coefficients.size() / channels, float
// or double (the map is computed in double either way). An error if Q is not orthogonal
// to 1e-9 (float: 1e-6).
Result<Ok> apply_orthogonal_map(const Eigen::Matrix3d& q, int channels, std::span<double> coefficients);
Result<Ok> apply_orthogonal_map(const Eigen::Matrix3f& q, int channels, std::span<float> coefficients);

}  // namespace shtool
