#include "shtool/rotation_helpers.h"

#include <cstdlib>
#include <string>
#include <system_error>

#include "shtool/sh.h"

namespace shtool {
namespace {

TableError helpers_error(const std::string& what) {
  return TableError{"rotation-helpers table: " + what};
}

}  // namespace

Table RotationHelpers::to_table(const nlohmann::json& generator) const {
  const std::int64_t n = sh_count(order);
  const std::int64_t nnz = static_cast<std::int64_t>(x90_val.size());
  Table t;
  t.kind = std::string(kRotationHelpersKind);
  t.kind_version = "1.0";
  t.order = order;
  t.generator = generator;
  t.meta = {{"x90_nonzeros", nnz}, {"description",
            "X90 = M(Rx(+90 deg)) in CSR; D1 = dM(Ry(b))/db(0) sub-diagonal; D2 = D1^2 diagonal "
            "and distance-2 diagonal"}};
  t.arrays.push_back(TableArray::from<std::int32_t>("x90_row", {n + 1}, x90_row));
  t.arrays.push_back(TableArray::from<std::int32_t>("x90_col", {nnz}, x90_col));
  t.arrays.push_back(TableArray::from<double>("x90_val", {nnz}, x90_val));
  t.arrays.push_back(TableArray::from<double>("dy_sub", {n}, dy_sub));
  t.arrays.push_back(TableArray::from<double>("ddy_diag", {n}, ddy_diag));
  t.arrays.push_back(TableArray::from<double>("ddy_off2", {n}, ddy_off2));
  return t;
}

TableResult<RotationHelpers> RotationHelpers::from_table(const Table& table) {
  if (table.kind != kRotationHelpersKind)
    return helpers_error("wrong kind '" + table.kind + "'");
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
  return h;
}

TableResult<RotationHelpers> RotationHelpers::load(const std::filesystem::path& path, int min_order) {
  TableResult<Table> table = read_table(path, TableExpectation{std::string(kRotationHelpersKind), 1, 0});
  if (!table) return table.error();
  TableResult<RotationHelpers> h = from_table(table.value());
  if (!h) return TableError{path.string() + ": " + h.error().message};
  if (h.value().order < min_order)
    return TableError{path.string() + ": rotation-helpers table covers order " +
                      std::to_string(h.value().order) + ", order " + std::to_string(min_order) +
                      " was asked for"};
  return h;
}

std::filesystem::path default_rotation_helpers_path() {
  const char* name = "rotation-helpers.shtb";
  std::error_code ec;
  if (const char* env = std::getenv("SHTOOL_TABLES")) {
    const std::filesystem::path p = std::filesystem::path(env) / name;
    if (std::filesystem::exists(p, ec)) return p;
  }
  for (const char* dir : {SHTOOL_SOURCE_TABLES_DIR, SHTOOL_INSTALL_TABLES_DIR}) {
    const std::filesystem::path p = std::filesystem::path(dir) / name;
    if (std::filesystem::exists(p, ec)) return p;
  }
  return {};
}

}  // namespace shtool
