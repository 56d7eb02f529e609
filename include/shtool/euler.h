// 3D rotation representations used by the SH rotations: 3x3 matrix, unit Hamilton
// quaternion (w, x, y, z) and zyz Euler angles R = Rz(alpha) Ry(beta) Rz(gamma).
//
// Rotating an SH function by R means g(w) = f(R^-1 w) (docs/conventions.md).
#pragma once

#include <cmath>
#include <limits>
#include <type_traits>

#include <Eigen/Core>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace shtool {

template <class T>
using Mat3 = Eigen::Matrix<T, 3, 3>;

template <class T>
struct EulerZYZ {
  T alpha = 0, beta = 0, gamma = 0;  // beta in [0, pi]
};

namespace detail {
// matrix_from_quaternion in plain scalar code: the reference of the SSE2 path in float
// (which gives these bits, tested) and the path for double.
template <class T>
inline Mat3<T> matrix_from_quaternion_scalar(T w, T x, T y, T z) {
  // Doubled components first: scaling by 2 is exact, so these are the same values as
  // 1 - 2 (y^2 + z^2), 2 (xy - wz), ... with 12 fewer operations.
  const T x2 = x + x, y2 = y + y, z2 = z + z;
  const T xx = x * x2, yy = y * y2, zz = z * z2;
  const T xy = x * y2, xz = x * z2, yz = y * z2, wx = w * x2, wy = w * y2, wz = w * z2;
  Mat3<T> r;
  r << 1 - (yy + zz), xy - wz, xz + wy,  //
      xy + wz, 1 - (xx + zz), yz - wx,   //
      xz - wy, yz + wx, 1 - (xx + yy);
  return r;
}

#if defined(__SSE2__)
// The lanes of v picked by a shuffle immediate, as floats (pshufd: one instruction,
// without the register copy that shufps of a register with itself needs).
template <int Imm>
inline __m128 lanes(__m128i v) {
  return _mm_castsi128_ps(_mm_shuffle_epi32(v, Imm));
}

inline __m128 sign_mask(bool l0, bool l1, bool l2, bool l3) {
  constexpr int kSign = static_cast<int>(0x80000000u);
  return _mm_castsi128_ps(_mm_setr_epi32(l0 ? kSign : 0, l1 ? kSign : 0, l2 ? kSign : 0, l3 ? kSign : 0));
}

// matrix_from_quaternion_scalar's operations, entry by entry, four entries to a vector:
// R column-major is (R00 R10 R20 R01) (R11 R21 R02 R12) R22, which are also the three
// stores. Lane 0's 1 - (s + t) is taken as 1 + ((-s) - t) and a lane's u + v as
// u - (-v): the same values to the bit, with sign flips (xor) where mixing the sums and
// differences of two vectors would take shuffles, which compete with the products'
// shuffles for the same ports. Operation counts: docs/rotation.md, "Operation counts".
inline Mat3<float> matrix_from_quaternion_sse2(float w, float x, float y, float z) {
  const __m128 q = _mm_setr_ps(w, x, y, z);
  const __m128i qi = _mm_castps_si128(q);
  const __m128i q2 = _mm_castps_si128(_mm_add_ps(q, q));
  // Lanes (w x y z) = (0 1 2 3); _MM_SHUFFLE lists lanes 3..0.
  const __m128 p1 = _mm_mul_ps(lanes<_MM_SHUFFLE(1, 1, 1, 2)>(qi), lanes<_MM_SHUFFLE(2, 3, 2, 2)>(q2));  // yy xy xz xy
  const __m128 p2 = _mm_mul_ps(lanes<_MM_SHUFFLE(0, 0, 0, 3)>(qi), lanes<_MM_SHUFFLE(3, 2, 3, 3)>(q2));  // zz wz wy wz
  const __m128 p3 = _mm_mul_ps(lanes<_MM_SHUFFLE(2, 1, 2, 1)>(qi), lanes<_MM_SHUFFLE(3, 3, 3, 1)>(q2));  // xx yz xz yz
  const __m128 p4 = _mm_mul_ps(lanes<_MM_SHUFFLE(0, 0, 0, 3)>(qi), lanes<_MM_SHUFFLE(1, 2, 1, 3)>(q2));  // zz wx wy wx
  // -0 in lanes 1..3 keeps them as they are (-0 + u = u for every u, zeros included).
  const __m128 k = _mm_setr_ps(1.0f, -0.0f, -0.0f, -0.0f);
  const __m128 lane0 = sign_mask(true, false, false, false);
  // (1 - (yy + zz), xy + wz, xz - wy, xy - wz)
  const __m128 col_a =
      _mm_add_ps(k, _mm_sub_ps(_mm_xor_ps(p1, lane0), _mm_xor_ps(p2, sign_mask(false, true, false, false))));
  // (1 - (xx + zz), yz + wx, xz + wy, yz - wx)
  const __m128 col_b =
      _mm_add_ps(k, _mm_sub_ps(_mm_xor_ps(p3, lane0), _mm_xor_ps(p4, sign_mask(false, true, true, false))));
  const __m128 col_c = _mm_sub_ss(_mm_set_ss(1.0f), _mm_add_ss(p3, p1));  // 1 - (xx + yy)
  Mat3<float> r;
  _mm_storeu_ps(r.data(), col_a);
  _mm_storeu_ps(r.data() + 4, col_b);
  _mm_store_ss(r.data() + 8, col_c);
  return r;
}
#endif
}  // namespace detail

