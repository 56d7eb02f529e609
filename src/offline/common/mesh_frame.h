// Mesh files' frames and shtool's. shtool's frame is right-handed, z up; meshes are
// turned into it when they are read and out of it when they are written. glTF is +Y up
// by its specification; an OBJ states no frame, so its up axis is an option (y, the
// default of Blender's OBJ importer, or z: shtool's own, taken as written).
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/enum_names.h"
#include "shtool/table.h"

namespace shtool {

// The up axis of a mesh file. glTF is always y; an OBJ is what the user says.
enum class UpAxis { y, z };
const EnumNames<UpAxis>& up_axis_names();  // "y", "z"
const char* up_axis_name(UpAxis up);

// shtool's frame from a y-up file's: shtool = (X, -Z, Y), a quarter turn about x (a
// rotation: windings and handedness are kept).
inline Eigen::Vector3d from_y_up(const Eigen::Vector3d& v) { return {v.x(), -v.z(), v.y()}; }
// The inverse, engine = (x, z, -y), for every y-up output (glTF positions, normals, axes).
inline Eigen::Vector3d to_y_up(const Eigen::Vector3d& v) { return {v.x(), v.z(), -v.y()}; }
// The same map as a matrix (to_y_up(v) = to_y_up_matrix() * v), for SH coefficients
// (shtool/orthogonal_map.h).
Eigen::Matrix3d to_y_up_matrix();

// The side a mesh file's model faces, in shtool's frame, by each format's own word:
// glTF's front is +Z (its specification), shtool's -y; an OBJ's is the forward axis of
// Blender's OBJ importer and exporter, -Z of a y-up file and +Y of Blender's (z-up) world,
// shtool's +y either way. render's default view looks at it.
Eigen::Vector3d gltf_front();
Eigen::Vector3d obj_front();

// A table baked on a mesh records the up axis of the file the mesh was read from, as
// meta "mesh_up" ("y" or "z"); its rows (lobe axes, SH vectors) are in shtool's frame of
// that reading. A command that puts such rows back on a mesh reads the mesh the same way
// or refuses: InputError naming `what` (the table) and `mesh` (the file) when the table's
// axis is not `mesh_up`. A table without the record predates it and was baked on a mesh
// taken as written: "z"; unless it fitted given vectors (fit-zh --transfer) that carried
// no record, whose frame nothing states: not checked.
inline constexpr const char* kMeshUpKey = "mesh_up";
void check_same_up(const Table& table, UpAxis mesh_up, const std::string& what, const std::string& mesh);

}  // namespace shtool
