// SH-to-Fourier and Fourier-to-SH tensors ([3] Sec. 3.2.3-3.2.4 and 4.3) in
// their reduced real form. Derivations, the mapping to the paper's complex 4D tensors
// y*_{l,m,s,t} and h*_{l,m,s,t}, and accuracy figures: docs/products.md.
//
// Real SH separate as y_l^m(t, p) = Theta_l^|m|(t) Phi_m(p) with
//   Theta_l^m(t) = sqrt(2 pi) K_l^m P_l^m(cos t)          (m >= 0, Condon-Shortley phase)
//   Phi_0 = 1/sqrt(2 pi), Phi_m = cos(m p)/sqrt(pi) (m > 0), sin(|m| p)/sqrt(pi) (m < 0).
// Theta_l^m is a trigonometric polynomial of degree l in t: a cosine series when m is
// even, a sine series when m is odd, with only frequencies s = l, l-2, ... So the
// paper's tensors, non-zero only for t = +-m, reduce to two real 3D arrays:
//   Theta_l^m(t) = sum_{s=0..l} to_fourier[l][m][s] * (m even ? cos(s t) : sin(s t))
//   to_sh[l][m][s] = integral_0^pi (m even ? cos(s t) : sin(s t)) Theta_l^m(t) sin t dt,
// for 0 <= m <= l < order and 0 <= s <= degree; both vanish unless s = l (mod 2).
// to_sh is the projection of one Fourier term onto Theta_l^m; the product of functions
// keeps the parity structure (cos * cos, sin * sin -> cos; cos * sin -> sin, matching the
// parity of t1 + t2), so the other half of the complex h* never contributes.
//
// Construction (exact up to rounding, stable for any l; no power-series expansion of
// P_l^m, which loses digits from l = 19 on): Theta_l^m is sampled at N + 1 equispaced t in
// [0, pi] with the pointwise Legendre recurrence, and a discrete cosine/sine transform
// (trapezoid sums, exact for these degrees) gives its coefficients; to_sh follows from
// to_fourier with the closed form integral_0^pi cos(a t) sin t dt = 2 / (1 - a^2) for even
// a (0 for odd a). All in long double. Running the Legendre recurrence directly on
// coefficient vectors is NOT stable for m ~ l/2 (errors 3e-13 at l = 39, measured).
#pragma once

#include <cstddef>
#include <filesystem>
#include <string_view>
#include <vector>

#include "shtool/table.h"

namespace shtool {

inline constexpr std::string_view kShFourierTensorsKind = "sh-fourier-tensors";

struct ShFourierTensors {
  int order = 0;   // n: bands 0..n-1
  int degree = 0;  // highest frequency s of to_sh (>= order - 1)
  std::vector<double> to_fourier;  // [order][order][order], zero unless m <= l, s <= l
  std::vector<double> to_sh;       // [order][order][degree + 1], zero unless m <= l

  double fourier(int l, int m, int s) const {
    return to_fourier[(static_cast<std::size_t>(l) * order + m) * order + s];
  }
  double projection(int l, int m, int s) const {
    return to_sh[(static_cast<std::size_t>(l) * order + m) * (degree + 1) + s];
  }

  // The tensors for bands 0..order-1 and frequencies up to `degree`. A k-multiple
  // product (k - 1 inputs of order n) needs degree = (k - 1)(n - 1) (Eq. 29).
  // Preconditions: 1 <= order <= kMaxOrder, order - 1 <= degree <= 4096.
  static ShFourierTensors compute(int order, int degree);

  // Table loading (kind "sh-fourier-tensors", schemas/sh-fourier-tensors.schema.json);
  // load is read_table + from_table, the path prefixed to any message.
  static Result<ShFourierTensors> from_table(const Table& table);
  static Result<ShFourierTensors> load(const std::filesystem::path& path);
};

}  // namespace shtool