// Rotation matrix of a unit quaternion (w, x, y, z). Precondition: |q| = 1. Inline: it
// is part of every per-object rotation and costs less than a call. In float on x86-64
// it runs in SSE2 lanes, with the scalar code's results bit for bit.
template <class T>
inline Mat3<T> matrix_from_quaternion(T w, T x, T y, T z) {
#if defined(__SSE2__)
  if constexpr (std::is_same_v<T, float>) return detail::matrix_from_quaternion_sse2(w, x, y, z);
#endif
  return detail::matrix_from_quaternion_scalar<T>(w, x, y, z);
}

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
// Inline: it is on the path of every rotation. One square root and two divisions, all
// three independent, and no branch on the hemisphere of the tilt: the divider's latency
// and a mispredicted branch each cost as much as a band of a low-order rotation.
template <class T>
inline ZyzCosSin<T> zyz_cos_sin_from_matrix(const Mat3<T>& r) {
  // R = Rz(a) Ry(b) Rz(g):
  //   (R02, R12) = sin b (cos a, sin a),  (-R20, R21) = sin b (cos g, sin g),  R22 = cos b
  //   (R00 + R11, R10 - R01) = (1 + cos b) (cos(a + g), sin(a + g))
  //   (R11 - R00, -(R10 + R01)) = (1 - cos b) (cos(a - g), sin(a - g))
  // With s = +1 for cos b >= +0 (a + g is well conditioned) and -1 otherwise (a - g), one
  // pair covers both halves: (u, v) = (R11 + s R00, s R10 - R01) = (1 + |cos b|)
  // (cos(a + s g), sin(a + s g)), and g = s ((a + s g) - a). Dividing by 1 + |cos b|, in
  // [1, 2], instead of by |(u, v)| takes R's orthonormality as given (its precondition),
  // as the quaternion route below does.
  ZyzCosSin<T> e;
  e.cb = r(2, 2);
  const T sb2 = r(0, 2) * r(0, 2) + r(1, 2) * r(1, 2);
  e.sb = std::sqrt(sb2);  // not sqrt(1 - cb^2): exact near b = 0
  const T s = std::copysign(T(1), e.cb);  // a sign-bit copy: no branch to mispredict
  const T u = r(1, 1) + s * r(0, 0), v = s * r(1, 0) - r(0, 1);
  const T norm = 1 + s * e.cb;
  if (sb2 >= std::numeric_limits<T>::min()) {
    // 1 / sin b = sin b / sin^2 b: the division runs beside the square root instead of
    // after it (their latencies dominate a low-order set()).
    const T inv_sb = e.sb * (1 / sb2), inv_g = inv_sb * (1 / norm);
    e.ca = r(0, 2) * inv_sb;
    e.sa = r(1, 2) * inv_sb;
    e.cg = (u * r(0, 2) + v * r(1, 2)) * inv_g;
    e.sg = s * ((v * r(0, 2) - u * r(1, 2)) * inv_g);
  } else {  // gimbal lock (tilt below 1e-19 in float): a = 0, g = a + s g
    const T inv_g = 1 / norm;
    e.cg = u * inv_g;
    e.sg = s * (v * inv_g);
  }
  return e;
}


// The same cosines and sines straight from a unit quaternion (w, x, y, z), with one
// square root and one division where the matrix route needs two and four. For
// R = Rz(a) Ry(b) Rz(g) the Hamilton product of the half-angle quaternions gives
//   (w, z) = cos(b/2) (cos P, sin P),  (y, -x) = sin(b/2) (cos Q, sin Q),
// P = (a + g) / 2, Q = (a - g) / 2 (-q gives P + pi, Q + pi: the same a mod 2 pi and g),
// so a = P + Q, g = P - Q and, with r1 = |(w, z)|, r2 = |(x, y)|:
//   (cos a, sin a) = (w y + z x, z y - w x) / (r1 r2),  (cos g, sin g) = (w y - z x, z y + w x) / (r1 r2)
//   cos b = r1^2 - r2^2,  sin b = 2 r1 r2.
// At a gimbal lock one of r1, r2 vanishes and only a + g (b = 0) or a - g (b = pi) is
// defined: then g = 0. Below a tilt of about 2 eps^1.5 (8e-11 in float, 3e-24 in double)
// the tilt is taken as 0, which changes nothing at T's precision and keeps (r1 r2)^2
// far from underflow.
template <class T>
inline ZyzCosSin<T> zyz_cos_sin_from_quaternion(T w, T x, T y, T z) {
  constexpr T kTiny = std::numeric_limits<T>::epsilon() * std::numeric_limits<T>::epsilon() *
                      std::numeric_limits<T>::epsilon();
  const T wz = w * w + z * z, xy = x * x + y * y;
  ZyzCosSin<T> e;
  e.cb = wz - xy;
  if (xy < kTiny) {  // b = 0: a = 2P
    const T inv = 1 / wz;
    e.cb = 1;
    e.ca = (w * w - z * z) * inv;
    e.sa = 2 * w * z * inv;
    return e;
  }
  if (wz < kTiny) {  // b = pi: a = 2Q
    const T inv = 1 / xy;
    e.cb = -1;
    e.ca = (y * y - x * x) * inv;
    e.sa = -2 * x * y * inv;
    return e;
  }
  const T r = std::sqrt(wz * xy);  // r1 r2
  const T inv = 1 / r;
  e.sb = r + r;
  e.ca = (w * y + z * x) * inv;
  e.sa = (z * y - w * x) * inv;
  e.cg = (w * y - z * x) * inv;
  e.sg = (z * y + w * x) * inv;
  return e;
}

// Largest entry of |R^T R - I| and the determinant, for validating user input.
template <class T>
T orthonormality_defect(const Mat3<T>& r);

}  // namespace shtool
