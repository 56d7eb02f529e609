// glTF 2.0 meshes through tinygltf: every triangle primitive of the default scene in world
// space. tinygltf parses the file and resolves buffers; every accessor read here is
// checked against its buffer view and buffer, since tinygltf leaves that to its user.
#include <tiny_gltf.h>

#include <array>
#include <cmath>
#include <cstring>
#include <cstdint>
#include <exception>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "common/input_error.h"
#include "common/input_file.h"
#include "fit/gltf_model.h"
#include "fit/mesh.h"
#include "io/table_format.h"

namespace shtool::fit {
namespace {

// Far below the int range of vertex numbers, and beyond any mesh a bake runs on.
constexpr std::size_t kMaxVertices = std::size_t(1) << 28;

// The JSON of a glTF: the whole text, or a GLB's first chunk (header: magic, version,
// length; chunk: length, type, data), clipped to the bytes there are.
std::string_view json_text_of(const std::string& bytes, bool binary) {
  if (!binary) return bytes;
  if (bytes.size() < 20) return {};
  std::uint32_t length = 0;
  std::memcpy(&length, bytes.data() + 12, 4);
  return std::string_view(bytes).substr(20, length);
}

// Textures play no part in a mesh's transfer: images are neither decoded nor required.
bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int,
                void*) {
  return true;
}

// A scene decodes its textures itself (lighting::decode_image: the project's one decoder,
// with the exact sRGB curve): the encoded bytes are kept as they are.
bool keep_image_bytes(tinygltf::Image* image, const int, std::string*, std::string*, int, int,
                      const unsigned char* bytes, int size, void*) {
  image->image.assign(bytes, bytes + size);
  image->width = image->height = -1;
  return true;
}


// Every element of accessor `index` (see accessor_view), each made by element(view, i).
template <class Out, class Element>
std::vector<Out> read_accessor(const tinygltf::Model& model, int index, int type,
                               const std::vector<int>& component_types, const std::string& what,
                               const std::filesystem::path& path, Element element) {
  const AccessorView v = accessor_view(model, index, type, component_types, what, path);
  std::vector<Out> out(v.count);
  for (std::size_t i = 0; i < v.count; ++i) out[i] = element(v, i);
  return out;
}

std::vector<Eigen::Vector3d> read_vec3(const tinygltf::Model& model, int index, const std::string& what,
                                       const std::filesystem::path& path) {
  return read_accessor<Eigen::Vector3d>(model, index, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT}, what, path,
                                        [](const AccessorView& v, std::size_t i) {
                                          return Eigen::Vector3d(v.component<float>(i, 0), v.component<float>(i, 1),
                                                                 v.component<float>(i, 2));
                                        });
}

// TEXCOORD_0: float, or normalised unsigned byte / short (glTF 2.0, 3.7.2.1), returned
// with v flipped into Mesh::uvs' bottom-left convention.
std::vector<Eigen::Vector2d> read_texcoords(const tinygltf::Model& model, int index, const std::filesystem::path& path) {
  return read_accessor<Eigen::Vector2d>(
      model, index, TINYGLTF_TYPE_VEC2,
      {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
      "TEXCOORD_0", path, [&path](const AccessorView& v, std::size_t i) {
        const double uv[2] = {v.number(i, 0, true), v.number(i, 1, true)};
        if (!std::isfinite(uv[0]) || !std::isfinite(uv[1]))
          fail_input(path, "TEXCOORD_0 of vertex " + std::to_string(i) + " is not finite");
        return Eigen::Vector2d(uv[0], 1.0 - uv[1]);
      });
}

std::vector<std::uint32_t> read_indices(const tinygltf::Model& model, int index, const std::filesystem::path& path) {
  return read_accessor<std::uint32_t>(
      model, index, TINYGLTF_TYPE_SCALAR,
      {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
       TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
      "indices", path,
      // Every u32 is exact in a double.
      [](const AccessorView& v, std::size_t i) { return static_cast<std::uint32_t>(v.number(i, 0, false)); });
}

// The node's local transform: its matrix, or T R S. Arrays of another length, and a
// rotation that is not a unit quaternion (glTF requires one; within 1e-3, which any
// printed quaternion meets), are refused, not read as the identity or normalised.
Eigen::Matrix4d local_transform(const tinygltf::Node& node, int index, const std::filesystem::path& path) {
  const std::string what = "node " + std::to_string(index) + "'s ";
  auto sized = [&](const std::vector<double>& v, std::size_t n, const char* name) {
    if (!v.empty() && v.size() != n)
      fail_input(path,
                 what + name + " has " + std::to_string(v.size()) + " numbers (" + std::to_string(n) + " expected)");
    return !v.empty();
  };
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (sized(node.matrix, 16, "matrix")) {
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = node.matrix[c * 4 + r];  // column-major
    return m;
  }
  Eigen::Matrix4d t = Eigen::Matrix4d::Identity(), rot = Eigen::Matrix4d::Identity(),
                  s = Eigen::Matrix4d::Identity();
  if (sized(node.translation, 3, "translation"))
    t.block<3, 1>(0, 3) = Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]);
  if (sized(node.rotation, 4, "rotation")) {  // glTF stores x, y, z, w
    const Eigen::Quaterniond q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
    if (!(std::abs(q.norm() - 1) <= 1e-3)) {
      std::ostringstream length;
      length << q.norm();
      fail_input(path, what + "rotation is not a unit quaternion (length " + length.str() + ")");
    }
    rot.block<3, 3>(0, 0) = q.normalized().toRotationMatrix();
  }
  if (sized(node.scale, 3, "scale"))
    s.diagonal().head<3>() = Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]);
  return t * rot * s;
}

