// Triangle meshes for the fit-zh job: OBJ loading with validation and vertex normals.
//
// Meshes are read in their own frame and turned into shtool's (right-handed, z up) here,
// at the boundary: glTF is +Y up by its specification, so shtool = (X, -Z, Y) of the
// file's (X, Y, Z); OBJ states no frame, so the caller says its up axis (y, Blender's
// importer default, or z: taken as written). Everything past the loader is z-up.
//
// Only vertices referenced by a valid triangle are kept (the Stanford bunny has
// unreferenced vertices; fitting them would produce garbage for points that are not on
// the surface). `source_index` maps each kept vertex back to its 0-based OBJ index.
#pragma once

#include "common/enum_names.h"
#include "common/input_error.h"
#include "common/mesh_frame.h"
#include "shtool/table.h"

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace shtool::fit {

// Malformed or unusable input mesh. The message names the file and the problem.
using MeshError = InputError;  // every mesh problem is bad input

// The part of an OBJ .mtl material a diffuse scene uses: Kd (diffuse reflectance) and
// Ke (emitted radiance), each only when the file states it.
struct ObjMaterial {
  std::string name;
  bool has_kd = false, has_ke = false;
  Eigen::Vector3d kd = Eigen::Vector3d::Zero(), ke = Eigen::Vector3d::Zero();
};

struct Mesh {
  std::vector<Eigen::Vector3d> positions;  // kept vertices only
  std::vector<Eigen::Vector3d> normals;    // unit vertex normals, one per position
  std::vector<std::uint32_t> source_index; // OBJ vertex index of each kept vertex
  std::vector<Eigen::Vector3i> triangles;  // indices into positions
  // Texture coordinates per triangle corner, parallel to `triangles` (a UV seam gives a
  // vertex several), v up with (0, 0) the bottom-left of the image (OBJ's convention;
  // glTF's top-left TEXCOORD_0 is flipped on load). Empty unless every corner of every
  // kept triangle has one.
  std::vector<std::array<Eigen::Vector2d, 3>> uvs;
  // The material of each kept triangle, parallel to `triangles`: a glTF material index or
  // an index into obj_materials; -1 for none. A scene's shading reads it (offline/scene).
  std::vector<int> triangle_material;
  // An OBJ's .mtl materials, when the loader was given the .mtl text.
  std::vector<ObjMaterial> obj_materials;

  std::uint32_t input_crc32 = 0;           // CRC-32 of the file's bytes (provenance)
  // Every file the mesh was read from: the file itself, and a glTF's external buffers and
  // images (a job's outputs are checked against all of them).
  std::vector<std::filesystem::path> files;
  UpAxis up = UpAxis::z;                   // the file's up axis: positions and normals were
                                           // turned from it into shtool's z-up frame
  Eigen::Vector3d front{0, 1, 0};          // the side the model faces (common/mesh_frame.h)

  // Counters for what was skipped while loading (reported as warnings, not errors).
  std::size_t obj_vertices = 0;            // vertices ("v" lines) in the file
  std::size_t unreferenced_vertices = 0;   // vertices no valid triangle uses
  std::size_t degenerate_faces = 0;        // triangles with repeated indices or zero area
  std::size_t polygons_triangulated = 0;   // faces with more than 3 corners (fanned)
  bool normals_from_file = false;          // false: angle-weighted normals computed here
  std::size_t zero_normals = 0;            // vertices whose normal summed to zero (set to +z)

  // Length of the bounding-box diagonal (scale for ray offsets).
  double bbox_diagonal() const;
};

// CRC-32 (table_crc32) of the mesh as loaded: positions, normals (doubles) and triangles
// (int32), little-endian. It names the geometry the rays saw, whatever file format or
// loader version produced it, so bakes of the same mesh can be told apart from others
// (input_crc32 names the file's bytes).
std::uint32_t loaded_mesh_crc32(const Mesh& mesh);

// CRC-32 of the UV layout: every kept triangle's corner UVs (doubles, little-endian, in
// triangle order). A texture-space bake records it, so that its maps are never sampled
// through another mesh's UVs. 0 for a mesh without UVs.
std::uint32_t uv_layout_crc32(const Mesh& mesh);

// The largest coordinate a mesh (or a probe box) may have, in shtool's units: rays are
// traced in single precision, and Embree refuses a ray origin beyond about 1.8e18; 1e15
// leaves room for the offsets and extents added to it. Beyond it is refused as bad input.
inline constexpr double kMaxCoordinate = 1e15;

enum class NormalSource { automatic, file, computed };
const EnumNames<NormalSource>& normal_source_names();  // auto, file, computed

// Loads an OBJ file, whose up axis is `up` (positions and normals turned into shtool's
// frame when it is y). Throws MeshError on: missing/unreadable file, parse failure,
// non-finite coordinates or normals, face indices out of range, no usable triangle.
// Polygons are fan-triangulated here (after the index check, so a bad index can never
// be dereferenced). NormalSource::automatic uses the file's normals when every corner
// of every kept triangle has one, and computed angle-weighted normals otherwise.
Mesh load_obj(const std::filesystem::path& path, NormalSource normals = NormalSource::automatic,
              UpAxis up = UpAxis::y);
// glTF 2.0, binary (.glb) or JSON (.gltf, its external buffers read beside it): every
// triangle primitive (strips and fans converted, points and lines skipped) of the default
// scene, in world space turned into shtool's frame (from +Y up; node matrices or T R S,
// composed down the hierarchy; normals by
// the inverse transpose, winding kept under mirroring transforms), indices of any
// component type, vertices of every primitive instance one after the other (their order
// is source_index). Normals as for OBJ: the file's when every primitive has NORMAL.
// Throws MeshError naming the file and the problem: a buffer that cannot be read, an
// accessor outside its buffer, a sparse or wrongly typed accessor, an index past its
// primitive's vertices, a node cycle, no triangle primitive, a non-finite position.
Mesh load_gltf_bytes(const std::string& bytes, const std::filesystem::path& path,
                     NormalSource normals = NormalSource::automatic);

// The mesh at `path`, glTF (binary magic, or a .gltf / .glb name) or OBJ with up axis
// `up`. A glTF with `up` z is refused (InputError): glTF is +Y up by its specification.
Mesh load_mesh(const std::filesystem::path& path, NormalSource normals = NormalSource::automatic,
               UpAxis up = UpAxis::y);

// A bake of a mesh records the CRC-32 of the mesh as loaded (generator
// parameters.mesh_crc32, loaded_mesh_crc32) and the normals it was loaded with
// (parameters.normals). A command that puts the table's rows back on `mesh` (read from
// `file` with automatic normals) refuses another mesh, even one with as many vertices:
// InputError naming `what` (the table) and `file`. The mesh is read again from `file`
// when the bake computed its normals and the file has its own. A table without the
// record (fit-zh --transfer, deform, older versions) is not checked.
void check_same_mesh(const Table& table, const Mesh& mesh, const std::filesystem::path& file, const std::string& what);
// The --normals a bake's mesh was loaded with: a table's generator parameters.normals,
// or a transfer file's record ("auto", "file", "computed"); auto where none is recorded.
// A command that draws or deforms the bake loads its mesh the same way, so that the
// frames it builds are the bake's (a bake that computed its normals from a file with its
// own would otherwise be drawn with the file's).
NormalSource recorded_normals(const Table& table);
NormalSource recorded_normals(std::string_view name);
// The same check of a recorded checksum and the --normals it was loaded with (a transfer
// file's record).
void check_mesh_crc32(std::uint64_t baked, std::string_view baked_normals, const Mesh& mesh,
                      const std::filesystem::path& file, const std::string& what);

// The same for OBJ text already in memory; `path` names it in messages.
// `mtl_text`, when not empty, is the .mtl the OBJ's usemtl lines name (Mesh::obj_materials,
// Mesh::triangle_material).
// The file named by an OBJ's first "mtllib NAME" line (the rest of the line: names may
// hold spaces); empty when there is none.
std::string obj_mtllib(const std::string& obj_text);

Mesh load_obj_text(const std::string& text, const std::filesystem::path& path,
                   NormalSource normals = NormalSource::automatic, UpAxis up = UpAxis::y,
                   const std::string& mtl_text = {});

// One corner of a triangle: a vertex, the normal and the texture coordinate it has
// there (-1: none).
struct Corner {
  int v, n;
  int t = -1;
};

// The common end of every loader: triangles with a repeated vertex or zero area dropped
// (counted), unreferenced vertices dropped (counted) with the rest kept in file order
// (source_index), normals from the file when every corner has one (averaged per vertex)
// and the source allows, computed angle-weighted otherwise. Throws MeshError when no
// usable triangle is left. `mesh` brings the counters the loader set. Texture
// coordinates (Corner::t indexes `texcoords`, already in Mesh::uvs' convention) are kept
// per corner when every kept corner has one. `materials`, when not empty, is parallel to
// `tris` and kept for the kept triangles (Mesh::triangle_material).
Mesh finish_mesh(Mesh mesh, const std::vector<Eigen::Vector3d>& positions, const std::vector<Eigen::Vector3d>& normals,
                 const std::vector<std::array<Corner, 3>>& tris, const std::filesystem::path& path,
                 NormalSource normal_source, const std::vector<Eigen::Vector2d>& texcoords = {},
                 const std::vector<int>& materials = {});

// Angle-weighted vertex normals (Thürmer and Wüthrich 1998): each incident triangle
// contributes its unit normal times the corner angle, which makes the result independent
// of how a surface is tessellated. Returns the number of vertices left at +z because the
// sum vanished.
std::size_t compute_angle_weighted_normals(Mesh& mesh);

}  // namespace shtool::fit
