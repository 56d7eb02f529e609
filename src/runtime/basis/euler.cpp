#include "shtool/euler.h"

#include <cmath>

#include <Eigen/Dense>

namespace shtool {

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
  const ZyzCosSin<T> cs = zyz_cos_sin_from_matrix(r);
  return {std::atan2(cs.sa, cs.ca), std::atan2(cs.sb, cs.cb), std::atan2(cs.sg, cs.cg)};
}

template <class T>
T orthonormality_defect(const Mat3<T>& r) {
  return (r.transpose() * r - Mat3<T>::Identity()).cwiseAbs().maxCoeff();
}

#define SHTOOL_INSTANTIATE(T)                                        \
  template Mat3<T> matrix_from_zyz<T>(const EulerZYZ<T>&);           \
  template EulerZYZ<T> zyz_from_matrix<T>(const Mat3<T>&);           \
  template T orthonormality_defect<T>(const Mat3<T>&);
SHTOOL_INSTANTIATE(float)
SHTOOL_INSTANTIATE(double)
#undef SHTOOL_INSTANTIATE

}  // namespace shtool