struct Builder {
  Builder(const tinygltf::Model& m, const std::filesystem::path& p) : model(m), path(p) {}
  const tinygltf::Model& model;
  const std::filesystem::path& path;
  std::vector<Eigen::Vector3d> positions, normals;
  std::vector<Eigen::Vector2d> texcoords;  // one per position (zero where a primitive has none)
  std::vector<std::array<Corner, 3>> triangles;
  std::vector<int> materials;  // per triangle: its primitive's material
  std::vector<GltfLightNode> lights;
  std::size_t primitives = 0, skipped_primitives = 0;
  bool every_vertex_has_normal = true;

  void primitive(const tinygltf::Primitive& p, const Eigen::Matrix4d& world) {
    const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
    if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
        mode != TINYGLTF_MODE_TRIANGLE_FAN) {
      ++skipped_primitives;  // points and lines have no surface
      return;
    }
    const auto pos = p.attributes.find("POSITION");
    if (pos == p.attributes.end()) fail_input(path, "a triangle primitive has no POSITION attribute");
    const std::vector<Eigen::Vector3d> local = read_vec3(model, pos->second, "POSITION", path);
    std::vector<Eigen::Vector3d> local_normals;
    const auto nrm = p.attributes.find("NORMAL");
    if (nrm != p.attributes.end()) {
      local_normals = read_vec3(model, nrm->second, "NORMAL", path);
      if (local_normals.size() != local.size()) fail_input(path, "NORMAL and POSITION counts differ in a primitive");
    } else {
      every_vertex_has_normal = false;
    }
    std::vector<Eigen::Vector2d> local_uvs;
    const auto tex = p.attributes.find("TEXCOORD_0");
    if (tex != p.attributes.end()) {
      local_uvs = read_texcoords(model, tex->second, path);
      if (local_uvs.size() != local.size()) fail_input(path, "TEXCOORD_0 and POSITION counts differ in a primitive");
    }
    std::vector<std::uint32_t> index;
    if (p.indices >= 0) {
      index = read_indices(model, p.indices, path);
    } else {
      index.resize(local.size());
      for (std::size_t i = 0; i < index.size(); ++i) index[i] = static_cast<std::uint32_t>(i);
    }
    for (std::uint32_t i : index)
      if (i >= local.size())
        fail_input(path, "an index (" + std::to_string(i) + ") is past the " + std::to_string(local.size()) +
                       " vertices of its primitive");
    const Eigen::Matrix3d linear = world.block<3, 3>(0, 0);
    const Eigen::Matrix3d normal_matrix = linear.inverse().transpose();
    const bool mirrored = linear.determinant() < 0, identity = world.isIdentity(0);
    // Vertex numbers are int (Corner): refused far below that.
    if (local.size() > kMaxVertices - positions.size())
      fail_input(path, "more than " + std::to_string(kMaxVertices) + " vertices in the scene");
    const int base = static_cast<int>(positions.size());
    for (std::size_t v = 0; v < local.size(); ++v) {
      // Untransformed where the node is the identity: -0 + 0 would turn -0.0 into +0.0,
      // and --gltf returns the input's positions bit for bit.
      const Eigen::Vector3d w = identity ? local[v] : Eigen::Vector3d(linear * local[v] + world.block<3, 1>(0, 3));
      if (!w.allFinite()) fail_input(path, "vertex " + std::to_string(base + v) + " is not finite");
      positions.push_back(w);
      normals.push_back(local_normals.empty() ? Eigen::Vector3d::Zero() : (normal_matrix * local_normals[v]).eval());
      if (!normals.back().allFinite()) fail_input(path, "normal of vertex " + std::to_string(base + v) + " is not finite");
      texcoords.push_back(local_uvs.empty() ? Eigen::Vector2d::Zero() : local_uvs[v]);
    }
    const bool has_normals = !local_normals.empty(), has_uvs = !local_uvs.empty();
    auto corner = [&](std::uint32_t i) {
      const int v = base + static_cast<int>(i);
      return Corner{v, has_normals ? v : -1, has_uvs ? v : -1};
    };
    auto add = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
      // A mirroring transform turns the winding around; swap to keep the front side.
      if (mirrored) std::swap(b, c);
      triangles.push_back({corner(a), corner(b), corner(c)});
      materials.push_back(p.material);
    };
    // glTF requires whole triangles: a short list would lose its tail without a word.
    if (mode == TINYGLTF_MODE_TRIANGLES ? index.size() % 3 != 0 : index.size() < 3)
      fail_input(path, "a " + std::string(mode == TINYGLTF_MODE_TRIANGLES ? "TRIANGLES" : "strip or fan") +
                           " primitive of " + std::to_string(index.size()) +
                           (p.indices >= 0 ? " indices" : " vertices") +
                           (mode == TINYGLTF_MODE_TRIANGLES ? ", not a multiple of 3" : ", fewer than 3"));
    if (mode == TINYGLTF_MODE_TRIANGLES) {
      for (std::size_t k = 0; k + 2 < index.size(); k += 3)
        add(index[k], index[k + 1], index[k + 2]);
    } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      for (std::size_t k = 0; k + 2 < index.size(); ++k)
        if (k % 2 == 0) add(index[k], index[k + 1], index[k + 2]);
        else add(index[k + 1], index[k], index[k + 2]);
    } else {
      for (std::size_t k = 1; k + 1 < index.size(); ++k) add(index[0], index[k], index[k + 1]);
    }
    ++primitives;
  }

  // glTF nodes form strict trees: a node reached twice (a cycle, a second parent, or listed
  // twice) is refused, which also bounds the work by the file's size.
  void node(int index, const Eigen::Matrix4d& parent, std::vector<bool>& visited, int depth) {
    if (index < 0 || static_cast<std::size_t>(index) >= model.nodes.size())
      fail_input(path, "node " + std::to_string(index) + " does not exist");
    if (visited[index])
      fail_input(path, "node " + std::to_string(index) + " is reached twice (a cycle or a second parent): glTF nodes form trees");
    if (depth > 1024) fail_input(path, "the node hierarchy is deeper than 1024");
    visited[index] = true;
    const tinygltf::Node& n = model.nodes[index];
    const Eigen::Matrix4d world = parent * local_transform(n, index, path);
    if (const auto ext = n.extensions.find("KHR_lights_punctual"); ext != n.extensions.end() && ext->second.IsObject()) {
      const tinygltf::Value& light = ext->second.Get("light");
      if (!light.IsInt() || light.GetNumberAsInt() < 0 ||
          static_cast<std::size_t>(light.GetNumberAsInt()) >= model.lights.size())
        fail_input(path, "node " + std::to_string(index) + " names a KHR_lights_punctual light that does not exist");
      lights.push_back({light.GetNumberAsInt(), world});
    }
    if (n.mesh >= 0) {
      if (static_cast<std::size_t>(n.mesh) >= model.meshes.size())
        fail_input(path, "node " + std::to_string(index) + " names mesh " + std::to_string(n.mesh) + ", which does not exist");
      for (const tinygltf::Primitive& p : model.meshes[n.mesh].primitives) primitive(p, world);
    }
    for (int child : n.children) node(child, world, visited, depth + 1);
  }
};

}  // namespace

