#include "shtool/rotation_helpers.h"

#include <cmath>
#include <cstdlib>
#include <string>
#include <system_error>
#include <vector>

#include "io/load_kind.h"
#include "rotation/x90_structure.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

Error helpers_error(const std::string& what) {
  return Error{"rotation-helpers table: " + what};
}

}  // namespace

Result<RotationHelpers> RotationHelpers::from_table(const Table& table) {
  if (table.kind != kRotationHelpersKind)
    return helpers_error("wrong kind '" + table.kind + "'");
  if (const auto problem = detail::array_sizes_problem(table)) return helpers_error(*problem);
  if (!is_supported_order(table.order))
    return helpers_error("unsupported order " + std::to_string(table.order));
  RotationHelpers h;
  h.order = table.order;
  const std::size_t n = static_cast<std::size_t>(sh_count(h.order));
  auto get = [&](const char* name, DType type, const TableArray*& out) -> bool {
    out = table.find(name);
    return out && out->dtype == type;
  };
  const TableArray *row, *col, *val, *dy, *ddd, *ddo;
  if (!get("x90_row", DType::i32, row) || !get("x90_col", DType::i32, col) ||
      !get("x90_val", DType::f64, val) || !get("dy_sub", DType::f64, dy) ||
      !get("ddy_diag", DType::f64, ddd) || !get("ddy_off2", DType::f64, ddo))
    return helpers_error("missing array or wrong dtype (need i32 x90_row, x90_col; f64 x90_val, "
                         "dy_sub, ddy_diag, ddy_off2)");
  h.x90_row = row->values<std::int32_t>();
  h.x90_col = col->values<std::int32_t>();
  h.x90_val = val->values<double>();
  h.dy_sub = dy->values<double>();
  h.ddy_diag = ddd->values<double>();
  h.ddy_off2 = ddo->values<double>();
  if (h.x90_row.size() != n + 1 || h.dy_sub.size() != n || h.ddy_diag.size() != n ||
      h.ddy_off2.size() != n)
    return helpers_error("array sizes do not match order " + std::to_string(h.order));
  if (h.x90_col.size() != h.x90_val.size() || h.x90_row.front() != 0 ||
      static_cast<std::size_t>(h.x90_row.back()) != h.x90_col.size())
    return helpers_error("inconsistent X90 compressed rows");
  // Every stored entry must lie inside its row's band block: the rotation code relies
  // on that and never checks indices in the hot loop.
  for (std::size_t i = 0; i < n; ++i) {
    if (h.x90_row[i + 1] < h.x90_row[i] ||
        static_cast<std::size_t>(h.x90_row[i + 1]) > h.x90_col.size())
      return helpers_error("X90 row starts decrease or pass the non-zeros at row " + std::to_string(i));
    const int l = sh_band(static_cast<int>(i));
    for (int k = h.x90_row[i]; k < h.x90_row[i + 1]; ++k)
      if (h.x90_col[k] < l * l || h.x90_col[k] > l * l + 2 * l)
        return helpers_error("X90 entry outside its band in row " + std::to_string(i));
  }
  // The class structure of every row of X90 and of X90^T (rotation/x90_structure.h),
  // which the rotation's packed loops rely on.
  for (int l = 0; l < h.order; ++l) {
    const int first = l * l, size = 2 * l + 1;
    std::vector<double> block(static_cast<std::size_t>(size) * size, 0.0);
    for (int i = first; i < first + size; ++i)
      for (int k = h.x90_row[i]; k < h.x90_row[i + 1]; ++k)
        block[static_cast<std::size_t>(i - first) * size + (h.x90_col[k] - first)] = h.x90_val[k];
    for (int r = 0; r < size; ++r) {
      const bool rows_ok = detail::x90_row_run(l, r, [&](int c) { return block[r * size + c]; }).has_value();
      const bool cols_ok = detail::x90_row_run(l, r, [&](int c) { return block[c * size + r]; }).has_value();
      if (!rows_ok || !cols_ok)
        return helpers_error("X90 band " + std::to_string(l) + (rows_ok ? " column " : " row ") + std::to_string(r) +
                             " breaks the sparsity structure of a rotation by 90 degrees about x");
    }
  }
  // Values: X90 is orthogonal (|entries| <= 1); D1's entries are at most l in band l and
  // D2 = D1^2's at most l (l + 1). Far looser bounds still keep a corrupted value (an
  // infinity, 1e300) from turning rotations into NaN.
  for (double v : h.x90_val)
    if (!(std::abs(v) <= 1.0 + 1e-9)) return helpers_error("X90 value outside [-1, 1]");
  for (std::size_t i = 0; i < n; ++i) {
    const double l = sh_band(static_cast<int>(i));
    if (!(std::abs(h.dy_sub[i]) <= l + 1)) return helpers_error("D1 value out of range at " + std::to_string(i));
    if (!(std::abs(h.ddy_diag[i]) <= 2 * (l + 1) * (l + 1)) || !(std::abs(h.ddy_off2[i]) <= 2 * (l + 1) * (l + 1)))
      return helpers_error("D2 value out of range at " + std::to_string(i));
  }
  return h;
}

Result<RotationHelpers> RotationHelpers::load(const std::filesystem::path& path) {
  return detail::load_kind<RotationHelpers>(path, kRotationHelpersKind);
}

std::filesystem::path default_rotation_helpers_path() { return find_shipped_table("rotation-helpers.shtb"); }

}  // namespace shtool
