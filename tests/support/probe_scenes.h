// Small glTF scenes for the bake-probes tests, written as .gltf text with the geometry in a
// base64 data URI: quads with a material each, KHR_lights_punctual lights on nodes.
// Coordinates are glTF's (+Y up); shtool reads them as (X, -Z, Y).
#pragma once

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "scratch_files.h"

namespace shtool::test {

inline std::string base64(const std::string& bytes) {
  static const char* a = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const std::uint32_t v = (std::uint8_t(bytes[i]) << 16) | (std::uint8_t(bytes[i + 1]) << 8) | std::uint8_t(bytes[i + 2]);
    out += {a[v >> 18], a[(v >> 12) & 63], a[(v >> 6) & 63], a[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const std::uint32_t v = std::uint8_t(bytes[i]) << 16;
    out += {a[v >> 18], a[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const std::uint32_t v = (std::uint8_t(bytes[i]) << 16) | (std::uint8_t(bytes[i + 1]) << 8);
    out += {a[v >> 18], a[(v >> 12) & 63], a[(v >> 6) & 63], '='};
  }
  return out;
}

struct ProbeTestMaterial {
  std::array<double, 3> base{1, 1, 1};
  std::array<double, 3> emissive{0, 0, 0};
  double strength = 1;  // KHR_materials_emissive_strength when != 1
  bool double_sided = false;
  bool textured = false;  // baseColorTexture and emissiveTexture: the scene's texture
};

class ProbeTestScene {
 public:
  int material(const ProbeTestMaterial& m) {
    nlohmann::json j = {{"pbrMetallicRoughness", {{"baseColorFactor", {m.base[0], m.base[1], m.base[2], 1.0}},
                                                  {"metallicFactor", 0.0}}},
                        {"emissiveFactor", m.emissive},
                        {"doubleSided", m.double_sided}};
    if (m.strength != 1) j["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"] = m.strength;
    if (m.textured) {
      j["pbrMetallicRoughness"]["baseColorTexture"] = {{"index", 0}};
      j["emissiveTexture"] = {{"index", 0}};
    }
    materials_.push_back(j);
    return static_cast<int>(materials_.size()) - 1;
  }
  // A quad a, b, c, d (counter-clockwise seen from its front) of material m.
  void quad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d,
            int m) {
    triangle(a, b, c, m);
    triangle(a, c, d, m);
  }
  void triangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, int m) {
    for (const Eigen::Vector3d* p : {&a, &b, &c}) {
      positions_.push_back(static_cast<float>(p->x()));
      positions_.push_back(static_cast<float>(p->y()));
      positions_.push_back(static_cast<float>(p->z()));
    }
    tri_material_.push_back(m);
  }
  // An axis-aligned box [lo, hi]; inward: faces seen from inside are front faces.
  void box(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, int m, bool inward) {
    const auto P = [&](int x, int y, int z) {
      return Eigen::Vector3d(x ? hi.x() : lo.x(), y ? hi.y() : lo.y(), z ? hi.z() : lo.z());
    };
    // Outward-facing quads (counter-clockwise seen from outside).
    const std::array<std::array<Eigen::Vector3d, 4>, 6> faces = {{
        {P(0, 0, 0), P(0, 0, 1), P(0, 1, 1), P(0, 1, 0)},  // -x
        {P(1, 0, 0), P(1, 1, 0), P(1, 1, 1), P(1, 0, 1)},  // +x
        {P(0, 0, 0), P(1, 0, 0), P(1, 0, 1), P(0, 0, 1)},  // -y
        {P(0, 1, 0), P(0, 1, 1), P(1, 1, 1), P(1, 1, 0)},  // +y
        {P(0, 0, 0), P(0, 1, 0), P(1, 1, 0), P(1, 0, 0)},  // -z
        {P(0, 0, 1), P(1, 0, 1), P(1, 1, 1), P(0, 1, 1)},  // +z
    }};
    for (const auto& f : faces) {
      if (inward) quad(f[3], f[2], f[1], f[0], m);
      else quad(f[0], f[1], f[2], f[3], m);
    }
  }
  // A KHR_lights_punctual light on a node at `position` whose local -Z is turned onto
  // `direction` (the way the light travels, glTF frame).
  void light(const nlohmann::json& light, const Eigen::Vector3d& position, const Eigen::Vector3d& direction) {
    lights_.push_back(light);
    const Eigen::Quaterniond q = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d(0, 0, -1), direction.normalized());
    light_nodes_.push_back({{"translation", {position.x(), position.y(), position.z()}},
                            {"rotation", {q.x(), q.y(), q.z(), q.w()}},
                            {"extensions", {{"KHR_lights_punctual", {{"light", lights_.size() - 1}}}}}});
  }

  // One texture (an encoded PNG) for the textured materials, and TEXCOORD_0 = uv at
  // every vertex (glTF's convention: v down from the image's top).
  void texture(const std::string& png, const Eigen::Vector2d& uv) {
    png_ = png;
    uv_ = uv;
  }

  std::string gltf() const {
    std::string bytes(reinterpret_cast<const char*>(positions_.data()), positions_.size() * sizeof(float));
    const std::size_t vertices = positions_.size() / 3;
    const std::size_t uv_offset = bytes.size();
    if (!png_.empty())
      for (std::size_t v = 0; v < vertices; ++v) {
        const float uv[2] = {static_cast<float>(uv_.x()), static_cast<float>(uv_.y())};
        bytes.append(reinterpret_cast<const char*>(uv), sizeof uv);
      }
    nlohmann::json j;
    j["asset"] = {{"version", "2.0"}};
    j["buffers"] = {{{"byteLength", bytes.size()}, {"uri", "data:application/octet-stream;base64," + base64(bytes)}}};
    j["bufferViews"] = nlohmann::json::array();
    j["accessors"] = nlohmann::json::array();
    nlohmann::json primitives = nlohmann::json::array();
    // One primitive per triangle (its own accessor): simple, and every triangle keeps its material.
    for (std::size_t t = 0; t < vertices / 3; ++t) {
      const std::size_t position_accessor = j["accessors"].size();
      j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", t * 36}, {"byteLength", 36}});
      Eigen::Vector3f lo(1e30f, 1e30f, 1e30f), hi(-1e30f, -1e30f, -1e30f);
      for (int v = 0; v < 3; ++v)
        for (int c = 0; c < 3; ++c) {
          lo[c] = std::min(lo[c], positions_[(t * 3 + v) * 3 + c]);
          hi[c] = std::max(hi[c], positions_[(t * 3 + v) * 3 + c]);
        }
      j["accessors"].push_back({{"bufferView", j["bufferViews"].size() - 1}, {"componentType", 5126}, {"count", 3},
                                {"type", "VEC3"},
                                {"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}});
      nlohmann::json p = {{"attributes", {{"POSITION", position_accessor}}}, {"mode", 4}};
      if (!png_.empty()) {
        const std::size_t index = j["accessors"].size();
        j["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", uv_offset + t * 24}, {"byteLength", 24}});
        j["accessors"].push_back(
            {{"bufferView", j["bufferViews"].size() - 1}, {"componentType", 5126}, {"count", 3}, {"type", "VEC2"}});
        p["attributes"]["TEXCOORD_0"] = index;
      }
      if (tri_material_[t] >= 0) p["material"] = tri_material_[t];
      primitives.push_back(p);
    }
    j["meshes"] = {{{"primitives", primitives}}};
    j["nodes"] = {{{"mesh", 0}}};
    nlohmann::json scene_nodes = {0};
    for (const nlohmann::json& n : light_nodes_) {
      scene_nodes.push_back(j["nodes"].size());
      j["nodes"].push_back(n);
    }
    j["scenes"] = {{{"nodes", scene_nodes}}};
    j["scene"] = 0;
    if (!materials_.empty()) j["materials"] = materials_;
    if (!png_.empty()) {
      j["images"] = {{{"uri", "data:image/png;base64," + base64(png_)}}};
      j["textures"] = {{{"source", 0}}};
    }
    if (!lights_.empty()) {
      j["extensions"]["KHR_lights_punctual"]["lights"] = lights_;
      j["extensionsUsed"] = {"KHR_lights_punctual"};
    }
    for (const nlohmann::json& m : materials_)
      if (m.contains("extensions")) j["extensionsUsed"].push_back("KHR_materials_emissive_strength");
    return j.dump();
  }
  void write(const std::filesystem::path& path) const { write_file(path, gltf()); }

 private:
  std::vector<float> positions_;
  std::vector<int> tri_material_;
  nlohmann::json materials_ = nlohmann::json::array();
  nlohmann::json lights_ = nlohmann::json::array();
  std::vector<nlohmann::json> light_nodes_;
  std::string png_;
  Eigen::Vector2d uv_ = Eigen::Vector2d::Zero();
};

// A solid grey cube [-0.5, 0.5]^3 (outward faces) lit by a point light: on a 3 x 3 x 3 grid
// over [-1.5, 1.5]^3 the centre probe is inside it (invalid, filled from its neighbours),
// the scene of the shard and MPI tests.
inline void write_solid_cube_scene(const std::filesystem::path& path) {
  ProbeTestScene t;
  const int m = t.material({{0.5, 0.5, 0.5}});
  t.box(Eigen::Vector3d(-0.5, -0.5, -0.5), Eigen::Vector3d(0.5, 0.5, 0.5), m, false);
  t.light({{"type", "point"}, {"intensity", 5.0}}, Eigen::Vector3d(1, 1.2, 0.7), Eigen::Vector3d(0, -1, 0));
  t.write(path);
}

// A closed room of coloured walls [-2, 2] x [0, 3] x [-2, 2] (glTF's frame), a coloured
// point light near the ceiling and a solid white block on the floor: the L1 band and
// band 2 are far from zero and differ per channel, and a probe inside the block is
// invalid and filled. The scene of the encoding tests.
inline void write_encoding_room_scene(const std::filesystem::path& path) {
  ProbeTestScene t;
  const int red = t.material({{0.8, 0.2, 0.1}}), white = t.material({{0.7, 0.7, 0.7}});
  t.box(Eigen::Vector3d(-2, 0, -2), Eigen::Vector3d(2, 3, 2), red, true);
  t.box(Eigen::Vector3d(-0.5, 0, -0.5), Eigen::Vector3d(0.5, 1.2, 0.5), white, false);
  t.light({{"type", "point"}, {"intensity", 8.0}, {"color", {1.0, 0.8, 0.5}}}, Eigen::Vector3d(1.2, 2.5, 0.8),
          Eigen::Vector3d(0, -1, 0));
  t.write(path);
}

}  // namespace shtool::test
