// Internal to the runtime: the checks every table kind made of ZH fit rows shares (the
// zh-fit table of fit-zh, the glossy-zh table of fit-glossy).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "shtool/result.h"
#include "shtool/table.h"
#include "shtool/zh_fit_table.h"

namespace shtool::table_format {

// The f64 array `name` with exactly `shape` and only finite values, or an error naming
// what differs, `prefix` first.
Result<std::vector<double>> finite_f64_array(const Table& t, const char* name, const std::vector<std::int64_t>& shape,
                                             const std::string& prefix);

// The rows of a fit: order, arrays axes [R, N, 3] (unit), coeffs [R, N, n], residual [R]
// and norm [R] (non-negative), optional direct [R, 1 or 4]; values that fit T. The kind,
// the meta and any other array are the caller's to check. Messages start with `prefix`.
template <class T>
Result<ZhFitTable<T>> zh_rows_from_table(const Table& t, const std::string& prefix);

}  // namespace shtool::table_format
