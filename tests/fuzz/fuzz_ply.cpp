// The PLY reader of transform-splats on arbitrary bytes: a file it accepts has every
// value of its vertex element in place (get() reads each, set() writes every float one
// back), and what it then writes parses again to the same values; everything else is
// InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "common/input_error.h"
#include "interop/ply.h"

namespace {

using shtool::interop::PlyElement;
using shtool::interop::PlyFile;
using shtool::interop::PlyType;

bool is_float(PlyType t) { return t == PlyType::float32 || t == PlyType::float64; }

// Equal as the property's type holds them (NaN equals NaN: its payload may be quieted).
bool same(PlyType t, double a, double b) {
  if (t == PlyType::float32) {
    const float fa = static_cast<float>(a), fb = static_cast<float>(b);
    return fa == fb || (std::isnan(fa) && std::isnan(fb));
  }
  return a == b || (std::isnan(a) && std::isnan(b));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::optional<PlyFile> parsed;
  try {
    parsed.emplace(PlyFile::parse(std::string(reinterpret_cast<const char*>(data), size), "fuzz.ply"));
  } catch (const shtool::InputError&) {
    return 0;
  }
  PlyFile& ply = *parsed;
  // A vertex element without properties may claim any count (it holds no bytes): there
  // is nothing to read, and transform-splats refuses it for want of x, y, z.
  const PlyElement* vertex = ply.element("vertex");
  if (!vertex || vertex->properties.empty()) return 0;
  const std::size_t props = vertex->properties.size();
  std::vector<double> values;
  values.reserve(vertex->count * props);
  for (std::size_t i = 0; i < vertex->count; ++i)
    for (std::size_t p = 0; p < props; ++p) values.push_back(ply.get(*vertex, i, p));
  for (std::size_t i = 0; i < vertex->count; ++i)
    for (std::size_t p = 0; p < props; ++p)
      if (is_float(vertex->properties[p].type)) ply.set(*vertex, i, p, values[i * props + p]);
  // What set() made is a PLY file again, with the same values: an InputError here is a
  // finding too (the reader refusing what its own writer wrote).
  std::optional<PlyFile> again;
  try {
    again.emplace(PlyFile::parse(ply.bytes(), "fuzz-again.ply"));
  } catch (const shtool::InputError&) {
    __builtin_trap();
  }
  const PlyElement* v2 = again->element("vertex");
  if (!v2 || v2->count != vertex->count || v2->properties.size() != props) __builtin_trap();
  for (std::size_t i = 0; i < vertex->count; ++i)
    for (std::size_t p = 0; p < props; ++p)
      if (!same(vertex->properties[p].type, values[i * props + p], again->get(*v2, i, p))) __builtin_trap();
  return 0;
}
