#include "fit/mesh.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>
#include <tiny_obj_loader.h>

#include "common/generator_record.h"
#include "common/input_error.h"
#include "common/input_file.h"
#include "shtool/table.h"

namespace shtool::fit {
namespace {

// tinyobjloader reads a coordinate it cannot parse ("nan", "inf", hexadecimal "0x10") as
// 0 without a warning, and a face index beyond int as a wrapped value, so both would pass
// silently. Scan the text first: "v" and "vn" coordinates (three) and "vt" coordinates
// (one to three) must be decimal numbers and finite, "f" lines name at least three
// vertices whose indices fit an int. Lines
// end at LF, CR or CR LF, as tinyobjloader splits them.
void check_obj_text(const std::filesystem::path& path, const std::string& text) {
  std::size_t number = 0, pos = 0;
  while (pos < text.size()) {
    std::size_t end = text.find_first_of("\r\n", pos);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(pos, end - pos);
    pos = end + 1;
    if (end < text.size() && text[end] == '\r' && pos < text.size() && text[pos] == '\n') ++pos;
    ++number;
    const std::size_t p = line.find_first_not_of(" \t");
    if (p == std::string::npos) continue;
    const bool is_v = line.compare(p, 2, "v ") == 0 || line.compare(p, 2, "v\t") == 0;
    const bool is_vn = line.compare(p, 3, "vn ") == 0 || line.compare(p, 3, "vn\t") == 0;
    const bool is_vt = line.compare(p, 3, "vt ") == 0 || line.compare(p, 3, "vt\t") == 0;
    const bool is_f = line.compare(p, 2, "f ") == 0 || line.compare(p, 2, "f\t") == 0;
    const std::string shown = line.size() > 80 ? line.substr(0, 80) + "..." : line;
    if (is_v || is_vn || is_vt) {
      const char* s = line.c_str() + p + (is_v ? 1 : 2);
      for (int c = 0; c < 3; ++c) {
        if (is_vt && c > 0 && s[std::strspn(s, " \t")] == '\0') break;  // v and w are optional
        char* stop = nullptr;
        const double value = std::strtod(s, &stop);
        if (stop == s || std::find_if(static_cast<const char*>(s), static_cast<const char*>(stop), [](char ch) {
                           return ch == 'x' || ch == 'X';
                         }) != stop)
          fail_input(path, "line " + std::to_string(number) + ": missing or unreadable coordinate in '" + shown + "'");
        // Stored as float: a double beyond float's range would become infinite.
        if (!std::isfinite(value) || std::abs(value) > std::numeric_limits<float>::max())
          fail_input(path, "line " + std::to_string(number) + ": non-finite coordinate (or beyond float range) in '" +
                         shown + "'");
        s = stop;
      }
    } else if (is_f) {
      // tinyobjloader drops a face of fewer than three vertices without a word: the last
      // line of a file cut short, most often.
      int corners = 0;
      for (std::istringstream words(line.substr(p + 1, line.find('#', p) - (p + 1)));; ++corners) {
        std::string word;
        if (!(words >> word)) break;
      }
      if (corners < 3)
        fail_input(path, "line " + std::to_string(number) + ": a face needs at least 3 vertices, '" + shown + "' has " +
                             std::to_string(corners) + " (a file cut short?)");
      for (const char* s = line.c_str() + p + 1; *s;) {
        if (*s == '-' || *s == '+' || (*s >= '0' && *s <= '9')) {
          char* stop = nullptr;
          const long long value = std::strtoll(s, &stop, 10);
          if (stop == s) {
            ++s;
            continue;
          }
          if (value > std::numeric_limits<int>::max() || value < -std::numeric_limits<int>::max())
            fail_input(path, "line " + std::to_string(number) + ": face index " + std::string(s, static_cast<const char*>(stop)) +
                           " is out of range in '" + shown + "'");
          s = stop;
        } else {
          ++s;
        }
      }
    }
  }
}

// Whether the .mtl block of material `name` has a `key` line (Kd, Ke).
// The colour that material `name` of the .mtl text states (`key r [g b]`), read from the
// text as the OBJ's coordinates are: tinyobjloader reads "nan" or an unreadable number as
// 0. One number stands for all three (the MTL format's rule). nullopt when the material
// does not state it; InputError naming the material and the line otherwise.
std::optional<Eigen::Vector3d> mtl_colour(const std::string& mtl, const std::string& name, const std::string& key,
                                          const std::filesystem::path& path) {
  std::istringstream in(mtl);
  std::string line;
  bool inside = false;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream words(line);
    std::string first;
    if (!(words >> first)) continue;
    if (first == "newmtl") {
      std::string n;
      std::getline(words >> std::ws, n);
      while (!n.empty() && (n.back() == '\r' || n.back() == ' ' || n.back() == '\t')) n.pop_back();
      inside = n == name;
      continue;
    }
    if (!inside || first != key) continue;
    const std::string where = "material '" + name + "' (its library's line " + std::to_string(number) + "): " + key;
    std::vector<double> values;
    for (std::string word; words >> word;) {
      char* stop = nullptr;
      const double v = std::strtod(word.c_str(), &stop);
      if (stop != word.c_str() + word.size() || word.find_first_of("xX") != std::string::npos)
        fail_input(path, where + " '" + word + "' is not a number (shtool reads r g b or one value)");
      if (!std::isfinite(v) || std::abs(v) > std::numeric_limits<float>::max())
        fail_input(path, where + " " + word + " is not a finite number (or is beyond float range)");
      values.push_back(v);
    }
    if (values.size() != 1 && values.size() != 3)
      fail_input(path, where + " has " + std::to_string(values.size()) + " numbers (r g b, or one for all three)");
    return values.size() == 1 ? Eigen::Vector3d::Constant(values[0]) : Eigen::Vector3d(values[0], values[1], values[2]);
  }
  return std::nullopt;
}

}  // namespace

