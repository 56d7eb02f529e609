// Accurate SH products by quadrature on a Gauss-Legendre x equispaced-azimuth grid:
// synthesize every input on the grid, multiply pointwise, project back to order N.
//
// The projected integrand y_lm f_1 ... f_q (q inputs of order N) is a polynomial of
// degree D = (q + 1)(N - 1) on the sphere, so the grid below integrates it exactly
// (up to rounding): no approximation is involved, for triple products (q = 2),
// k-multiple products (q = k - 1) and triple product integrals alike.
//  - polar: n_t = floor(D / 2) + 1 Gauss-Legendre nodes in x = cos t (exact for degree
//    2 n_t - 1 >= D);
//  - azimuth: n_p >= D + 1 equispaced points (the product has frequencies |m| <= q (N-1);
//    aliasing folds frequency m onto m - n_p, which stays outside |m| < N).
// Synthesis and projection use the normalized associated Legendre values at the nodes
// (computed once, in long double, whatever T is) and the equatorial symmetry
// P_l^m(-x) = (-1)^(l+m) P_l^m(x), which halves the Legendre sums. Two azimuthal
// transforms, both exact (GridAzimuth):
//  - direct: sums over the N frequencies the inputs and the projection use, n_p = D + 1,
//    vectorised across rings; the default in float up to N = 20 and in double up to
//    N = 11, where it was measured faster (docs/products.md);
//  - fft: FFTW real transforms over all rings at once (one plan_many each way, made once
//    per object, FFTW_ESTIMATE for byte-identical results), n_p the smallest of a fixed
//    list of even lengths measured fast, so the grid does not depend on timing.
// Method notes and measured speed: docs/products.md.
//
// One GridProduct serves one (order, number of inputs) and owns all buffers: multiply()
// and integral() allocate nothing. Not safe to use from two threads at once; creating
// and destroying objects is thread-safe.
#pragma once

#include <memory>
#include <span>

#include "shtool/fourier_product.h"  // kMaxFourierProductOrder, kMaxProductInputs

namespace shtool {

// How the grid goes between azimuthal frequencies and points on each ring.
enum class GridAzimuth {
  automatic,  // direct below a measured number of points, FFT above (grid_product.cpp)
  direct,     // direct sums over |m| < N: nphi = D + 1, the fewest points possible
  fft,        // FFTW real transforms: nphi an FFT-friendly even length >= D + 1
};

// order(), inputs(); grid_theta() x grid_phi(): Gauss-Legendre rings x azimuthal points.
// Move-only.
template <class T>
class GridProduct : public detail::ProductSizes {
 public:
  // Preconditions: 1 <= order <= kMaxFourierProductOrder, 1 <= inputs <= kMaxProductInputs
  // (std::invalid_argument otherwise).
  GridProduct(int order, int inputs, GridAzimuth azimuth = GridAzimuth::automatic);

  // g = product of the inputs() functions f truncated to the order ([3] Eq. 7).
  // Every span holds N^2 coefficients; g may alias an input.
  void multiply(std::span<const std::span<const T>> f, std::span<T> g);
  // Triple product g = f1 (x) f2 (only when inputs() == 2).
  void multiply(std::span<const T> f1, std::span<const T> f2, std::span<T> g);
  // Integral over the sphere of the product of inputs() + 1 functions (Eq. 4 for
  // inputs() == 2): the grid is exact for that degree too.
  T integral(std::span<const std::span<const T>> f);

  GridAzimuth azimuth() const;  // never automatic

  struct Impl;  // one per azimuthal method, in grid_product.cpp

 private:
  detail::ImplPtr<Impl> impl_{nullptr, nullptr};
};

extern template class GridProduct<float>;
extern template class GridProduct<double>;

}  // namespace shtool
