// gen-tensors: the sparse helper matrices of the zxzxz and Taylor rotations.
#pragma once

#include <filesystem>
#include <memory>
#include <vector>

#include <nlohmann/json.hpp>

#include "shtool/rotation_helpers.h"
#include "shtool/table.h"

namespace shtool {

// X90 = M(Rx(+90 deg)) by projection with a quadrature that is exact for the degree-2l
// integrands of band l (so exact up to rounding, and independent of the recurrence the
// reference rotation uses). D1 = dM(Ry(b))/db(0) from its closed form (tridiagonal,
// antisymmetric), checked against X90^T G_z X90 with G_z the exact generator of
// z-rotations (Ry(b) = Rx(-90) Rz(b) Rx(+90)); D2 = D1^2 (M(Ry(b)) = exp(b D1)).
// X90 entries below 1e-13 in magnitude are structural zeros (exact zeros by parity) and
// are dropped. Throws std::logic_error if the closed form and the X90 table disagree,
// which would mean a convention error. The quadrature sums (the N^5 part) run on
// `threads` threads (0: every core), the same values whatever the count.
RotationHelpers compute_rotation_helpers(int order, int threads = 0);

// The helpers of the fast rotation methods for `order`. From `table` when one is given
// (InputError with the loader's message, or when it covers fewer bands than `order`);
// otherwise as shipped_rotation_helpers_for with the shipped table
// (shtool/rotation_helpers.h).
std::shared_ptr<const RotationHelpers> rotation_helpers_for(int order, const std::filesystem::path& table = {});

// The helpers for `order` given the shipped table `shipped` (empty: none found): read from
// it when it covers the order, computed otherwise (the bytes gen-tensors writes: seconds
// from order 40 on, minutes above 100, growing as N^5). A shipped table that does not load
// (damaged, not a rotation-helpers table) is an InputError, not a reason to compute.
std::shared_ptr<const RotationHelpers> shipped_rotation_helpers_for(int order, const std::filesystem::path& shipped);

// Band l of X90 as a dense (2l+1) x (2l+1) block, [row][column], from the compressed rows:
// what the kernel generators (C++ and shaders) write out as literals.
std::vector<std::vector<double>> x90_band_block(const RotationHelpers& h, int l);

// The "rotation-helpers" table of `h` (schemas/rotation-helpers.schema.json), with the
// generator record the caller made (common/generator_record.h).
Table to_table(const RotationHelpers& h, const nlohmann::json& generator);

}  // namespace shtool