std::uint32_t loaded_mesh_crc32(const Mesh& mesh) {
  std::uint32_t crc = 0;
  std::byte buf[3 * sizeof(double)];
  auto add_vectors = [&](const std::vector<Eigen::Vector3d>& vs) {
    for (const Eigen::Vector3d& v : vs) {
      for (int c = 0; c < 3; ++c) table_detail::store_le(v[c], buf + c * sizeof(double));
      crc = table_crc32(std::span<const std::byte>(buf, 3 * sizeof(double)), crc);
    }
  };
  add_vectors(mesh.positions);
  add_vectors(mesh.normals);
  for (const Eigen::Vector3i& t : mesh.triangles) {
    for (int c = 0; c < 3; ++c) table_detail::store_le(static_cast<std::int32_t>(t[c]), buf + c * sizeof(std::int32_t));
    crc = table_crc32(std::span<const std::byte>(buf, 3 * sizeof(std::int32_t)), crc);
  }
  return crc;
}

std::uint32_t uv_layout_crc32(const Mesh& mesh) {
  std::uint32_t crc = 0;
  std::byte buf[6 * sizeof(double)];
  for (const std::array<Eigen::Vector2d, 3>& corners : mesh.uvs) {
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 2; ++k) table_detail::store_le(corners[c][k], buf + (c * 2 + k) * sizeof(double));
    crc = table_crc32(std::span<const std::byte>(buf, sizeof buf), crc);
  }
  return crc;
}

double Mesh::bbox_diagonal() const {
  if (positions.empty()) return 0.0;
  Eigen::Vector3d lo = positions[0], hi = positions[0];
  for (const Eigen::Vector3d& p : positions) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  return (hi - lo).norm();
}

std::size_t compute_angle_weighted_normals(Mesh& mesh) {
  std::vector<Eigen::Vector3d> sum(mesh.positions.size(), Eigen::Vector3d::Zero());
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d face = (mesh.positions[t[1]] - mesh.positions[t[0]])
                                     .cross(mesh.positions[t[2]] - mesh.positions[t[0]]);
    const double len = face.norm();
    if (!(len > 0)) continue;
    const Eigen::Vector3d n = face / len;
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d a = mesh.positions[t[(c + 1) % 3]] - mesh.positions[t[c]];
      const Eigen::Vector3d b = mesh.positions[t[(c + 2) % 3]] - mesh.positions[t[c]];
      // atan2 of |a x b| and a.b: accurate for small and near-pi angles alike.
      const double angle = std::atan2(a.cross(b).norm(), a.dot(b));
      sum[t[c]] += angle * n;
    }
  }
  std::size_t zero = 0;
  mesh.normals.resize(mesh.positions.size());
  for (std::size_t i = 0; i < sum.size(); ++i) {
    const double len = sum[i].norm();
    if (len > 0 && std::isfinite(len)) {
      mesh.normals[i] = sum[i] / len;
    } else {
      mesh.normals[i] = Eigen::Vector3d::UnitZ();
      ++zero;
    }
  }
  return zero;
}

