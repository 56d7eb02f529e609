// Zeros of the associated Legendre functions P_l^m(cos t) in t in (0, pi).
//
// These are the theta candidates of the sparse-lobe search (paper 000, Sec. 5).
// For 0 <= m <= l, P_l^m(cos t) = sin^m(t) * (a polynomial of degree l - m in cos t),
// and that polynomial is orthogonal for the weight (1 - z^2)^m, so it has exactly
// l - m simple zeros inside (0, pi); P_l^l has none.
#pragma once

#include <span>
#include <vector>

namespace shtool {

// Zeros t_k of P_l^m(cos t) in (0, pi), ascending, accurate to a few 1e-15 rad
// (tested to 1e-14 up to l = 127).
// Requires 0 <= m <= l < kMaxOrder.
std::vector<double> legendre_zeros(int l, int m);

// Normalised associated Legendre value K_l^m P_l^m(cos t) (Condon-Shortley phase
// included), the same quantity the SH evaluator uses; 0 <= m <= l.
double normalized_legendre(int l, int m, double theta);

// Every normalised associated Legendre value at one point, in long double for the
// table builders (tripling tensor, SH<->Fourier tensors, grid product): for
// 0 <= m <= l < order, out[l (l+1) / 2 + m] = p00 sqrt(4 pi) K_l^m P_l^m(z), where
// z = cos t and s = sin t >= 0 are passed separately so the poles are exact; p00 is the
// (0, 0) value (1 / sqrt(4 pi) gives K_l^m P_l^m itself). Same recurrence as the SH
// evaluator (sh.cpp). out.size() >= order (order + 1) / 2.
void normalized_legendre_all(int order, long double z, long double s, long double p00, std::span<long double> out);

}  // namespace shtool
