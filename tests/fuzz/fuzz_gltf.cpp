// The glTF loader (tinygltf, then shtool's accessor, index and node checks) on arbitrary
// bytes, binary (.glb) or JSON (.gltf: whatever does not start with the GLB magic), under
// each normal source: a mesh it returns has in-range indices, finite positions, unit
// normals and a UV per corner of every triangle or none; everything else is InputError.
// The file is named inside a folder that does not exist, so external buffers and images
// never resolve (only data: URIs and a GLB's BIN chunk are read).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/input_error.h"
#include "fit/mesh.h"
#include "mesh_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  for (shtool::fit::NormalSource normals :
       {shtool::fit::NormalSource::automatic, shtool::fit::NormalSource::file, shtool::fit::NormalSource::computed}) {
    try {
      const shtool::fit::Mesh mesh =
          shtool::fit::load_gltf_bytes(bytes, "/nonexistent-shtool-fuzz/fuzz.gltf", normals);
      const std::size_t n = mesh.positions.size();
      if (n == 0 || mesh.triangles.empty()) __builtin_trap();
      trap_unless_mesh_is_whole(mesh);
      if (!mesh.uvs.empty()) {
        if (mesh.uvs.size() != mesh.triangles.size()) __builtin_trap();
        for (const auto& corners : mesh.uvs)
          for (const auto& uv : corners)
            if (!uv.allFinite()) __builtin_trap();
      }
    } catch (const shtool::InputError&) {
    }
  }
  return 0;
}
