// The parsed glTF behind load_gltf_bytes, for readers that need more of the file than its
// triangles (offline/scene: materials, textures, KHR_lights_punctual). The same parse and
// node walk as the mesh loader, so a scene's triangles are exactly the mesh's.
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <tiny_gltf.h>

#include <Eigen/Core>

#include "fit/mesh.h"

namespace shtool::fit {

// A node of the default scene that carries a KHR_lights_punctual light: the light's index
// in Model::lights and the node's world transform, in the file's (+Y up) frame.
struct GltfLightNode {
  int light = -1;
  Eigen::Matrix4d world = Eigen::Matrix4d::Identity();
};

// Where accessor `index` keeps its `count` elements (of `type`, with one of the allowed
// component types), checked against its buffer view and buffer without overflow.
struct AccessorView {
  const unsigned char* data = nullptr;
  std::size_t count = 0, stride = 0;
  int component_type = 0;

  // Component c of element i stored as a U (copied out: the data need not be aligned).
  template <class U>
  U component(std::size_t i, int c) const {
    U u;
    std::memcpy(&u, data + i * stride + c * sizeof(U), sizeof u);
    return u;
  }
  // Component c of element i: a float as it is, an integer as its value or, when
  // `normalized`, divided by the type's maximum (signed: clamped at -1; glTF 2.0, 3.11).
  double number(std::size_t i, int c, bool normalized) const {
    switch (component_type) {
      case TINYGLTF_COMPONENT_TYPE_FLOAT:
        return component<float>(i, c);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
        return normalized ? component<std::uint8_t>(i, c) / 255.0 : component<std::uint8_t>(i, c);
      case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT:
        return normalized ? component<std::uint16_t>(i, c) / 65535.0 : component<std::uint16_t>(i, c);
      case TINYGLTF_COMPONENT_TYPE_BYTE:
        return normalized ? std::max(component<std::int8_t>(i, c) / 127.0, -1.0) : component<std::int8_t>(i, c);
      case TINYGLTF_COMPONENT_TYPE_SHORT:
        return normalized ? std::max(component<std::int16_t>(i, c) / 32767.0, -1.0) : component<std::int16_t>(i, c);
      default:
        return component<std::uint32_t>(i, c);
    }
  }
};

// Accessor `index` of `type` with a component type among `component_types`; MeshError
// naming `what` and the file when it does not exist, is sparse, has another type or reads
// past its buffer.
AccessorView accessor_view(const tinygltf::Model& model, int index, int type, const std::vector<int>& component_types,
                           const std::string& what, const std::filesystem::path& path);

// The file parsed by tinygltf with the checks of load_gltf_bytes. With `keep_images`, each
// image's encoded bytes (PNG, JPEG, ...) are kept undecoded in Image::image, its width and
// height left at -1 (decode them with lighting::decode_image); without, images are skipped.
// Throws MeshError naming the file.
tinygltf::Model parse_gltf(const std::string& bytes, const std::filesystem::path& path, bool keep_images);

// load_gltf_bytes on a parsed model: Mesh::triangle_material holds each triangle's
// primitive material (-1: none), and `lights`, when given, receives the light nodes.
Mesh mesh_from_gltf(const tinygltf::Model& model, const std::string& bytes, const std::filesystem::path& path,
                    NormalSource normals, std::vector<GltfLightNode>* lights);

// Writers share one buffer (model.buffers[0], which must exist) and give every accessor a
// view of its own, 4-byte aligned as float accessors require, without stride.
// Appends `size` bytes as a new view for `target`; the view's index.
int append_buffer_view(tinygltf::Model& model, const void* bytes, std::size_t size, int target);
// A float accessor of `type` over `values` (whole elements) in a new view; with `bounds`,
// min and max per component (POSITION must have them), taken from the floats as stored.
// The accessor's index.
int append_float_accessor(tinygltf::Model& model, const std::vector<float>& values, int type, bool bounds);
// `model` with `mesh` as its only mesh, on the one node of its default scene, written as
// glTF (`binary`: .glb, else indented JSON); std::runtime_error when tinygltf fails.
std::string write_single_mesh_gltf(tinygltf::Model& model, tinygltf::Mesh mesh, bool binary);

}  // namespace shtool::fit
