// The OBJ loader and its mesh validation on arbitrary text: a mesh it returns has
// in-range indices, finite positions and unit normals; everything else is InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/input_error.h"
#include "fit/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (shtool::fit::NormalSource normals : {shtool::fit::NormalSource::automatic, shtool::fit::NormalSource::file}) {
    try {
      const shtool::fit::Mesh mesh = shtool::fit::load_obj_text(text, "fuzz.obj", normals);
      const std::size_t n = mesh.positions.size();
      if (mesh.normals.size() != n || mesh.source_index.size() != n) __builtin_trap();
      for (const auto& t : mesh.triangles)
        for (int c = 0; c < 3; ++c)
          if (t[c] < 0 || static_cast<std::size_t>(t[c]) >= n) __builtin_trap();
      for (std::size_t i = 0; i < n; ++i) {
        if (!mesh.positions[i].allFinite()) __builtin_trap();
        if (!(std::abs(mesh.normals[i].norm() - 1.0) < 1e-6)) __builtin_trap();
      }
    } catch (const shtool::InputError&) {
    }
  }
  return 0;
}
