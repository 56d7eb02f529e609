// gen-tensors: the tripling tensor C_ijk = integral y_i y_j y_k ([3] Eq. 5) by
// an exact construction: Wigner 3j symbols (Racah's formula, summed in quadruple
// precision), Gaunt's formula for the complex harmonics, and the real basis through
// the separation y_l^m = Theta_l^|m|(t) Phi_m(p) (details in tripling.cpp and
// docs/products.md). The runtime builds the same tensor by exact Gauss-Legendre
// quadrature (TriplingTensor::compute); the tests check one against the other and both
// against a sphere quadrature of eval_sh.
#pragma once

#include <nlohmann/json.hpp>

#include "shtool/table.h"
#include "shtool/tripling_product.h"

namespace shtool {

// Wigner 3j symbol (j1 j2 j3; m1 m2 m3) for integer j up to 3 * kMaxTriplingOrder.
// Racah's alternating sum is formed in __float128 (113-bit mantissa) so its cancellation
// (a few digits at j ~ 60) stays far below double precision; relative error ~1e-19.
// Returns 0 outside the selection rules.
long double wigner_3j(int j1, int j2, int j3, int m1, int m2, int m3);

// Complex Gaunt coefficient integral Y_l1^m1 Y_l2^m2 Y_l3^m3 (Condon-Shortley phase).
long double gaunt_complex(int l1, int m1, int l2, int m2, int l3, int m3);

// Real-SH tripling coefficient C for flat indices i, j, k (any order), exact to ~1 ulp.
double tripling_coefficient_exact(int i, int j, int k);

// All canonical non-zeros (i <= j <= k) by the exact construction.
// Precondition: 1 <= order <= kMaxTriplingOrder.
TriplingTensor compute_tripling_tensor_exact(int order);

// The "tripling-tensor" table of the given order (exact construction), with the
// generator record the caller made (offline_version.h, generator_record).
Table tripling_tensor_table(int order, const nlohmann::json& generator);

// The "tripling-tensor" table of `tensor` (schemas/tripling-tensor.schema.json);
// `extra_meta` adds fields to the kind's own "meta".
Table to_table(const TriplingTensor& tensor, const nlohmann::json& generator,
               const nlohmann::json& extra_meta = nlohmann::json::object());

}  // namespace shtool
