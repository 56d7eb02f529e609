// Internal to the runtime: the one body of every table kind's X::load(path), so that
// each kind reads its file the same way and names the file in every message.
#pragma once

#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <string_view>

#include "shtool/table.h"

namespace shtool::detail {

// read_table with the kind's expectation (schema major 1), then X::from_table.
template <class X>
Result<X> load_kind(const std::filesystem::path& path, std::string_view kind) {
  Result<Table> table = read_table(path, TableExpectation{std::string(kind), 1, 0});
  if (!table) return table.error();
  Result<X> x = X::from_table(table.value());
  if (!x) return Error{path.string() + ": " + x.error().message};
  return x;
}

// An array whose bytes are not what its dtype and shape need, or nothing. read_table never
// returns one; a Table built in memory (TableArray::from does not check) can hold one, and
// a loader that believed the shape would read past the data.
inline std::optional<std::string> array_sizes_problem(const Table& t) {
  for (const TableArray& a : t.arrays) {
    std::size_t n = dtype_size(a.dtype);
    for (const std::int64_t d : a.shape) {
      if (d < 0 || (d > 0 && n > std::numeric_limits<std::size_t>::max() / static_cast<std::size_t>(d)))
        return "array '" + a.name + "' has a negative or overflowing shape";
      n *= static_cast<std::size_t>(d);
    }
    if (n != a.data.size())
      return "array '" + a.name + "' holds " + std::to_string(a.data.size()) + " bytes, its dtype and shape need " +
             std::to_string(n);
  }
  return std::nullopt;
}

// The first checks of a from_table: the kind, then the order within lo..hi, then every
// array's size (array_sizes_problem); the problem (without the kind's prefix) or nothing.
inline std::optional<std::string> kind_and_order_problem(const Table& t, std::string_view kind, int lo, int hi) {
  if (t.kind != kind) return "wrong kind '" + t.kind + "'";
  if (t.order < lo || t.order > hi)
    return "order " + std::to_string(t.order) + " is outside " + std::to_string(lo) + ".." + std::to_string(hi);
  return array_sizes_problem(t);
}

// A stored value a loader keeps in T with room for the sums it later takes part in: at
// most max(T) / 2^64, so that sums of products with SH values and a caller's data of
// ordinary size stay finite. A finite value beyond it (1e300 in a double table, 1e30 for
// float) is a corrupted table, and taking it would turn shading into infinities.
template <class T>
bool within_headroom(double v) {
  return std::abs(v) <= static_cast<double>(std::numeric_limits<T>::max()) * 0x1p-64;
}

}  // namespace shtool::detail

// X<T>::load for a kind whose loader is templated on the precision, then X's float and
// double instantiations: the tail of each such kind's source file.
#define SHTOOL_LOAD_KIND_FLOAT_AND_DOUBLE(X, kind)             \
  template <class T>                                           \
  Result<X<T>> X<T>::load(const std::filesystem::path& path) { \
    return detail::load_kind<X<T>>(path, kind);                \
  }                                                            \
  template struct X<float>;                                    \
  template struct X<double>;