AccessorView accessor_view(const tinygltf::Model& model, int index, int type, const std::vector<int>& component_types,
                           const std::string& what, const std::filesystem::path& path) {
  if (index < 0 || static_cast<std::size_t>(index) >= model.accessors.size())
    fail_input(path, what + ": accessor " + std::to_string(index) + " does not exist");
  const tinygltf::Accessor& a = model.accessors[index];
  if (a.sparse.isSparse) fail_input(path, what + ": sparse accessors are not supported");
  if (a.type != type) fail_input(path, what + ": accessor " + std::to_string(index) + " has the wrong type");
  bool allowed = false;
  for (int t : component_types) allowed = allowed || a.componentType == t;
  if (!allowed) fail_input(path, what + ": accessor " + std::to_string(index) + " has an unsupported component type");
  if (a.bufferView < 0 || static_cast<std::size_t>(a.bufferView) >= model.bufferViews.size())
    fail_input(path, what + ": accessor " + std::to_string(index) + " has no buffer view");
  const tinygltf::BufferView& view = model.bufferViews[a.bufferView];
  if (view.buffer < 0 || static_cast<std::size_t>(view.buffer) >= model.buffers.size())
    fail_input(path, what + ": buffer view " + std::to_string(a.bufferView) + " names no buffer");
  const std::vector<unsigned char>& buffer = model.buffers[view.buffer].data;
  const std::size_t element = static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(a.componentType)) *
                              static_cast<std::size_t>(tinygltf::GetNumComponentsInType(a.type));
  const std::size_t stride = view.byteStride ? view.byteStride : element;
  if (stride < element)
    fail_input(path, what + ": buffer view " + std::to_string(a.bufferView) + " has a byteStride (" +
                   std::to_string(view.byteStride) + ") below its element size (" + std::to_string(element) + ")");
  const auto out_of_range = [&] {
    fail_input(path, what + ": accessor " + std::to_string(index) + " reads past the end of its buffer");
  };
  if (view.byteOffset > buffer.size() || view.byteLength > buffer.size() - view.byteOffset) out_of_range();
  if (a.byteOffset > view.byteLength) out_of_range();
  if (a.count > 0) {
    const std::size_t available = view.byteLength - a.byteOffset;
    if (element > available) out_of_range();
    if ((a.count - 1) > (available - element) / stride) out_of_range();
  }
  return {buffer.data() + view.byteOffset + a.byteOffset, a.count, stride, a.componentType};
}

