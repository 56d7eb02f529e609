// Zeros of the associated Legendre functions P_l^m(cos t) in t in (0, pi): the theta
// candidates of the sparse-lobe search ([1] Sec. 5).
// For 0 <= m <= l, P_l^m(cos t) = sin^m(t) * (a polynomial of degree l - m in cos t),
// and that polynomial is orthogonal for the weight (1 - z^2)^m, so it has exactly
// l - m simple zeros inside (0, pi); P_l^l has none.
#pragma once

#include <vector>

namespace shtool {

// Zeros t_k of P_l^m(cos t) in (0, pi), ascending, accurate to a few 1e-15 rad
// (tested to 1e-14 up to l = 127).
// Requires 0 <= m <= l < kMaxOrder.
std::vector<double> legendre_zeros(int l, int m);

}  // namespace shtool
