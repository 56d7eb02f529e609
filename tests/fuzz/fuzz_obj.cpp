// The OBJ loader and its mesh validation on arbitrary text: a mesh it returns has
// in-range indices, finite positions and unit normals; everything else is InputError.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/input_error.h"
#include "fit/mesh.h"
#include "mesh_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (shtool::fit::NormalSource normals : {shtool::fit::NormalSource::automatic, shtool::fit::NormalSource::file}) {
    try {
      const shtool::fit::Mesh mesh = shtool::fit::load_obj_text(text, "fuzz.obj", normals);
      trap_unless_mesh_is_whole(mesh);
    } catch (const shtool::InputError&) {
    }
  }
  return 0;
}