tinygltf::Model parse_gltf(const std::string& bytes, const std::filesystem::path& path, bool keep_images) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(keep_images ? keep_image_bytes : skip_image, nullptr);
  std::string err, warn;
  const std::string base = path.has_parent_path() ? path.parent_path().string() : std::string(".");
  const bool binary = bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0;
  if (bytes.size() > std::numeric_limits<unsigned int>::max()) fail_input(path, "file too large");
  // tinygltf reads a GLB of any container version as glTF 2.0's, and a .glb without the
  // magic as JSON (its message then a JSON parse error at byte 0).
  if (!binary && lowercase_extension(path) == ".glb")
    fail_input(path, "not a GLB: it does not begin with the magic 'glTF' (binary glTF's header)");
  if (binary) {
    if (bytes.size() < 12)
      fail_input(path, "truncated: " + std::to_string(bytes.size()) + " bytes, a GLB header takes 12");
    std::uint32_t version = 0;
    std::memcpy(&version, bytes.data() + 4, 4);
    if (version != 2)
      fail_input(path, "GLB container version " + std::to_string(version) +
                           ": glTF 2.0's binary container is version 2 (version 1 is glTF 1.0's, which is not read)");
  }
  // tinygltf turns JSON into its values recursively (extras, extensions): nesting deep
  // enough would exhaust the stack, so it is bounded before tinygltf sees the text.
  if (auto problem = table_format::check_json_depth(json_text_of(bytes, binary), table_format::kMaxJsonDepth))
    fail_input(path, "glTF JSON " + *problem);
  bool ok = false;
  try {
    ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                              static_cast<unsigned int>(bytes.size()), base)
                : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(),
                                             static_cast<unsigned int>(bytes.size()), base);
  } catch (const std::exception& e) {
    // tinygltf reports most problems in `err`, but some reach a throwing library call: a
    // GLB buffer of byteLength 0 beside a BIN chunk is copied from data.at(0) of an empty
    // vector (std::out_of_range; found by fuzz_gltf).
    fail_input(path, std::string("cannot read glTF: tinygltf failed (") + e.what() + ")");
  }
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    fail_input(path, "cannot read glTF" + (err.empty() ? std::string() : ": " + err));
  }
  return model;
}

