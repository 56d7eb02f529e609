// The parsed glTF behind load_gltf_bytes, for readers that need more of the file than its
// triangles (offline/scene: materials, textures, KHR_lights_punctual). The same parse and
// node walk as the mesh loader, so a scene's triangles are exactly the mesh's.
#pragma once

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

// The file parsed by tinygltf with the checks of load_gltf_bytes. With `keep_images`, each
// image's encoded bytes (PNG, JPEG, ...) are kept undecoded in Image::image, its width and
// height left at -1 (decode them with lighting::decode_image); without, images are skipped.
// Throws MeshError naming the file.
tinygltf::Model parse_gltf(const std::string& bytes, const std::filesystem::path& path, bool keep_images);

// load_gltf_bytes on a parsed model: Mesh::triangle_material holds each triangle's
// primitive material (-1: none), and `lights`, when given, receives the light nodes.
Mesh mesh_from_gltf(const tinygltf::Model& model, const std::string& bytes, const std::filesystem::path& path,
                    NormalSource normals, std::vector<GltfLightNode>* lights);

}  // namespace shtool::fit