Mesh finish_mesh(Mesh mesh, const std::vector<Eigen::Vector3d>& positions, const std::vector<Eigen::Vector3d>& normals,
                 const std::vector<std::array<Corner, 3>>& tris, const std::filesystem::path& path,
                 NormalSource normal_source, const std::vector<Eigen::Vector2d>& texcoords,
                 const std::vector<int>& materials) {
  const std::size_t nv = positions.size(), nn = normals.size();
  auto position = [&](int v) { return positions[v]; };
  // Every vertex a face uses is within reach first: far out, a small triangle's edges
  // round to zero and it would pass for degenerate.
  for (const auto& t : tris)
    for (const Corner& c : t)
      if (positions[c.v].cwiseAbs().maxCoeff() > kMaxCoordinate) {
        std::ostringstream where;
        where << "vertex " << c.v + 1 << " (" << positions[c.v].x() << ", " << positions[c.v].y() << ", "
              << positions[c.v].z() << ") lies beyond +-1e15, which single-precision ray tracing cannot reach";
        fail_input(path, where.str());
      }
  // Degenerate: repeated index or zero area. Zero area is tested exactly (cross product
  // of edges equal to zero): a sliver with tiny but non-zero area still has a normal.
  std::vector<std::array<Corner, 3>> kept;
  kept.reserve(tris.size());
  for (std::size_t f = 0; f < tris.size(); ++f) {
    const auto& t = tris[f];
    const bool repeated = t[0].v == t[1].v || t[1].v == t[2].v || t[0].v == t[2].v;
    const Eigen::Vector3d p0 = position(t[0].v);
    const double area2 = (position(t[1].v) - p0).cross(position(t[2].v) - p0).norm();
    if (repeated || !(area2 > 0)) {
      ++mesh.degenerate_faces;
      continue;
    }
    kept.push_back(t);
    if (!materials.empty()) mesh.triangle_material.push_back(materials[f]);
  }
  if (kept.empty())
    fail_input(path, tris.empty() ? "no faces (need at least one triangle)"
                            : "no usable triangle (all " + std::to_string(tris.size()) + " are degenerate)");

  // Keep referenced vertices only, in file order (so output order follows the file).
  std::vector<int> remap(nv, -1);
  for (const auto& t : kept)
    for (const Corner& c : t) remap[c.v] = 0;
  for (std::size_t v = 0; v < nv; ++v) {
    if (remap[v] < 0) {
      ++mesh.unreferenced_vertices;
      continue;
    }
    remap[v] = static_cast<int>(mesh.positions.size());
    mesh.positions.push_back(position(static_cast<int>(v)));
    mesh.source_index.push_back(static_cast<std::uint32_t>(v));
  }
  for (const auto& t : kept) mesh.triangles.emplace_back(remap[t[0].v], remap[t[1].v], remap[t[2].v]);
  bool all_have_uvs = !texcoords.empty();
  for (const auto& t : kept)
    for (const Corner& c : t) all_have_uvs = all_have_uvs && c.t >= 0;
  if (all_have_uvs) {
    mesh.uvs.reserve(kept.size());
    for (const auto& t : kept) mesh.uvs.push_back({texcoords[t[0].t], texcoords[t[1].t], texcoords[t[2].t]});
  }

  bool all_have_normals = nn > 0;
  for (const auto& t : kept)
    for (const Corner& c : t) all_have_normals = all_have_normals && c.n >= 0;
  if (normal_source == NormalSource::file && !all_have_normals)
    fail_input(path, "--normals file: not every face corner has a normal in the file");
  if (normal_source != NormalSource::computed && all_have_normals) {
    // A vertex may carry different normals on different faces (a crease); average them.
    std::vector<Eigen::Vector3d> sum(mesh.positions.size(), Eigen::Vector3d::Zero());
    for (const auto& t : kept)
      for (const Corner& c : t) {
        const Eigen::Vector3d n = normals[c.n];
        const double len = n.norm();
        if (len > 0) sum[remap[c.v]] += n / len;
      }
    mesh.normals.resize(mesh.positions.size());
    for (std::size_t i = 0; i < sum.size(); ++i) {
      const double len = sum[i].norm();
      if (len > 0) {
        mesh.normals[i] = sum[i] / len;
      } else {
        mesh.normals[i] = Eigen::Vector3d::UnitZ();
        ++mesh.zero_normals;
      }
    }
    mesh.normals_from_file = true;
  } else {
    mesh.zero_normals = compute_angle_weighted_normals(mesh);
  }
  return mesh;
}

