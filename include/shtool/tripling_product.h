// The tripling tensor C_ijk = integral y_i y_j y_k over the sphere (the real-SH Gaunt
// coefficients; [3] Eq. 5) and the SH triple product by that tensor:
//   g_k = sum_ij C_ijk f1_i f2_j            (Eq. 6, g = f1 (x) f2 truncated to order N)
//   integral F1 F2 F3 = sum_ijk C_ijk f1_i f2_j f3_k    (Eq. 4)
// Conventions (real SH, Condon-Shortley phase, flat index l(l+1)+m): docs/conventions.md.
// Method notes and measured figures: docs/products.md.
//
// Storage: C is symmetric under every permutation of (i, j, k) and vanishes unless
// the bands satisfy the triangle rule |l1 - l2| <= l3 <= l1 + l2 with l1 + l2 + l3 even,
// and the azimuthal indices satisfy the real-SH rule (one |m| is the sum of the other
// two or the difference, and an even number of them are negative). Only the non-zeros
// with i <= j <= k are kept ("canonical" entries, sorted by (i, j, k)); the product
// expands them once into a gather layout with no zero entries.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string_view>
#include <vector>

#include "shtool/table.h"

namespace shtool {

inline constexpr std::string_view kTriplingTensorKind = "tripling-tensor";
// The tensor has O(N^5) non-zeros (2,449,404 canonical ones at N = 32): beyond
// this order use the Fourier product (shtool/fourier_product.h).
inline constexpr int kMaxTriplingOrder = 32;

// Canonical non-zeros of C for bands 0..order-1.
struct TriplingTensor {
  int order = 0;
  std::vector<std::uint32_t> index;  // 3 per entry: i <= j <= k, entries sorted by (i, j, k)
  std::vector<double> value;         // C_ijk of each entry

  std::size_t size() const { return value.size(); }

  // Runtime construction, no table needed. C_ijk factors into an azimuthal integral
  // (closed form) times a polar integral of three normalised associated Legendre
  // functions, which is a polynomial of degree l1 + l2 + l3 in cos t and is integrated
  // exactly by Gauss-Legendre (long double accumulation). Agrees with the exact Wigner
  // 3j construction of the offline tool (src/tensors/tripling.h) to ~1e-15.
  // Precondition: 1 <= order <= kMaxTriplingOrder.
  static TriplingTensor compute(int order);

  // The shared skeleton of every construction: enumerates the index triples i <= j <= k
  // that the selection rules of real SH leave possibly non-zero, asks `coefficient` for
  // each, drops values below 1e-12 and returns them sorted.
  static TriplingTensor from_candidates(int order,
                                        const std::function<double(int i, int j, int k)>& coefficient);

  // Table loading (kind "tripling-tensor", schemas/tripling-tensor.schema.json).
  // from_table checks kind, order, shapes, index bounds, canonical order, uniqueness and
  // the selection rules, so a corrupted table cannot make the product read out of range;
  // load is read_table + from_table, the path prefixed to any message.
  static Result<TriplingTensor> from_table(const Table& table);
  static Result<TriplingTensor> load(const std::filesystem::path& path);
};

// Azimuthal factor of the real-SH tripling coefficient: the integral over p in [0, 2 pi)
// of Phi_m1 Phi_m2 Phi_m3, with Phi_0 = 1/sqrt(2 pi), Phi_m = cos(m p)/sqrt(pi) (m > 0),
// sin(|m| p)/sqrt(pi) (m < 0). Exact up to one rounding; 0 when the m rule fails.
double tripling_azimuthal_factor(int m1, int m2, int m3);

// Sparse triple product by the tripling tensor. Gather layout: for every output k, the
// pairs i <= j with C_ijk != 0 and the weight C_ijk (C_iik / 2 on the diagonal, so every
// pair costs w (f1_i f2_j + f1_j f2_i)). Thread-safe after construction (const).
template <class T>
class TriplingProduct {
 public:
  explicit TriplingProduct(const TriplingTensor& tensor);

  int order() const { return order_; }
  std::size_t pair_count() const { return weight_.size(); }
  // The generated kernel of its order that multiply() runs (nullptr: the gather loop).
  using Kernel = void (*)(const T* f1, const T* f2, T* g);
  Kernel kernel() const { return kernel_; }
  bool uses_kernel() const { return kernel_ != nullptr; }

  // g = f1 (x) f2 (Eq. 6). All spans hold N^2 coefficients (precondition); g must not
  // alias f1 or f2. Allocation-free.
  void multiply(std::span<const T> f1, std::span<const T> f2, std::span<T> g) const;
  // integral F1 F2 F3 over the sphere (Eq. 4). Allocation-free.
  T integral(std::span<const T> f1, std::span<const T> f2, std::span<const T> f3) const;

 private:
  int order_ = 0;
  std::vector<std::uint32_t> row_;   // N^2 + 1 starts into pair_/weight_
  std::vector<std::uint32_t> pair_;  // i | (j << 16)
  std::vector<T> weight_;
  // Orders 2..kUnrolledTriplingOrder: a generated straight-line kernel (values as
  // literals, pair products as vector rows), used when the tensor holds its entries.
  Kernel kernel_ = nullptr;
};

// Highest order with a generated straight-line tripling kernel
// (`shtool gen-tensors --what tripling-kernels`).
inline constexpr int kUnrolledTriplingOrder = 6;

extern template class TriplingProduct<float>;
extern template class TriplingProduct<double>;

}  // namespace shtool
