// Internal to the runtime: the checks every table kind made of ZH fit rows shares (the
// zh-fit table of fit-zh, the glossy-zh table of fit-glossy).
#pragma once

#include <cstddef>
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

// The optional u32 array 'vertex_index' of shape [vertices] (empty when the table has
// none); the error, without a prefix, says what V is by `v_is` ("V = rows / n_b = 12").
Result<std::vector<std::uint32_t>> optional_vertex_index(const Table& t, std::size_t vertices, const std::string& v_is);

// The rows of a fit: order, arrays axes [R, N, 3] (unit), coeffs [R, N, n], residual [R]
// and norm [R] (non-negative), optional direct [R, 1 or 4]; values that fit T. The kind,
// the meta and any other array are the caller's to check. Messages start with `prefix`.
template <class T>
Result<ZhFitTable<T>> zh_rows_from_table(const Table& t, const std::string& prefix);

}  // namespace shtool::table_format
