// Internal to the runtime: the one body of every table kind's X::load(path), so that
// each kind reads its file the same way and names the file in every message.
#pragma once

#include <filesystem>
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

// The first checks of a from_table: the kind, then the order within lo..hi; the problem
// (without the kind's prefix) or nothing.
inline std::optional<std::string> kind_and_order_problem(const Table& t, std::string_view kind, int lo, int hi) {
  if (t.kind != kind) return "wrong kind '" + t.kind + "'";
  if (t.order < lo || t.order > hi)
    return "order " + std::to_string(t.order) + " is outside " + std::to_string(lo) + ".." + std::to_string(hi);
  return std::nullopt;
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
