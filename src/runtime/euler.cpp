#include "shtool/euler.h"

#include <cmath>
#include <numbers>

#include <Eigen/Dense>

namespace shtool {

template <class T>
Mat3<T> matrix_from_quaternion(T w, T x, T y, T z) {
  Mat3<T> r;
  r << 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),  //
      2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),   //
      2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y);
  return r;
}

template <class T>
Mat3<T> matrix_from_zyz(const EulerZYZ<T>& e) {
  const T ca = std::cos(e.alpha), sa = std::sin(e.alpha);
  const T cb = std::cos(e.beta), sb = std::sin(e.beta);
  const T cg = std::cos(e.gamma), sg = std::sin(e.gamma);
  Mat3<T> r;
  r << ca * cb * cg - sa * sg, -ca * cb * sg - sa * cg, ca * sb,  //
      sa * cb * cg + ca * sg, -sa * cb * sg + ca * cg, sa * sb,   //
      -sb * cg, sb * sg, cb;
  return r;
}

template <class T>
EulerZYZ<T> zyz_from_matrix(const Mat3<T>& r) {
  constexpr T pi = std::numbers::pi_v<T>;
  EulerZYZ<T> e;
  e.beta = std::atan2(std::hypot(r(0, 2), r(1, 2)), r(2, 2));
  // Individual angles: exact up to rounding divided by sin(beta).
  const bool has_sin = r(0, 2) != 0 || r(1, 2) != 0 || r(2, 0) != 0 || r(2, 1) != 0;
  const T a1 = has_sin ? std::atan2(r(1, 2), r(0, 2)) : T(0);
  const T g1 = has_sin ? std::atan2(r(2, 1), -r(2, 0)) : T(0);
  // R00 + R11 = (1 + cos b) cos(a + g),  R10 - R01 = (1 + cos b) sin(a + g)
  // R11 - R00 = (1 - cos b) cos(a - g),  R10 + R01 = (cos b - 1) sin(a - g)
  // One of the two combinations is well conditioned at any beta; the other is only
  // multiplied by sin(beta) in R, so its error does not matter. The well-conditioned
  // one is moved by 2 pi to lie next to the raw value, which fixes the branch.
  auto nearest = [pi](T value, T target) {
    return value + 2 * pi * std::round((target - value) / (2 * pi));
  };
  T sum = a1 + g1, diff = a1 - g1;
  if (r(2, 2) >= 0)
    sum = nearest(std::atan2(r(1, 0) - r(0, 1), r(0, 0) + r(1, 1)), sum);
  else
    diff = nearest(std::atan2(-(r(1, 0) + r(0, 1)), r(1, 1) - r(0, 0)), diff);
  e.alpha = (sum + diff) / 2;
  e.gamma = (sum - diff) / 2;
  return e;
}

template <class T>
T orthonormality_defect(const Mat3<T>& r) {
  return (r.transpose() * r - Mat3<T>::Identity()).cwiseAbs().maxCoeff();
}

#define SHTOOL_INSTANTIATE(T)                                        \
  template Mat3<T> matrix_from_quaternion<T>(T, T, T, T);            \
  template Mat3<T> matrix_from_zyz<T>(const EulerZYZ<T>&);           \
  template EulerZYZ<T> zyz_from_matrix<T>(const Mat3<T>&);           \
  template T orthonormality_defect<T>(const Mat3<T>&);
SHTOOL_INSTANTIATE(float)
SHTOOL_INSTANTIATE(double)
#undef SHTOOL_INSTANTIATE

}  // namespace shtool