Mesh load_obj(const std::filesystem::path& path, NormalSource normal_source, UpAxis up) {
  // Read once: the same bytes are checked, parsed and hashed.
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail_input(path, "no such file");
  if (std::filesystem::is_directory(path, ec)) fail_input(path, "is a directory, not an OBJ file");
  return load_obj_text(read_input_file(path, "mesh"), path, normal_source, up);
}

Mesh load_mesh(const std::filesystem::path& path, NormalSource normal_source, UpAxis up) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail_input(path, "no such file");
  if (std::filesystem::is_directory(path, ec)) fail_input(path, "is a directory, not a mesh file");
  std::string bytes = read_input_file(path, "mesh");
  const std::string ext = lowercase_extension(path);
  if ((bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0) || ext == ".gltf" || ext == ".glb") {
    if (up != UpAxis::y) fail_input(path, "--up z: glTF is +Y up by its specification (--up applies to OBJ files)");
    return load_gltf_bytes(bytes, path, normal_source);
  }
  return load_obj_text(bytes, path, normal_source, up);
}

void check_mesh_crc32(std::uint64_t baked, std::string_view baked_normals, const Mesh& mesh,
                      const std::filesystem::path& file, const std::string& what) {
  std::uint32_t loaded = loaded_mesh_crc32(mesh);
  // Normals are part of the checksum: a bake that computed them from a file that has its
  // own saw other normals than the automatic loading here.
  if (loaded != baked && mesh.normals_from_file && baked_normals == "computed")
    loaded = loaded_mesh_crc32(load_mesh(file, NormalSource::computed, mesh.up));
  if (loaded == baked) return;
  throw InputError(what + " was baked on another mesh: it records mesh_crc32 " + std::to_string(baked) + ", and " +
                   file.string() + " loads as " + std::to_string(loaded) +
                   " (positions, normals and triangles in shtool's frame); give the mesh it was baked on");
}

NormalSource recorded_normals(std::string_view name) {
  for (const auto& [text, source] : normal_source_names())
    if (text == name) return source;
  return NormalSource::automatic;
}

NormalSource recorded_normals(const Table& table) {
  const nlohmann::json params = recorded_parameters(table);
  return params.contains("normals") && params["normals"].is_string()
             ? recorded_normals(params["normals"].get<std::string>())
             : NormalSource::automatic;
}

void check_same_mesh(const Table& table, const Mesh& mesh, const std::filesystem::path& file, const std::string& what) {
  const nlohmann::json params = recorded_parameters(table);
  if (!params.contains("mesh_crc32")) return;
  if (!params["mesh_crc32"].is_number_unsigned())
    throw InputError(what + ": generator.parameters.mesh_crc32 must be an unsigned integer");
  const std::string normals =
      params.contains("normals") && params["normals"].is_string() ? params["normals"].get<std::string>() : "";
  check_mesh_crc32(params["mesh_crc32"].get<std::uint64_t>(), normals, mesh, file, what);
}

std::string obj_mtllib(const std::string& obj_text) {
  std::istringstream in(obj_text);
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string first;
    if (!(words >> first) || first != "mtllib") continue;
    std::string name;
    std::getline(words >> std::ws, name);
    while (!name.empty() && (name.back() == '\r' || name.back() == ' ' || name.back() == '\t')) name.pop_back();
    return name;
  }
  return {};
}

