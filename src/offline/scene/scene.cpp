#include "scene/scene.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>
#include <sstream>

#include "common/input_error.h"
#include "common/input_file.h"
#include "fit/gltf_model.h"
#include "lighting/image_io.h"

namespace shtool::scene {
namespace {

Rgb factor3(const std::vector<double>& v, const Rgb& fallback) {
  return v.size() >= 3 ? Rgb(v[0], v[1], v[2]) : fallback;
}

// A texture reference of a material: its image decoded once (textures[k] for image k).
int texture_image(const tinygltf::Model& model, int texture, const std::filesystem::path& path) {
  if (texture < 0) return -1;
  if (static_cast<std::size_t>(texture) >= model.textures.size())
    fail_input(path, "a material names texture " + std::to_string(texture) + ", which does not exist");
  const int source = model.textures[texture].source;
  if (source < 0 || static_cast<std::size_t>(source) >= model.images.size())
    fail_input(path, "texture " + std::to_string(texture) + " has no image");
  return source;
}

void check_color(const Rgb& c, const std::filesystem::path& path, const std::string& what) {
  if (!c.allFinite() || (c.array() < 0).any()) fail_input(path, what + " must be finite and not negative");
}

Scene gltf_scene(const std::string& bytes, const std::filesystem::path& path) {
  const tinygltf::Model model = fit::parse_gltf(bytes, path, /*keep_images=*/true);
  std::vector<fit::GltfLightNode> light_nodes;
  Scene s;
  s.gltf = true;
  s.mesh = fit::mesh_from_gltf(model, bytes, path, fit::NormalSource::automatic, &light_nodes);
  for (int& m : s.mesh.triangle_material)
    if (m >= static_cast<int>(model.materials.size()))
      fail_input(path, "a primitive names material " + std::to_string(m) + ", which does not exist");
  std::vector<int> used_images;
  for (std::size_t i = 0; i < model.materials.size(); ++i) {
    const tinygltf::Material& gm = model.materials[i];
    const std::string what = "material " + std::to_string(i);
    Material m;
    const std::vector<double>& base = gm.pbrMetallicRoughness.baseColorFactor;
    m.base_color = factor3(base, Rgb(1, 1, 1));
    m.emissive = factor3(gm.emissiveFactor, Rgb(0, 0, 0));
    if (const auto ext = gm.extensions.find("KHR_materials_emissive_strength"); ext != gm.extensions.end()) {
      const tinygltf::Value& strength = ext->second.Get("emissiveStrength");
      if (strength.IsNumber()) m.emissive *= strength.GetNumberAsDouble();
    }
    check_color(m.base_color, path, what + " baseColorFactor");
    // The schema's range; an albedo above 1 would gain energy at every bounce.
    if ((m.base_color.array() > 1).any()) fail_input(path, what + " baseColorFactor must be at most 1");
    check_color(m.emissive, path, what + " emissive radiance");
    m.base_texture = texture_image(model, gm.pbrMetallicRoughness.baseColorTexture.index, path);
    m.emissive_texture = texture_image(model, gm.emissiveTexture.index, path);
    if ((m.base_texture >= 0 && gm.pbrMetallicRoughness.baseColorTexture.texCoord != 0) ||
        (m.emissive_texture >= 0 && gm.emissiveTexture.texCoord != 0))
      fail_input(path, what + ": only TEXCOORD_0 is supported for textures");
    m.double_sided = gm.doubleSided;
    s.materials.push_back(m);
  }
  // Images: decoded only when a material uses them (the index is kept).
  s.textures.resize(model.images.size());
  for (Material& m : s.materials)
    for (int image : {m.base_texture, m.emissive_texture}) {
      if (image < 0 || s.textures[image].width > 0) continue;
      const tinygltf::Image& gi = model.images[image];
      if (gi.image.empty()) fail_input(path, "image " + std::to_string(image) + " has no data");
      const std::string encoded(gi.image.begin(), gi.image.end());
      const lighting::Image decoded =
          lighting::decode_image(encoded, path.string() + " image " + std::to_string(image), lighting::kMaxImageTexels, 1);
      Texture t;
      t.width = decoded.width;
      t.height = decoded.height;
      t.rgb.resize(static_cast<std::size_t>(t.width) * t.height * 3);
      for (std::size_t k = 0; k < static_cast<std::size_t>(t.width) * t.height; ++k)
        for (int c = 0; c < 3; ++c) t.rgb[3 * k + c] = decoded.texels[k * decoded.channels + c];
      s.textures[image] = std::move(t);
    }
  // Materials whose textures cannot be sampled (no UVs) keep their factors.
  if (s.mesh.uvs.empty())
    for (Material& m : s.materials) m.base_texture = m.emissive_texture = -1;
  s.default_material = Material{};
  for (const fit::GltfLightNode& node : light_nodes) {
    const tinygltf::Light& gl = model.lights[node.light];
    PunctualLight l;
    const std::string what = "light " + std::to_string(node.light);
    if (gl.type == "directional") l.type = LightType::directional;
    else if (gl.type == "point") l.type = LightType::point;
    else if (gl.type == "spot") l.type = LightType::spot;
    else {
      ++s.unsupported_lights;
      continue;
    }
    l.intensity = factor3(gl.color, Rgb(1, 1, 1)) * gl.intensity;
    check_color(l.intensity, path, what + " colour x intensity");
    if (!(gl.range >= 0) || !std::isfinite(gl.range)) fail_input(path, what + " range must be positive");
    l.range = gl.range;
    l.inner_cone = gl.spot.innerConeAngle;
    l.outer_cone = gl.spot.outerConeAngle;
    if (l.type == LightType::spot &&
        !(l.inner_cone >= 0 && l.inner_cone < l.outer_cone && l.outer_cone <= std::acos(-1.0) / 2))
      fail_input(path, what + ": spot cone angles need 0 <= innerConeAngle < outerConeAngle <= pi/2");
    const Eigen::Matrix3d linear = node.world.block<3, 3>(0, 0);
    Eigen::Vector3d dir = linear * Eigen::Vector3d(0, 0, -1);  // lights shine along local -Z
    if (!(dir.norm() > 0) || !dir.allFinite()) fail_input(path, what + ": its node's transform collapses its direction");
    l.direction = from_y_up(dir.normalized());
    l.position = from_y_up(node.world.block<3, 1>(0, 3));
    if (!l.position.allFinite()) fail_input(path, what + ": position is not finite");
    s.lights.push_back(l);
  }
  return s;
}

Scene obj_scene(const std::string& text, const std::filesystem::path& path, UpAxis up) {
  std::string mtl;
  const std::string lib = fit::obj_mtllib(text);
  std::filesystem::path mtl_path;
  if (!lib.empty()) {
    mtl_path = path.parent_path() / lib;
    std::error_code ec;
    // A library that is not there would bake every face at the default 0.8 without a
    // word: the scene is not the one its author made.
    if (!std::filesystem::is_regular_file(mtl_path, ec))
      fail_input(path, "its material library '" + lib + "' (mtllib) is not beside it: " + mtl_path.string() +
                           " is missing (remove the mtllib line to bake every face at the default albedo 0.8)");
    mtl = read_input_file(mtl_path, "the OBJ's material library");
  }
  Scene s;
  s.mesh = fit::load_obj_text(text, path, fit::NormalSource::automatic, up, mtl);
  s.default_material.base_color = Rgb(0.8, 0.8, 0.8);
  for (const fit::ObjMaterial& om : s.mesh.obj_materials) {
    Material m = s.default_material;
    if (om.has_kd) m.base_color = om.kd;
    if (om.has_ke) m.emissive = om.ke;
    check_color(m.base_color, path, "material '" + om.name + "' Kd");
    check_color(m.emissive, path, "material '" + om.name + "' Ke");
    s.materials.push_back(m);
  }
  if (s.mesh.triangle_material.empty()) s.mesh.triangle_material.assign(s.mesh.triangles.size(), -1);
  return s;
}

}  // namespace

const char* light_type_name(LightType t) {
  switch (t) {
    case LightType::directional: return "directional";
    case LightType::point: return "point";
    case LightType::spot: return "spot";
  }
  return "?";
}

Rgb Texture::sample(double u, double v) const {
  // Texel centres at (i + 1/2) / width; repeat wrapping on both axes.
  const double x = u * width - 0.5, y = v * height - 0.5;
  const double fx = std::floor(x), fy = std::floor(y);
  const double tx = x - fx, ty = y - fy;
  auto wrap = [](long long i, int n) { return static_cast<int>(((i % n) + n) % n); };
  auto texel = [&](long long i, long long j) {
    const std::size_t k = (static_cast<std::size_t>(wrap(j, height)) * width + wrap(i, width)) * 3;
    return Rgb(rgb[k], rgb[k + 1], rgb[k + 2]);
  };
  const long long i0 = static_cast<long long>(fx), j0 = static_cast<long long>(fy);
  return (1 - ty) * ((1 - tx) * texel(i0, j0) + tx * texel(i0 + 1, j0)) +
         ty * ((1 - tx) * texel(i0, j0 + 1) + tx * texel(i0 + 1, j0 + 1));
}

LightSample light_at(const PunctualLight& light, const Eigen::Vector3d& x) {
  if (light.type == LightType::directional)
    return {-light.direction, std::numeric_limits<double>::infinity(), light.intensity};
  const Eigen::Vector3d d = light.position - x;
  const double dist = d.norm();
  if (!(dist > 0)) return {Eigen::Vector3d::UnitZ(), 0, Rgb::Zero()};
  const Eigen::Vector3d to_light = d / dist;
  double scale = 1 / (dist * dist);
  if (light.range > 0) {
    const double r = dist / light.range;
    scale *= std::clamp(1 - r * r * r * r, 0.0, 1.0);
  }
  if (light.type == LightType::spot) {
    const double cos_outer = std::cos(light.outer_cone), cos_inner = std::cos(light.inner_cone);
    const double cd = light.direction.dot(-to_light);
    const double t = std::clamp((cd - cos_outer) / std::max(1e-3, cos_inner - cos_outer), 0.0, 1.0);
    scale *= t * t;
  }
  return {to_light, dist, light.intensity * scale};
}

const Material& Scene::material_of(std::size_t triangle) const {
  const int m = mesh.triangle_material[triangle];
  return m >= 0 ? materials[m] : default_material;
}

namespace {
Eigen::Vector2d hit_uv(const fit::Mesh& mesh, std::size_t triangle, double u, double v) {
  // Mesh::uvs has v up (bottom left origin); glTF textures are sampled top left.
  const auto& c = mesh.uvs[triangle];
  const Eigen::Vector2d uv = (1 - u - v) * c[0] + u * c[1] + v * c[2];
  return {uv.x(), 1 - uv.y()};
}
}  // namespace

Rgb Scene::albedo(std::size_t triangle, double u, double v) const {
  const Material& m = material_of(triangle);
  if (m.base_texture < 0) return m.base_color;
  const Eigen::Vector2d uv = hit_uv(mesh, triangle, u, v);
  return m.base_color.cwiseProduct(textures[m.base_texture].sample(uv.x(), uv.y()));
}

Rgb Scene::emitted(std::size_t triangle, double u, double v) const {
  const Material& m = material_of(triangle);
  if (m.emissive_texture < 0) return m.emissive;
  const Eigen::Vector2d uv = hit_uv(mesh, triangle, u, v);
  return m.emissive.cwiseProduct(textures[m.emissive_texture].sample(uv.x(), uv.y()));
}

Eigen::Vector3d Scene::lower() const {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const Eigen::Vector3d& p : mesh.positions) lo = lo.cwiseMin(p);
  return lo;
}
Eigen::Vector3d Scene::upper() const {
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-std::numeric_limits<double>::infinity());
  for (const Eigen::Vector3d& p : mesh.positions) hi = hi.cwiseMax(p);
  return hi;
}

Scene load_scene(const std::filesystem::path& path, UpAxis up) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) fail_input(path, "no such file");
  if (std::filesystem::is_directory(path, ec)) fail_input(path, "is a directory, not a scene file");
  const std::string bytes = read_input_file(path, "scene");
  const std::string ext = lowercase_extension(path);
  Scene s;
  if ((bytes.size() >= 4 && bytes.compare(0, 4, "glTF") == 0) || ext == ".gltf" || ext == ".glb") {
    if (up != UpAxis::y) fail_input(path, "--up z: glTF is +Y up by its specification (--up applies to OBJ files)");
    s = gltf_scene(bytes, path);
  } else {
    s = obj_scene(bytes, path, up);
  }
  s.face_normals.reserve(s.mesh.triangles.size());
  for (const Eigen::Vector3i& t : s.mesh.triangles) {
    const Eigen::Vector3d n =
        (s.mesh.positions[t[1]] - s.mesh.positions[t[0]]).cross(s.mesh.positions[t[2]] - s.mesh.positions[t[0]]);
    s.face_normals.push_back(n.normalized());
  }
  s.embree = fit::build_scene(s.mesh);
  return s;
}

}  // namespace shtool::scene
