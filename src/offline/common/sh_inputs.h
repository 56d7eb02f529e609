// The inputs of the runtime commands (rotate --in, product --in, rotations), parsed and
// checked in the library so that tests, fuzz targets and the Python module reach the
// same code as the command line.
// Every function throws InputError naming the input and the problem.
#pragma once

#include <array>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Geometry>

#include "shtool/euler.h"
#include "shtool/product.h"
#include "shtool/sh.h"

namespace shtool {

// How far from unit length / orthonormal a user's rotation may be before it is refused
// rather than silently renormalised: a few float epsilons, so rotations printed with 7
// significant digits are accepted.
inline constexpr double kRotationInputTolerance = 1e-6;

// Whether r is a rotation for a user's input: orthonormal to kRotationInputTolerance
// (max |R^T R - I|) and det +1 (a reflection is no rotation of SH). Inline and without
// messages, in the matrix's own precision (float: its rounding, 1e-7, is well inside the
// tolerance): the Python module checks a matrix per splat. Branch-free until the end so
// that the compiler keeps it in vector registers.
template <class T>
inline bool is_rotation_matrix(const Mat3<T>& r) {
  const Mat3<T> defect = r.transpose() * r - Mat3<T>::Identity();
  return (defect.array().abs() <= T(kRotationInputTolerance)).all() && r.col(0).dot(r.col(1).cross(r.col(2))) > 0;
}

// r if is_rotation_matrix(r), else InputError naming `what` and the problem.
Mat3<double> checked_rotation_matrix(const Mat3<double>& r, const std::string& what);

// A user's quaternion (w, x, y, z), unit to kRotationInputTolerance, as a rotation
// matrix (normalised first). InputError naming `what` otherwise.
Mat3<double> checked_quaternion_matrix(const std::array<double, 4>& q, const std::string& what);

// A user's direction scaled to unit length: by its largest component first, so that tiny
// or huge (but valid) directions neither underflow nor overflow in the norm. False for
// a zero or non-finite vector.
template <class T>
bool normalize_direction(Vec3<T>& w) {
  // allFinite first: maxCoeff skips a NaN that is not the first component.
  if (!w.allFinite()) return false;
  const T largest = w.cwiseAbs().maxCoeff();
  if (!(largest > T(0))) return false;
  w /= largest;
  w /= w.norm();
  return true;
}

// "auto", "tripling", "fourier", "grid" (product --method); empty for any other name.
std::optional<ProductMethod> product_method_from_name(std::string_view name);

// {"coefficients": [numbers]} (rotate --in); `where` names the input.
std::vector<double> parse_coefficients_json(std::string_view text, const std::string& where);

// {"inputs": [[N^2 numbers], ...]} with min_inputs..max_inputs finite vectors of order N
// (product --in).
std::vector<std::vector<double>> parse_product_inputs(std::string_view text, const std::string& where, int order,
                                                      int min_inputs, int max_inputs);

}  // namespace shtool
