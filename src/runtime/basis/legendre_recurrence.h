// Internal to the runtime: the coefficients of the normalised associated Legendre
// recurrence, in one place for every evaluator (SH basis, ZHF lobe evaluation, the
// long-double table builders, the offline root finder). The recurrence runs on the
// pole-free quantity
//   Q_l^m(z) = K_l^m P_l^m(z) / sin^m(t)          (Condon-Shortley phase included):
//   Q_0^0 = 1 / sqrt(4 pi)
//   Q_m^m = -sqrt((2m+1) / (2m)) Q_{m-1}^{m-1}                   (diagonal)
//   Q_{m+1}^m = sqrt(2m+3) z Q_m^m                                (sub-diagonal)
//   Q_l^m = a_l^m (z Q_{l-1}^m - b_l^m Q_{l-2}^m),
//     a_l^m = sqrt((4l^2 - 1) / (l^2 - m^2)),  b_l^m = sqrt(((l-1)^2 - m^2) / (4 (l-1)^2 - 1)).
// Each coefficient is computed in R (double or long double) by one expression, so every
// user gets the same bits.
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "shtool/sh.h"

namespace shtool::detail {

template <class R>
R legendre_q00() {
  return R(0.5) / std::sqrt(std::numbers::pi_v<R>);
}
template <class R>
R legendre_diag(int m) {
  return -std::sqrt((R(2) * m + R(1)) / (R(2) * m));
}
template <class R>
R legendre_subdiag(int m) {
  return std::sqrt(R(2) * m + R(3));
}
template <class R>
R legendre_a(int l, int m) {
  const R ld = l, md = m;
  return std::sqrt((4 * ld * ld - 1) / (ld * ld - md * md));
}
template <class R>
R legendre_b(int l, int m) {
  const R ld = l, md = m;
  return std::sqrt(((ld - 1) * (ld - 1) - md * md) / (4 * (ld - 1) * (ld - 1) - 1));
}

// Q_l^m(z) and dQ/dz for one (l, m), in double, off the hot paths (lobe candidates,
// single values).
inline void legendre_q_and_derivative(int l, int m, double z, double& q, double& dq) {
  double qmm = legendre_q00<double>();
  for (int k = 1; k <= m; ++k) qmm *= legendre_diag<double>(k);
  double q2 = 0, dq2 = 0, q1 = qmm, dq1 = 0;
  for (int k = m + 1; k <= l; ++k) {
    const double a = legendre_a<double>(k, m);
    const double b = legendre_b<double>(k, m);
    const double q0 = a * (z * q1 - b * q2);
    const double dq0 = a * (q1 + z * dq1 - b * dq2);
    q2 = q1;
    dq2 = dq1;
    q1 = q0;
    dq1 = dq0;
  }
  q = q1;
  dq = dq1;
}

// The coefficients up to kMaxOrder, computed in double and stored as T.
template <class T>
struct LegendreRecurrence {
  T q00;
  std::array<T, kMaxOrder> diag;     // diag[m], m >= 1 (diag[0] = 0)
  std::array<T, kMaxOrder> subdiag;  // subdiag[m]
  std::vector<T> a, b;               // triangular index tri(l, m), m = 0..l-2

  LegendreRecurrence() : a(kMaxOrder * (kMaxOrder + 1) / 2), b(kMaxOrder * (kMaxOrder + 1) / 2) {
    q00 = static_cast<T>(legendre_q00<double>());
    diag[0] = 0;
    for (int m = 1; m < kMaxOrder; ++m) diag[m] = static_cast<T>(legendre_diag<double>(m));
    for (int m = 0; m < kMaxOrder; ++m) subdiag[m] = static_cast<T>(legendre_subdiag<double>(m));
    for (int l = 2; l < kMaxOrder; ++l)
      for (int m = 0; m <= l - 2; ++m) {
        a[tri(l, m)] = static_cast<T>(legendre_a<double>(l, m));
        b[tri(l, m)] = static_cast<T>(legendre_b<double>(l, m));
      }
  }
  static constexpr int tri(int l, int m) { return l * (l + 1) / 2 + m; }
};

template <class T>
const LegendreRecurrence<T>& legendre_recurrence() {
  static const LegendreRecurrence<T> table;
  return table;
}

}  // namespace shtool::detail
