#include "shtool/euler.h"

#include <cmath>

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
ZyzCosSin<T> zyz_cos_sin_from_matrix(const Mat3<T>& r) {
  // R = Rz(a) Ry(b) Rz(g):
  //   (R02, R12) = sin b (cos a, sin a),  (-R20, R21) = sin b (cos g, sin g),  R22 = cos b
  //   (R00 + R11, R10 - R01) = (1 + cos b) (cos(a + g), sin(a + g))
  //   (R11 - R00, -(R10 + R01)) = (1 - cos b) (cos(a - g), sin(a - g))
  ZyzCosSin<T> e;
  e.cb = r(2, 2);
  e.sb = std::sqrt(r(0, 2) * r(0, 2) + r(1, 2) * r(1, 2));  // not sqrt(1 - cb^2): exact near b = 0
  if (e.sb > 0) {
    e.ca = r(0, 2) / e.sb;
    e.sa = r(1, 2) / e.sb;
  }
  if (e.cb >= 0) {
    T cs = r(0, 0) + r(1, 1), ss = r(1, 0) - r(0, 1);
    const T norm = std::sqrt(cs * cs + ss * ss);  // = 1 + cos b >= 1
    cs /= norm;
    ss /= norm;
    e.cg = cs * e.ca + ss * e.sa;  // g = (a + g) - a
    e.sg = ss * e.ca - cs * e.sa;
  } else {
    T cd = r(1, 1) - r(0, 0), sd = -(r(1, 0) + r(0, 1));
    const T norm = std::sqrt(cd * cd + sd * sd);  // = 1 - cos b > 1
    cd /= norm;
    sd /= norm;
    e.cg = e.ca * cd + e.sa * sd;  // g = a - (a - g)
    e.sg = e.sa * cd - e.ca * sd;
  }
  return e;
}

template <class T>
EulerZYZ<T> zyz_from_matrix(const Mat3<T>& r) {
  const ZyzCosSin<T> cs = zyz_cos_sin_from_matrix(r);
  return {std::atan2(cs.sa, cs.ca), std::atan2(cs.sb, cs.cb), std::atan2(cs.sg, cs.cg)};
}

template <class T>
T orthonormality_defect(const Mat3<T>& r) {
  return (r.transpose() * r - Mat3<T>::Identity()).cwiseAbs().maxCoeff();
}

#define SHTOOL_INSTANTIATE(T)                                        \
  template Mat3<T> matrix_from_quaternion<T>(T, T, T, T);            \
  template Mat3<T> matrix_from_zyz<T>(const EulerZYZ<T>&);           \
  template EulerZYZ<T> zyz_from_matrix<T>(const Mat3<T>&);           \
  template ZyzCosSin<T> zyz_cos_sin_from_matrix<T>(const Mat3<T>&);  \
  template T orthonormality_defect<T>(const Mat3<T>&);
SHTOOL_INSTANTIATE(float)
SHTOOL_INSTANTIATE(double)
#undef SHTOOL_INSTANTIATE

}  // namespace shtool
