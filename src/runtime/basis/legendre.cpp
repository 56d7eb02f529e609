#include "shtool/legendre.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "basis/legendre_recurrence.h"
#include "shtool/sh.h"

namespace shtool {
double normalized_legendre(int l, int m, double theta) {
  double q, dq;
  detail::legendre_q_and_derivative(l, m, std::cos(theta), q, dq);
  return q * std::pow(std::sin(theta), m);
}

void normalized_legendre_all(int order, long double z, long double s, long double p00, std::span<long double> out) {
  long double diag = p00;  // Q_m^m sin^m t, carried along the diagonal
  for (int m = 0; m < order; ++m) {
    if (m > 0) diag *= detail::legendre_diag<long double>(m) * s;
    long double p2 = 0, p1 = diag;
    out[static_cast<std::size_t>(m) * (m + 1) / 2 + m] = p1;
    for (int l = m + 1; l < order; ++l) {
      long double p;
      if (l == m + 1) {
        p = detail::legendre_subdiag<long double>(m) * z * p1;
      } else {
        p = detail::legendre_a<long double>(l, m) * (z * p1 - detail::legendre_b<long double>(l, m) * p2);
      }
      out[static_cast<std::size_t>(l) * (l + 1) / 2 + m] = p;
      p2 = p1;
      p1 = p;
    }
  }
}

}  // namespace shtool
