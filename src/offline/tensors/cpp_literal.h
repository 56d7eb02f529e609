// The text of a double in generated C++ source: 17 significant digits, which read back
// as the same double, and the same characters on every run (the generated kernels are
// compared byte for byte with the committed ones).
#pragma once

#include <cstdio>
#include <string>

namespace shtool {

inline std::string cpp_literal(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

}  // namespace shtool
