// Internal to the runtime's lighting functions: the order N of coefficients laid out as
// [i * channels + c], checked (a precondition: the size must be channels x N^2).
#pragma once

#include <cmath>
#include <cstddef>
#include <string>

#include "precondition.h"
#include "shtool/sh.h"

namespace shtool::detail {

inline int order_of_layout(std::size_t size, int channels, const char* who) {
  if (channels < 1 || size % static_cast<std::size_t>(channels) != 0)
    precondition_failed(std::string(who) + ": the coefficients are not a whole number of channels");
  const int order = static_cast<int>(std::lround(std::sqrt(static_cast<double>(size / channels))));
  if (static_cast<std::size_t>(sh_count(order)) * channels != size || order < 1)
    precondition_failed(std::string(who) + ": " + std::to_string(size) + " coefficients are not channels x N^2");
  return order;
}

}  // namespace shtool::detail
