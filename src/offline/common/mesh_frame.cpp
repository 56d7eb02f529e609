#include "common/mesh_frame.h"

#include <cctype>
#include <filesystem>

#include <nlohmann/json.hpp>

#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/input_file.h"

namespace shtool {

const EnumNames<UpAxis>& up_axis_names() {
  using enum UpAxis;
  static const EnumNames<UpAxis> names = {{"y", y}, {"z", z}};
  return names;
}

const char* up_axis_name(UpAxis up) { return up == UpAxis::y ? "y" : "z"; }

Eigen::Matrix3d to_y_up_matrix() {
  Eigen::Matrix3d q;
  q << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return q;
}

Eigen::Vector3d gltf_front() { return from_y_up(Eigen::Vector3d(0, 0, 1)); }
Eigen::Vector3d obj_front() { return Eigen::Vector3d(0, 1, 0); }

void check_same_up(const Table& table, UpAxis mesh_up, const std::string& what, const std::string& mesh) {
  const nlohmann::json meta = nlohmann::json::parse(table.meta, nullptr, false);
  std::string table_up = "z";
  if (!meta.is_object() || !meta.contains(kMeshUpKey)) {
    // A fit of given vectors that carried no record: nothing says which frame they are in.
    if (recorded_parameters(table).contains("transfer")) return;
  }
  if (meta.is_object() && meta.contains(kMeshUpKey)) {
    const nlohmann::json& up = meta[kMeshUpKey];
    if (!up.is_string() || (up != "y" && up != "z"))
      throw InputError(what + ": meta." + kMeshUpKey + " must be \"y\" or \"z\"");
    table_up = up.get<std::string>();
  }
  if (table_up == up_axis_name(mesh_up)) return;
  // A glTF takes no --up: the advice is then the mesh the table was baked on.
  const std::string ext = lowercase_extension(mesh);
  const std::string advice = ext == ".gltf" || ext == ".glb"
                                 ? "a glTF is always read y-up: give the mesh the bake was made on"
                                 : "give the --up the bake was made with, " + table_up;
  throw InputError(what + " was baked on a mesh read " + table_up + "-up, but " + mesh + " is read " +
                   up_axis_name(mesh_up) + "-up: the lobes would light it from the wrong side (" + advice + ")");
}

}  // namespace shtool