Mesh mesh_from_gltf(const tinygltf::Model& model, const std::string& bytes, const std::filesystem::path& path,
                    NormalSource normal_source, std::vector<GltfLightNode>* lights) {
  const std::string base = path.has_parent_path() ? path.parent_path().string() : std::string(".");
  // glTF 2.x only: another major version says its fields mean something else.
  if (model.asset.version.rfind("2.", 0) != 0)
    fail_input(path, "asset.version '" + model.asset.version + "': glTF 2.x is read");
  // An extension listed as required changes what the file means (compressed or moved
  // data, transformed texture coordinates): read as plain glTF its values would be wrong.
  for (const std::string& required : model.extensionsRequired)
    if (required != "KHR_lights_punctual" && required != "KHR_materials_emissive_strength")
      fail_input(path, "it requires the glTF extension " + required +
                           " (extensionsRequired), which shtool does not implement (it reads KHR_lights_punctual and "
                           "KHR_materials_emissive_strength)");
  if (model.scenes.empty()) fail_input(path, "no scene (glTF without scenes has nothing to render)");
  const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
  if (static_cast<std::size_t>(scene) >= model.scenes.size()) fail_input(path, "the default scene does not exist");
  Builder b(model, path);
  std::vector<bool> visited(model.nodes.size(), false);
  for (int n : model.scenes[scene].nodes) b.node(n, Eigen::Matrix4d::Identity(), visited, 0);
  if (b.primitives == 0)
    fail_input(path, b.skipped_primitives ? "no triangle primitive (only points or lines)" : "the default scene has no mesh");
  if (normal_source == NormalSource::file && !b.every_vertex_has_normal)
    fail_input(path, "--normals file: not every primitive has NORMAL");
  if (lights) *lights = b.lights;
  Mesh mesh;
  mesh.input_crc32 = input_crc32(bytes);
  mesh.files.push_back(path);
  // The external buffers and images: outputs must never replace them.
  auto external = [&](const std::string& uri) {
    if (!uri.empty() && uri.rfind("data:", 0) != 0) mesh.files.push_back(std::filesystem::path(base) / uri);
  };
  for (const tinygltf::Buffer& buffer : model.buffers) external(buffer.uri);
  for (const tinygltf::Image& i : model.images) external(i.uri);
  mesh.obj_vertices = b.positions.size();
  mesh.up = UpAxis::y;
  mesh.front = gltf_front();
  for (Eigen::Vector3d& p : b.positions) p = from_y_up(p);
  for (Eigen::Vector3d& n : b.normals) n = from_y_up(n);
  return finish_mesh(std::move(mesh), b.positions, b.normals, b.triangles, path, normal_source, b.texcoords,
                     b.materials);
}

Mesh load_gltf_bytes(const std::string& bytes, const std::filesystem::path& path, NormalSource normal_source) {
  const tinygltf::Model model = parse_gltf(bytes, path, /*keep_images=*/false);
  return mesh_from_gltf(model, bytes, path, normal_source, nullptr);
}

int append_buffer_view(tinygltf::Model& model, const void* bytes, std::size_t size, int target) {
  std::vector<unsigned char>& data = model.buffers[0].data;
  tinygltf::BufferView v;
  v.buffer = 0;
  v.byteOffset = data.size();
  v.byteLength = size;
  v.target = target;
  const auto* p = static_cast<const unsigned char*>(bytes);
  data.insert(data.end(), p, p + size);
  data.resize((data.size() + 3) / 4 * 4, 0);
  model.bufferViews.push_back(v);
  return static_cast<int>(model.bufferViews.size()) - 1;
}

int append_float_accessor(tinygltf::Model& model, const std::vector<float>& values, int type, bool bounds) {
  const int components = tinygltf::GetNumComponentsInType(type);
  tinygltf::Accessor a;
  a.bufferView = append_buffer_view(model, values.data(), values.size() * sizeof(float), TINYGLTF_TARGET_ARRAY_BUFFER);
  a.componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  a.type = type;
  a.count = values.size() / components;
  if (bounds) {
    a.minValues.assign(components, std::numeric_limits<double>::infinity());
    a.maxValues.assign(components, -std::numeric_limits<double>::infinity());
    for (std::size_t i = 0; i < values.size(); ++i) {
      a.minValues[i % components] = std::min<double>(a.minValues[i % components], values[i]);
      a.maxValues[i % components] = std::max<double>(a.maxValues[i % components], values[i]);
    }
  }
  model.accessors.push_back(a);
  return static_cast<int>(model.accessors.size()) - 1;
}

std::string write_single_mesh_gltf(tinygltf::Model& model, tinygltf::Mesh mesh, bool binary) {
  model.meshes.push_back(std::move(mesh));
  tinygltf::Node node;
  node.mesh = 0;
  model.nodes.push_back(node);
  tinygltf::Scene scene;
  scene.nodes = {0};
  model.scenes.push_back(scene);
  model.defaultScene = 0;
  std::ostringstream out;
  tinygltf::TinyGLTF writer;
  if (!writer.WriteGltfSceneToStream(&model, out, !binary, binary) || !out)
    throw std::runtime_error("tinygltf could not write the model");
  return out.str();
}

}  // namespace shtool::fit
