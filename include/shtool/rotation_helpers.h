// The precomputed sparse matrices that the zxzxz and small-angle Taylor rotations need,
// as written by `shtool gen-tensors --what rotation` into a "rotation-helpers" table
// (shipped in tables/rotation-helpers.shtb).
//
//  - X90 = M(Rx(+90 deg)), the SH rotation matrix of a +90 degree turn about x, block
//    diagonal by band and about half zeros; stored in compressed rows (CSR) over the
//    flat index. M(Rx(-90 deg)) = X90^T.
//  - The derivatives at b = 0 of the y-rotation M(Ry(b)) ([2] Sec. 3, App. A):
//    D1 = dM/db(0) is antisymmetric and tridiagonal inside each band, so only its
//    sub-diagonal D1[i][i-1] is stored; D2 = d2M/db2(0) = D1^2 is symmetric with
//    non-zeros on the diagonal and at distance 2, so D2[i][i] and D2[i][i-2] are stored.
#pragma once

#include <filesystem>
#include <string_view>
#include <vector>

#include "shtool/table.h"

namespace shtool {

inline constexpr std::string_view kRotationHelpersKind = "rotation-helpers";

struct RotationHelpers {
  int order = 0;
  std::vector<int> x90_row;     // N^2 + 1 row starts
  std::vector<int> x90_col;     // flat column index of each non-zero
  std::vector<double> x90_val;  // value of each non-zero
  std::vector<double> dy_sub;   // N^2 entries: D1[i][i-1] (0 where i is the first of its band)
  std::vector<double> ddy_diag; // N^2 entries: D2[i][i]
  std::vector<double> ddy_off2; // N^2 entries: D2[i][i-2] (0 where i-2 is in another band)

  // Table loading (the writer is offline). from_table checks kind, shapes and internal
  // consistency (CSR bounds, columns inside the row's band) so a corrupted table cannot
  // index out of range; load is read_table + from_table, the path prefixed to any message.
  // A rotation of a higher order than `order` refuses these helpers (ShRotation::set).
  static Result<RotationHelpers> from_table(const Table& table);
  static Result<RotationHelpers> load(const std::filesystem::path& path);
};

// The shipped table (find_shipped_table in shtool/table.h: $SHTOOL_TABLES, then the
// installed share/shtool/tables). Returns an empty path if none exists.
std::filesystem::path default_rotation_helpers_path();

}  // namespace shtool
