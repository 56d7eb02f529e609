// Pieces of generated source text (the C++ kernels of gen-tensors, the GLSL and HLSL of
// gen-shader), identical on every run: the generated files are compared byte for byte
// with the committed ones.
#pragma once

#include <cstdio>
#include <string>

namespace shtool {

// A double as 17 significant digits, which read back as the same double.
inline std::string cpp_literal(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// prefix followed by the number, "c" and 3 giving "c3". Built by append: GCC 12 warns,
// wrongly, about "literal" + std::string at -O3 (-Wrestrict, -Wstringop-overflow).
inline std::string indexed(const char* prefix, int j) { return std::string(prefix).append(std::to_string(j)); }

}  // namespace shtool
