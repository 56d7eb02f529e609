// The offline jobs' enum options are lists of (name, value) pairs shared by the CLI's
// parsing and the generator records: the name of a value, found once here.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace shtool {

// An enum option's accepted names, each with its value, in the order --help lists them.
template <class E>
using EnumNames = std::vector<std::pair<std::string, E>>;

template <class E>
const std::string& name_of(E value, const EnumNames<E>& names) {
  for (const auto& n : names)
    if (n.second == value) return n.first;
  static const std::string unknown = "?";
  return unknown;
}

}  // namespace shtool
