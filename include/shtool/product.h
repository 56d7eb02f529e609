// SH products, one entry point: triple products g = f1 (x) f2, triple product integrals,
// accurate k-multiple products and the recursive triple-product approximation
// ([3]; methods and measured speed in docs/products.md).
//
//  - tripling: the sparse tripling tensor (shtool/tripling_product.h), O(N^5);
//  - fourier:  SH -> Fourier, FFT convolution, Fourier -> SH (shtool/fourier_product.h),
//              the paper's method, O(N^3) for triple products;
//  - grid:     Gauss-Legendre x equispaced-azimuth quadrature (shtool/grid_product.h):
//              synthesis, pointwise product, projection; O(N^3), exact to rounding;
//  - automatic: whichever is faster at the order (measured, kGridTripleFromOrder).
// Accurate multiple products of more than two inputs use the grid (automatic, grid,
// tripling) or the Fourier method with divide and conquer (Eq. 27) when it is asked for;
// the tripling tensor can only chain triple products, which truncates after every step
// (Eq. 11) and is what recursive() computes.
//
// Not thread-safe (the Fourier plans share buffers): one ShProduct per thread.
#pragma once

#include <memory>
#include <span>
#include <vector>

#include "shtool/fourier_product.h"
#include "shtool/grid_product.h"
#include "shtool/tripling_product.h"

namespace shtool {

enum class ProductMethod { automatic, tripling, fourier, grid };

// From this order on the grid triple product beats the tripling tensor on the reference
// machine in both float and double (bench/bench_products.cpp, docs/products.md); below
// it the generated tripling kernels (orders 2..6) are faster. The grid beats the Fourier
// method at every order.
inline constexpr int kGridTripleFromOrder = 7;

template <class T>
class ShProduct {
 public:
  // `tensor` (optional) is a tripling tensor for at least this order's bands, e.g. one
  // loaded from a table; it is copied into the product's own layout. Without it the
  // tensor is computed when the tripling method is first needed.
  // Preconditions: 1 <= order <= kMaxFourierProductOrder, and order <= kMaxTriplingOrder
  // when the method resolves to tripling.
  explicit ShProduct(int order, ProductMethod method = ProductMethod::automatic,
                     const TriplingTensor* tensor = nullptr);
  ~ShProduct();

  int order() const { return order_; }
  // The method triple() uses (automatic resolved).
  ProductMethod triple_method() const { return triple_method_; }

  // g = f1 (x) f2 (Eq. 6). N^2 coefficients each; g may alias an input.
  void triple(std::span<const T> f1, std::span<const T> f2, std::span<T> g) {
    // Small orders: the generated tripling kernel, called from here (inline) because at
    // N = 3 a product costs about 30 ns and every call layer shows.
    if (triple_kernel_ && g.data() != f1.data() && g.data() != f2.data()) {
      triple_kernel_(f1.data(), f2.data(), g.data());
      return;
    }
    triple_general(f1, f2, g);
  }
  // integral F1 F2 F3 (Eq. 4).
  T triple_integral(std::span<const T> f1, std::span<const T> f2, std::span<const T> f3);
  // Accurate product of all inputs truncated to order N (Eq. 7). 1 <= f.size() <=
  // kMaxProductInputs; two inputs use triple().
  // Uses the Fourier method if this object was made with ProductMethod::fourier, the
  // grid otherwise.
  void multiple(std::span<const std::span<const T>> f, std::span<T> g);
  // Recursive triple-product approximation (Eq. 11): ((f1 (x) f2) (x) f3) ... with the
  // triple method of this object; truncates to order N after every step.
  void recursive(std::span<const std::span<const T>> f, std::span<T> g);
  // Builds the plans for `inputs` inputs now, so that the first multiple() call does not
  // allocate. Called implicitly when needed.
  void prepare(int inputs);

 private:
  void triple_general(std::span<const T> f1, std::span<const T> f2, std::span<T> g);
  const TriplingProduct<T>& tripling();
  FourierProduct<T>& fourier(int inputs);
  GridProduct<T>& grid(int inputs);

  int order_;
  ProductMethod triple_method_;
  bool multiple_fourier_;  // accurate multiple products by the Fourier method, not the grid
  std::unique_ptr<TriplingProduct<T>> tripling_;
  typename TriplingProduct<T>::Kernel triple_kernel_ = nullptr;  // its kernel, if triple() uses it
  std::vector<std::unique_ptr<FourierProduct<T>>> fourier_;  // index: number of inputs
  std::vector<std::unique_ptr<GridProduct<T>>> grid_;        // index: number of inputs
  std::vector<T> scratch_a_, scratch_b_;
};

// Accurate product of k inputs of order N by the tripling tensor alone: the second
// reference beside the Fourier method. Each step multiplies the running product by the
// next input exactly, keeping min(j (N-1) + 1, N + (k-j) (N-1)) bands after j inputs
// (higher bands cannot reach the final order N), so nothing is lost to truncation. Builds
// tensors per call: a reference path, not for hot loops.
// Returns the largest intermediate order needed; if it exceeds kMaxTriplingOrder, g is
// untouched and the caller should use the Fourier method.
int tripling_order_needed(int order, int inputs);
template <class T>
int tripling_multiple_product(int order, std::span<const std::span<const T>> f, std::span<T> g);

extern template class ShProduct<float>;
extern template class ShProduct<double>;

}  // namespace shtool