Mesh load_obj_text(const std::string& text, const std::filesystem::path& path, NormalSource normal_source,
                   UpAxis up, const std::string& mtl_text) {
  // Compressed files are not unpacked here (and would read as garbled OBJ lines): say so.
  struct Magic {
    std::string_view bytes, format;
  };
  for (const Magic& m : {Magic{"\x1f\x8b", "gzip"}, Magic{"\x28\xb5\x2f\xfd", "zstd"},
                         Magic{"\xfd"
                               "7zXZ",
                               "xz"},
                         Magic{"BZh", "bzip2"}, Magic{"PK\x03\x04", "zip"}})
    if (std::string_view(text).substr(0, m.bytes.size()) == m.bytes)
      fail_input(path, "is " + std::string(m.format) +
                           "-compressed; shtool reads OBJ and glTF (.gltf, .glb) files: decompress it first");
  check_obj_text(path, text);

  tinyobj::ObjReaderConfig config;
  // Triangulated here instead, after the index check: tinyobjloader's own triangulation
  // reads vertex positions through unchecked indices.
  config.triangulate = false;
  config.vertex_color = false;
  tinyobj::ObjReader reader;
  if (!reader.ParseFromString(text, mtl_text, config)) {
    std::string e = reader.Error();
    while (!e.empty() && (e.back() == '\n' || e.back() == '.')) e.pop_back();
    fail_input(path, "cannot parse OBJ" + (e.empty() ? std::string() : ": " + e));
  }
  const tinyobj::attrib_t& attrib = reader.GetAttrib();
  const std::size_t nv = attrib.vertices.size() / 3;
  const std::size_t nn = attrib.normals.size() / 3;
  const std::size_t nt = attrib.texcoords.size() / 2;

  // What tinyobjloader stored, whatever the text said.
  for (std::size_t i = 0; i < attrib.vertices.size(); ++i)
    if (!std::isfinite(attrib.vertices[i])) fail_input(path, "vertex " + std::to_string(i / 3 + 1) + " is not finite");
  for (std::size_t i = 0; i < attrib.normals.size(); ++i)
    if (!std::isfinite(attrib.normals[i])) fail_input(path, "normal " + std::to_string(i / 3 + 1) + " is not finite");
  for (std::size_t i = 0; i < attrib.texcoords.size(); ++i)
    if (!std::isfinite(attrib.texcoords[i]))
      fail_input(path, "texture coordinate " + std::to_string(i / 2 + 1) + " is not finite");

  Mesh mesh;
  mesh.input_crc32 = input_crc32(text);
  mesh.files.push_back(path);
  // Its material library is part of the asset (bake-probes reads it): no output replaces it.
  if (const std::string lib = obj_mtllib(text); !lib.empty()) mesh.files.push_back(path.parent_path() / lib);
  mesh.obj_vertices = nv;
  if (nv == 0) fail_input(path, "no vertices");

  // Corners of every face, checked, then fanned: (c0, ci, ci+1).
  std::vector<std::array<Corner, 3>> tris;
  std::vector<int> tri_materials;
  const bool with_materials = !mtl_text.empty();
  if (with_materials)
    for (const tinyobj::material_t& m : reader.GetMaterials()) {
      ObjMaterial om;
      om.name = m.name;
      // Only stated colours count (tinyobjloader leaves absent ones at its defaults).
      const std::optional<Eigen::Vector3d> kd = mtl_colour(mtl_text, m.name, "Kd", path);
      const std::optional<Eigen::Vector3d> ke = mtl_colour(mtl_text, m.name, "Ke", path);
      om.has_kd = kd.has_value(), om.has_ke = ke.has_value();
      om.kd = kd.value_or(Eigen::Vector3d::Zero());
      om.ke = ke.value_or(Eigen::Vector3d::Zero());
      mesh.obj_materials.push_back(std::move(om));
    }
  std::size_t face_number = 0;
  for (const tinyobj::shape_t& shape : reader.GetShapes()) {
    const tinyobj::mesh_t& m = shape.mesh;
    std::size_t offset = 0;
    for (std::size_t f = 0; f < m.num_face_vertices.size(); ++f, ++face_number) {
      const std::size_t count = m.num_face_vertices[f];
      std::vector<Corner> corners;
      for (std::size_t k = 0; k < count; ++k) {
        const tinyobj::index_t& idx = m.indices[offset + k];
        if (idx.vertex_index < 0 || static_cast<std::size_t>(idx.vertex_index) >= nv)
          fail_input(path, "face " + std::to_string(face_number + 1) + " refers to vertex " +
                         std::to_string(static_cast<long long>(idx.vertex_index) + 1) +
                         ", but the file has " + std::to_string(nv) + " vertices");
        if (idx.normal_index >= 0 && static_cast<std::size_t>(idx.normal_index) >= nn)
          fail_input(path, "face " + std::to_string(face_number + 1) + " refers to normal " +
                         std::to_string(static_cast<long long>(idx.normal_index) + 1) +
                         ", but the file has " + std::to_string(nn) + " normals");
        if (idx.texcoord_index >= 0 && static_cast<std::size_t>(idx.texcoord_index) >= nt)
          fail_input(path, "face " + std::to_string(face_number + 1) + " refers to texture coordinate " +
                         std::to_string(static_cast<long long>(idx.texcoord_index) + 1) +
                         ", but the file has " + std::to_string(nt) + " of them");
        corners.push_back({idx.vertex_index, idx.normal_index, idx.texcoord_index});
      }
      offset += count;
      if (count < 3) {
        ++mesh.degenerate_faces;
        continue;
      }
      if (count > 3) ++mesh.polygons_triangulated;
      const int material = f < m.material_ids.size() && m.material_ids[f] >= 0 &&
                                   static_cast<std::size_t>(m.material_ids[f]) < mesh.obj_materials.size()
                               ? m.material_ids[f]
                               : -1;
      for (std::size_t k = 1; k + 1 < count; ++k) {
        tris.push_back({corners[0], corners[k], corners[k + 1]});
        if (with_materials) tri_materials.push_back(material);
      }
    }
  }

  std::vector<Eigen::Vector3d> positions(nv), normals(nn);
  for (std::size_t v = 0; v < nv; ++v)
    positions[v] = Eigen::Vector3d(attrib.vertices[3 * v], attrib.vertices[3 * v + 1], attrib.vertices[3 * v + 2]);
  for (std::size_t k = 0; k < nn; ++k)
    normals[k] = Eigen::Vector3d(attrib.normals[3 * k], attrib.normals[3 * k + 1], attrib.normals[3 * k + 2]);
  std::vector<Eigen::Vector2d> texcoords(nt);
  for (std::size_t k = 0; k < nt; ++k) texcoords[k] = Eigen::Vector2d(attrib.texcoords[2 * k], attrib.texcoords[2 * k + 1]);
  mesh.up = up;
  mesh.front = obj_front();
  if (up == UpAxis::y) {
    for (Eigen::Vector3d& p : positions) p = from_y_up(p);
    for (Eigen::Vector3d& n : normals) n = from_y_up(n);
  }
  mesh = finish_mesh(std::move(mesh), positions, normals, tris, path, normal_source, texcoords, tri_materials);
  // tinyobjloader stores coordinates as float: far from the origin for its size, a mesh's
  // shape is rounded coarser than the shadow rays' offset off the surface (1e-4 of its
  // box's diagonal) and it shadows itself in speckles. Refused, as glTF (whose node
  // translations apply in double) is not.
  double reach = 0;
  for (const Eigen::Vector3d& p : mesh.positions) reach = std::max(reach, p.cwiseAbs().maxCoeff());
  const double spacing = reach * std::numeric_limits<float>::epsilon(), diagonal = mesh.bbox_diagonal();
  if (spacing > 1e-4 * diagonal) {
    std::ostringstream why;
    why << "its coordinates reach " << reach << ", where an OBJ's single precision (as tinyobjloader reads it) spaces "
        << "them " << spacing << " apart: more than a ten-thousandth of the mesh's size (" << diagonal
        << "), which breaks its shadows; move it near the origin (or export glTF: a node's translation is applied in "
           "double)";
    fail_input(path, why.str());
  }
  return mesh;
}


const EnumNames<NormalSource>& normal_source_names() {
  using enum NormalSource;
  static const EnumNames<NormalSource> names = {{"auto", automatic}, {"file", file}, {"computed", computed}};
  return names;
}

}  // namespace shtool::fit
