// 3D rotation representations used by the SH rotations: 3x3 matrix, unit Hamilton
// quaternion (w, x, y, z) and zyz Euler angles R = Rz(alpha) Ry(beta) Rz(gamma).
//
// Rotating an SH function by R means g(w) = f(R^-1 w) (docs/conventions.md).
#pragma once

#include <Eigen/Core>

namespace shtool {

template <class T>
using Mat3 = Eigen::Matrix<T, 3, 3>;

template <class T>
struct EulerZYZ {
  T alpha = 0, beta = 0, gamma = 0;  // beta in [0, pi]
};

// Rotation matrix of a unit quaternion (w, x, y, z). Precondition: |q| = 1.
template <class T>
Mat3<T> matrix_from_quaternion(T w, T x, T y, T z);

// Rz(alpha) Ry(beta) Rz(gamma).
template <class T>
Mat3<T> matrix_from_zyz(const EulerZYZ<T>& e);

// Decomposition of a rotation matrix into zyz angles, accurate at every angle: beta by
// atan2 (not acos, which loses half the digits near the identity), and at the gimbal
// locks beta = 0 and beta = pi the well-determined combination (alpha + gamma or
// alpha - gamma) is taken from the matrix directly, so the recomposed matrix matches R
// to rounding for every input.
template <class T>
EulerZYZ<T> zyz_from_matrix(const Mat3<T>& r);

// The same decomposition as cosines and sines, without any trigonometric call (what
// the rotations need: the z-rotations use cos(m a), sin(m a) from a recurrence).
// cos/sin of alpha come from (R02, R12) / sin(beta); those of gamma from the
// well-conditioned alpha +- gamma combination composed with alpha, so alpha + gamma
// (beta near 0) or alpha - gamma (beta near pi) is exact even where alpha alone is not.
template <class T>
struct ZyzCosSin {
  T ca = 1, sa = 0, cb = 1, sb = 0, cg = 1, sg = 0;
};
template <class T>
ZyzCosSin<T> zyz_cos_sin_from_matrix(const Mat3<T>& r);

// Largest entry of |R^T R - I| and the determinant, for validating user input.
template <class T>
T orthonormality_defect(const Mat3<T>& r);

}  // namespace shtool
