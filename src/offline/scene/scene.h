// A lit scene for light transport (bake-probes): the triangles of a glTF 2.0 or OBJ file in
// shtool's frame (fit/mesh.h reads them), their diffuse materials, KHR_lights_punctual
// lights and an optional distant environment, with an Embree scene for the rays.
//
// Materials are Lambertian:
// - glTF: albedo = baseColorFactor x baseColorTexture (sRGB, decoded to linear, sampled
//   bilinearly at the hit's TEXCOORD_0 with repeat wrapping), emitted radiance =
//   emissiveFactor x emissiveTexture x KHR_materials_emissive_strength; `doubleSided`
//   honoured (a single-sided triangle seen from behind neither reflects nor emits). A
//   primitive without a material gets glTF's default: white, single-sided.
// - OBJ: Kd of the face's .mtl material as albedo and Ke as emitted radiance when the
//   file states them; albedo 0.8 and no emission otherwise. OBJ states no sidedness:
//   faces are single-sided (front = counter-clockwise), as three.js's OBJLoader shows them.
// Lights (glTF KHR_lights_punctual, three.js's physical units): directional, intensity =
// irradiance (lux) on a surface facing it; point and spot, intensity = radiant intensity
// (candela) with inverse-square falloff, the range window and the spot cone as the
// extension's specification recommends (LightFalloff below).
#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "common/mesh_frame.h"
#include "fit/embree_scene.h"
#include "fit/mesh.h"

namespace shtool::scene {

using Rgb = Eigen::Vector3d;

// A decoded texture: linear RGB, rows top first.
struct Texture {
  int width = 0, height = 0;
  std::vector<float> rgb;
  // Bilinear, repeat wrapping, at glTF's (u, v) (origin top left).
  Rgb sample(double u, double v) const;
};

struct Material {
  Rgb base_color{1, 1, 1};
  int base_texture = -1;  // index into Scene::textures
  Rgb emissive{0, 0, 0};  // factor x strength
  int emissive_texture = -1;
  bool double_sided = false;
};

enum class LightType { directional, point, spot };
const char* light_type_name(LightType t);

struct PunctualLight {
  LightType type = LightType::point;
  Rgb intensity{1, 1, 1};            // colour x intensity: lux (directional) or candela
  Eigen::Vector3d position{0, 0, 0};  // point, spot (shtool frame)
  Eigen::Vector3d direction{0, 0, -1};  // unit, the way the light travels (directional, spot)
  double range = 0;                   // 0: unbounded
  double inner_cone = 0, outer_cone = 0.7853981633974483;  // spot, radians
};

// What a light delivers at a point x: the unit direction from x toward the light, the
// distance to it (infinity for directional) and the irradiance on a surface facing it.
struct LightSample {
  Eigen::Vector3d to_light;
  double distance;
  Rgb irradiance;
};
// KHR_lights_punctual's recommended falloff: range window max(min(1 - (d / range)^4, 1), 0)
// over d^2, and for a spot, t = clamp((cos a - cos outer) / max(1e-3, cos inner - cos outer),
// 0, 1) squared, a the angle between the spot's axis and the direction to x.
LightSample light_at(const PunctualLight& light, const Eigen::Vector3d& x);

struct Scene {
  fit::Mesh mesh;                         // triangles in shtool's frame, triangle_material set
  std::vector<Material> materials;        // indexed by Mesh::triangle_material
  Material default_material;              // triangles without one: glTF white, OBJ 0.8
  std::vector<Texture> textures;
  std::vector<PunctualLight> lights;
  std::vector<Eigen::Vector3d> face_normals;  // unit, right-handed winding (front side)
  std::unique_ptr<fit::EmbreeScene> embree;
  bool gltf = false;
  std::size_t unsupported_lights = 0;     // KHR_lights_punctual lights of an unknown type

  const Material& material_of(std::size_t triangle) const;
  // Albedo and emitted radiance at barycentric (u, v) of a triangle (Embree's).
  Rgb albedo(std::size_t triangle, double u, double v) const;
  Rgb emitted(std::size_t triangle, double u, double v) const;
  Eigen::Vector3d lower() const;  // bounding box of the triangles
  Eigen::Vector3d upper() const;
};

// Reads glTF (by magic or extension) or OBJ (with `up`; its .mtl from the mtllib line,
// beside the file, when present). Throws InputError naming the file and the problem.
Scene load_scene(const std::filesystem::path& path, UpAxis up);

}  // namespace shtool::scene
