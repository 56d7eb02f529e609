// Real spherical harmonics: indexing, evaluation, gradients and reconstruction.
//
// Conventions (sign, index, normalisation, direction) are fixed in
// docs/conventions.md; this header only restates the index rule:
//   flat index i = l (l + 1) + m,  "order N" = bands 0..N-1 = N^2 coefficients.
//
// All functions here are allocation-free and exception-free. Directions must be
// unit vectors (precondition; not checked in the hot path). float and double are
// both supported; the recurrence coefficients are computed once in double.
#pragma once

#include <cstddef>
#include <span>

#include <Eigen/Core>

namespace shtool {

template <class T>
using Vec3 = Eigen::Matrix<T, 3, 1>;

// Highest order (number of bands) the evaluators accept. The recurrence is stable
// far beyond this; the limit only bounds the size of the coefficient table.
inline constexpr int kMaxOrder = 128;

constexpr int sh_index(int l, int m) { return l * (l + 1) + m; }
constexpr int sh_count(int order) { return order * order; }
// Band l of flat index i (inverse of sh_index).
int sh_band(int index);

bool is_supported_order(int order);

// All N^2 values y_i(w) for i = 0..N^2-1. out.size() must be >= N^2.
template <class T>
void eval_sh(int order, const Vec3<T>& w, std::span<T> out);

// Many directions: dirs holds `count` unit vectors as x,y,z triples; out holds
// count * N^2 values, direction-major (the N^2 values of direction k are contiguous).
template <class T>
void eval_sh_batch(int order, std::span<const T> dirs, std::span<T> out);

// Values and surface gradients: grad[3 i + c] is component c of the gradient of y_i
// on the unit sphere at w (tangent to the sphere, so grad_i . w = 0).
// values.size() >= N^2, grad.size() >= 3 N^2.
template <class T>
void eval_sh_with_gradient(int order, const Vec3<T>& w, std::span<T> values, std::span<T> grad);

// Band-limited reconstruction f(w) = sum_i coeffs[i] y_i(w), with N^2 = coeffs.size()
// (coeffs.size() must be a perfect square). Evaluates the basis on the fly.
template <class T>
T reconstruct(std::span<const T> coeffs, const Vec3<T>& w);

// Direction from polar angle t in [0, pi] and azimuth p:
// w = (sin t cos p, sin t sin p, cos t).
template <class T>
Vec3<T> direction_from_angles(T theta, T phi);

}  // namespace shtool
