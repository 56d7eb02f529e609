// Quadrature on the sphere and SH projection.
//
// The product rule "Gauss-Legendre in z = cos t times uniform in p" integrates exactly
// every polynomial of degree <= D on the sphere when it has ceil((D+1)/2) Gauss nodes in
// z and D+1 equally spaced azimuths. Projecting an order-N band-limited function needs
// D = 2N-2, i.e. N nodes in z and 2N-1 azimuths.
#pragma once

#include <functional>
#include <vector>

#include "shtool/sh.h"

namespace shtool {

// n-point Gauss-Legendre rule on [-1, 1], nodes ascending. Newton on the three-term
// recurrence from Tricomi's initial guesses; nodes and weights to ~1 ulp.
struct GaussLegendre {
  std::vector<double> nodes;
  std::vector<double> weights;
};
GaussLegendre gauss_legendre(int n);

struct SphereQuadrature {
  std::vector<Vec3<double>> directions;
  std::vector<double> weights;  // sum to 4 pi
};

// Rule exact for polynomials of total degree <= degree on the sphere.
SphereQuadrature sphere_quadrature(int degree);

// Projection f_i = integral f(w) y_i(w) dw for i < N^2, using a rule exact for
// band-limited input of order `exact_order` (>= order; a larger value integrates
// non-band-limited input more accurately). Returns N^2 coefficients.
std::vector<double> project_sh(int order, const std::function<double(const Vec3<double>&)>& f,
                               int exact_order = 0);

}  // namespace shtool
