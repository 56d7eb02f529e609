// Internal to the runtime: the one body of every table kind's X::load(path), so that
// each kind reads its file the same way and names the file in every message.
#pragma once

#include <filesystem>
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

}  // namespace shtool::detail
