// Normalised associated Legendre functions K_l^m P_l^m(cos t), one value or all of them
// at a point (the table builders).
#pragma once

#include <span>

namespace shtool {

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
