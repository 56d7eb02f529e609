// Accurate SH triple and k-multiple products in Fourier space ([3] Sec. 4):
// SH -> 2D Fourier series (Eq. 17), 2D convolution by FFT (Eq. 24-25) in the
// divide-and-conquer order of Eq. 27, Fourier -> SH with the truncated range of Eq. 29.
// Exact for band-limited inputs up to rounding: no approximation is involved.
//
// One FourierProduct object serves one (order, number of inputs): it builds the reduced
// tensors (shtool/fourier_tensors.h) and the FFTW plans once, owns all work buffers, and
// multiply() allocates nothing. Plans are made with FFTW_ESTIMATE: measured planning
// would pick algorithms by timing, so the same inputs could give different last bits
// from run to run. An object is not safe to use from two threads at once (its buffers
// are shared); make one per thread. Creating and destroying objects is thread-safe.
#pragma once

#include <cstddef>
#include <span>

#include "shtool/detail/product_sizes.h"

namespace shtool {

// Highest order the Fourier products accept (grid sizes grow as (k n)^2).
inline constexpr int kMaxFourierProductOrder = 64;
// Most inputs of one multiple product (k - 1 <= 16, i.e. k <= 17).
inline constexpr int kMaxProductInputs = 16;

// order(), inputs(); grid_theta() x grid_phi(): the grid of the top-level convolution.
// Move-only.
template <class T>
class FourierProduct : public detail::ProductSizes {
 public:
  // Preconditions: 1 <= order <= kMaxFourierProductOrder, 1 <= inputs <= kMaxProductInputs.
  FourierProduct(int order, int inputs);

  // g = (x)_k(f_1, ..., f_{k-1}) truncated to the order (Eq. 7), k - 1 = inputs().
  // Every span holds N^2 coefficients; g may alias an input.
  void multiply(std::span<const std::span<const T>> f, std::span<T> g);
  // Triple product g = f1 (x) f2 (only when inputs() == 2).
  void multiply(std::span<const T> f1, std::span<const T> f2, std::span<T> g);

 private:
  struct Impl;
  detail::ImplPtr<Impl> impl_{nullptr, nullptr};
};

extern template class FourierProduct<float>;
extern template class FourierProduct<double>;

}  // namespace shtool
