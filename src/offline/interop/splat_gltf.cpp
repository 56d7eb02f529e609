#include "interop/splat_gltf.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include <Eigen/Dense>

#include "common/input_error.h"
#include "fit/gltf_model.h"

namespace shtool::interop {
namespace {

constexpr const char* kExtension = "KHR_gaussian_splatting";

std::string attribute(const std::string& name) { return std::string(kExtension).append(":").append(name); }
std::string sh_attribute(int l, int n) {
  return attribute("SH_DEGREE_" + std::to_string(l) + "_COEF_" + std::to_string(n));
}

// Accessor `index` as floats, `components` per element: float, or (normalized) integer
// types among `allowed` (the checked view of the mesh reader).
std::vector<float> read_accessor(const tinygltf::Model& model, int index, int type, const std::vector<int>& allowed,
                                 const std::string& what, const std::filesystem::path& path) {
  const fit::AccessorView v = fit::accessor_view(model, index, type, allowed, what, path);
  const bool normalized = model.accessors[index].normalized;
  if (v.component_type != TINYGLTF_COMPONENT_TYPE_FLOAT && !normalized && what.find("SCALE") == std::string::npos)
    fail_input(path, what + ": integer components must be normalized");
  const int components = tinygltf::GetNumComponentsInType(type);
  std::vector<float> out(v.count * static_cast<std::size_t>(components));
  for (std::size_t i = 0; i < v.count; ++i)
    for (int c = 0; c < components; ++c) out[i * components + c] = static_cast<float>(v.number(i, c, normalized));
  return out;
}

// The node's transform as a matrix (glTF: its matrix, column-major, or T R S with the
// rotation x, y, z, w, normalised here).
Eigen::Matrix4d local_matrix(const tinygltf::Node& n) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (n.matrix.size() == 16) {
    for (int k = 0; k < 16; ++k) m(k % 4, k / 4) = n.matrix[k];
    return m;
  }
  if (n.scale.size() == 3) m.topLeftCorner<3, 3>() = Eigen::Vector3d(n.scale[0], n.scale[1], n.scale[2]).asDiagonal();
  if (n.rotation.size() == 4) {
    const Eigen::Quaterniond q(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2]);
    m.topLeftCorner<3, 3>() = (q.norm() > 0 ? q.normalized().toRotationMatrix() : Eigen::Matrix3d::Identity()) *
                              m.topLeftCorner<3, 3>();
  }
  if (n.translation.size() == 3) m.topRightCorner<3, 1>() = Eigen::Vector3d(n.translation[0], n.translation[1], n.translation[2]);
  return m;
}

struct Reader {
  const tinygltf::Model& model;
  const std::filesystem::path& path;
  int threads;
  std::vector<SplatScene> parts;

  void primitive(const tinygltf::Primitive& p) {
    if (!p.extensions.count(kExtension)) return;
    if (p.mode != TINYGLTF_MODE_POINTS) fail_input(path, "a KHR_gaussian_splatting primitive whose mode is not POINTS");
    // The extension object: the kernel must be the 3DGS ellipse (another kernel gives the
    // attributes another meaning); the colour space is carried with the splats. Both are
    // required by the extension; files without them (older drafts) are taken as 3DGS's.
    const tinygltf::Value& object = p.extensions.at(kExtension);
    auto text = [&](const char* key) -> std::optional<std::string> {
      if (!object.IsObject() || !object.Has(key)) return std::nullopt;
      const tinygltf::Value& v = object.Get(key);
      if (!v.IsString()) fail_input(path, std::string("KHR_gaussian_splatting: '") + key + "' is not a string");
      return v.Get<std::string>();
    };
    if (const std::optional<std::string> kernel = text("kernel"); kernel && *kernel != "ellipse")
      fail_input(path, "KHR_gaussian_splatting kernel '" + *kernel +
                           "': shtool implements only the 'ellipse' kernel of 3DGS (another kernel's splats are not "
                           "Gaussians it can convert)");
    SplatColourSpace colour_space = SplatColourSpace::srgb_rec709_display;
    if (const std::optional<std::string> name = text("colorSpace")) {
      const std::optional<SplatColourSpace> known = parse_splat_colour_space(*name);
      if (!known)
        fail_input(path, "KHR_gaussian_splatting colorSpace '" + *name +
                             "': shtool knows srgb_rec709_display and lin_rec709_display");
      colour_space = *known;
    }
    auto find = [&](const std::string& name) -> int {
      const auto it = p.attributes.find(name);
      return it == p.attributes.end() ? -1 : it->second;
    };
    auto need = [&](const std::string& name) {
      const int i = find(name);
      if (i < 0) fail_input(path, "a splat primitive without " + name);
      return i;
    };
    constexpr int F = TINYGLTF_COMPONENT_TYPE_FLOAT, B = TINYGLTF_COMPONENT_TYPE_BYTE,
                  UB = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, S = TINYGLTF_COMPONENT_TYPE_SHORT,
                  US = TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    const std::vector<float> pos = read_accessor(model, need("POSITION"), TINYGLTF_TYPE_VEC3, {F}, "POSITION", path);
    const std::vector<float> rot =
        read_accessor(model, need(attribute("ROTATION")), TINYGLTF_TYPE_VEC4, {F, B, S}, attribute("ROTATION"), path);
    const std::vector<float> scale =
        read_accessor(model, need(attribute("SCALE")), TINYGLTF_TYPE_VEC3, {F, UB, US}, attribute("SCALE"), path);
    const std::vector<float> opacity =
        read_accessor(model, need(attribute("OPACITY")), TINYGLTF_TYPE_SCALAR, {F, UB, US}, attribute("OPACITY"), path);
    int degree = -1;
    for (int l = 0; l <= 3 && find(sh_attribute(l, 0)) >= 0; ++l) degree = l;
    if (degree < 0) fail_input(path, "a splat primitive without " + sh_attribute(0, 0));
    for (int l = degree + 1; l <= 4; ++l)
      for (int n = 0; n <= 2 * l; ++n)
        if (find(sh_attribute(l, n)) >= 0)
          fail_input(path, sh_attribute(l, n) + " without every coefficient of the lower degrees, or past degree 3");
    const std::size_t count = pos.size() / 3;
    SplatScene s;
    s.resize(count, degree);
    s.colour_space = colour_space;
    const std::size_t stride = s.sh_stride();
    for (int l = 0; l <= degree; ++l)
      for (int n = 0; n <= 2 * l; ++n) {
        const std::vector<float> c =
            read_accessor(model, need(sh_attribute(l, n)), TINYGLTF_TYPE_VEC3, {F}, sh_attribute(l, n), path);
        if (c.size() != 3 * count) fail_input(path, sh_attribute(l, n) + " has not one value per splat");
        for (std::size_t i = 0; i < count; ++i)
          for (int ch = 0; ch < 3; ++ch) s.sh[i * stride + 3 * (l * l + n) + ch] = c[3 * i + ch];
      }
    if (rot.size() != 4 * count || scale.size() != 3 * count || opacity.size() != count)
      fail_input(path, "the splat attributes have different counts");
    for (std::size_t i = 0; i < count; ++i) {
      for (int c = 0; c < 3; ++c) {
        s.position[3 * i + c] = pos[3 * i + c];
        const float sc = scale[3 * i + c];
        if (sc < 0) fail_input(path, "splat " + std::to_string(i) + ": a negative scale (the extension's scales are linear, >= 0)");
        s.log_scale[3 * i + c] = std::log(std::max(sc, 1e-30f));
      }
      s.rotation[4 * i] = rot[4 * i + 3];
      for (int c = 0; c < 3; ++c) s.rotation[4 * i + 1 + c] = rot[4 * i + c];
      const float a = opacity[i];
      if (!(a >= 0 && a <= 1)) fail_input(path, "splat " + std::to_string(i) + ": opacity outside [0, 1]");
      const float clamped = std::clamp(a, 1e-7f, 1 - 1e-7f);
      s.opacity[i] = std::log(clamped / (1 - clamped));
    }
    parts.push_back(std::move(s));
  }

  // The splats of primitives parts[from..] put where `world` (node to scene) puts them.
  // A similarity (rotation or reflection, uniform scale, translation) moves the
  // Gaussians exactly, their SH colours included; anything else would change the SH's
  // meaning (the extension turns colours by the node's rotation only) and is refused.
  void place(std::size_t from, const Eigen::Matrix4d& world, int index) {
    if (world.isIdentity(0)) return;
    const std::string node = "node " + std::to_string(index) + ": ";
    if (!world.allFinite() || !world.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 0))
      fail_input(path, node + "its transform is not finite or not affine");
    const Eigen::Matrix3d a = world.topLeftCorner<3, 3>();
    const double det = a.determinant();
    const double s = std::cbrt(std::abs(det));
    if (!(s > 0) || !std::isfinite(s)) fail_input(path, node + "its transform flattens its splats (determinant 0)");
    const Eigen::Matrix3d u = a / s;
    if (!(u.transpose() * u).isApprox(Eigen::Matrix3d::Identity(), 1e-4))
      fail_input(path, node + "a non-uniform scale or shear over its splats: only rotations, reflections, uniform scales and "
                        "translations are applied to Gaussians with SH colours");
    // The nearest orthogonal matrix (the polar factor): node values are often printed
    // to 6 or 7 digits.
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(u, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Eigen::Matrix3d orthogonal = svd.matrixU() * svd.matrixV().transpose();
    const Eigen::Vector3d t = world.topRightCorner<3, 1>();
    for (std::size_t k = from; k < parts.size(); ++k) transform_splat_scene(parts[k], orthogonal, s, t, threads);
  }

  void node(int index, std::vector<bool>& visited, int depth, const Eigen::Matrix4d& parent) {
    if (index < 0 || static_cast<std::size_t>(index) >= model.nodes.size())
      fail_input(path, "node " + std::to_string(index) + " does not exist");
    if (visited[index]) fail_input(path, "node " + std::to_string(index) + " is reached twice: glTF nodes form trees");
    if (depth > 1024) fail_input(path, "the node hierarchy is deeper than 1024");
    visited[index] = true;
    const tinygltf::Node& n = model.nodes[index];
    const Eigen::Matrix4d world = parent * local_matrix(n);
    if (n.mesh >= 0) {
      if (static_cast<std::size_t>(n.mesh) >= model.meshes.size())
        fail_input(path, "node " + std::to_string(index) + " names a mesh that does not exist");
      const std::size_t before = parts.size();
      for (const tinygltf::Primitive& p : model.meshes[n.mesh].primitives) primitive(p);
      if (parts.size() != before) place(before, world, index);
    }
    for (int child : n.children) node(child, visited, depth + 1, world);
  }
};


}  // namespace

SplatScene read_gltf_splats(const std::string& bytes, const std::filesystem::path& path, int threads) {
  const tinygltf::Model model = fit::parse_gltf(bytes, path, /*keep_images=*/false);
  // An extension listed as required changes what the file means (compressed or moved
  // data, other attributes): read as plain glTF its values would be wrong.
  for (const std::string& required : model.extensionsRequired)
    if (required != kExtension)
      fail_input(path, "it requires the glTF extension " + required +
                           " (extensionsRequired), which shtool does not implement: only " + kExtension + " is read");
  if (model.scenes.empty()) fail_input(path, "no scene");
  const int scene = model.defaultScene >= 0 ? model.defaultScene : 0;
  if (static_cast<std::size_t>(scene) >= model.scenes.size()) fail_input(path, "the default scene does not exist");
  Reader r{model, path, threads, {}};
  std::vector<bool> visited(model.nodes.size(), false);
  for (int n : model.scenes[scene].nodes) r.node(n, visited, 0, Eigen::Matrix4d::Identity());
  if (r.parts.empty()) fail_input(path, "no KHR_gaussian_splatting primitive in the default scene");
  SplatScene out = std::move(r.parts[0]);
  for (std::size_t k = 1; k < r.parts.size(); ++k) {
    const SplatScene& p = r.parts[k];
    if (p.degree != out.degree) fail_input(path, "splat primitives of different SH degrees");
    if (p.colour_space != out.colour_space)
      fail_input(path, std::string("splat primitives of different colour spaces (") +
                           splat_colour_space_name(out.colour_space) + ", " + splat_colour_space_name(p.colour_space) +
                           ")");
    out.count += p.count;
    out.position.insert(out.position.end(), p.position.begin(), p.position.end());
    out.log_scale.insert(out.log_scale.end(), p.log_scale.begin(), p.log_scale.end());
    out.rotation.insert(out.rotation.end(), p.rotation.begin(), p.rotation.end());
    out.opacity.insert(out.opacity.end(), p.opacity.begin(), p.opacity.end());
    out.sh.insert(out.sh.end(), p.sh.begin(), p.sh.end());
  }
  check_scene_finite(out, path.string());
  return out;
}

std::string write_gltf_splats(const SplatScene& s, bool binary) {
  const std::size_t n = s.count, stride = s.sh_stride();
  const double bytes = 4.0 * double(n) * double(3 + 4 + 3 + 1 + stride);
  if (bytes > double(std::numeric_limits<std::uint32_t>::max()) - (1 << 20))
    throw InputError("the scene would take " + std::to_string(bytes / 1e9) + " GB, past the 4 GB limit of glTF buffers");
  if (n == 0) throw InputError("glTF cannot hold an empty splat scene (accessors need count >= 1)");
  tinygltf::Model model;
  model.asset.version = "2.0";
  model.asset.generator = "shtool transform-splats";
  model.buffers.emplace_back();
  std::vector<float> rot(4 * n), scale(3 * n), opacity(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::array<float, 4> q = unit_rotation(&s.rotation[4 * i]);  // w x y z; glTF's order is x y z w
    for (int c = 0; c < 3; ++c) rot[4 * i + c] = q[1 + c];
    rot[4 * i + 3] = q[0];
    for (int c = 0; c < 3; ++c) {
      scale[3 * i + c] = std::exp(s.log_scale[3 * i + c]);
      // glTF holds no infinity; a log-scale past log(FLT_MAX) = 88.72 has no linear float.
      if (!std::isfinite(scale[3 * i + c]))
        throw InputError("splat " + std::to_string(i) + ": its log-scale " + message_number(s.log_scale[3 * i + c]) +
                         " gives a linear scale exp(" + message_number(s.log_scale[3 * i + c]) +
                         ") past float's range (3.4e+38), which glTF's KHR_gaussian_splatting:SCALE cannot hold");
    }
    opacity[i] = 1.0f / (1.0f + std::exp(-s.opacity[i]));
  }
  tinygltf::Primitive p;
  p.mode = TINYGLTF_MODE_POINTS;
  p.attributes["POSITION"] = fit::append_float_accessor(model, s.position, TINYGLTF_TYPE_VEC3, true);
  p.attributes[attribute("ROTATION")] = fit::append_float_accessor(model, rot, TINYGLTF_TYPE_VEC4, false);
  p.attributes[attribute("SCALE")] = fit::append_float_accessor(model, scale, TINYGLTF_TYPE_VEC3, false);
  p.attributes[attribute("OPACITY")] = fit::append_float_accessor(model, opacity, TINYGLTF_TYPE_SCALAR, false);
  std::vector<float> coef(3 * n);
  for (int l = 0; l <= s.degree; ++l)
    for (int k = 0; k <= 2 * l; ++k) {
      for (std::size_t i = 0; i < n; ++i)
        for (int c = 0; c < 3; ++c) coef[3 * i + c] = s.sh[i * stride + 3 * (l * l + k) + c];
      p.attributes[sh_attribute(l, k)] = fit::append_float_accessor(model, coef, TINYGLTF_TYPE_VEC3, false);
    }
  p.extensions[kExtension] = tinygltf::Value(tinygltf::Value::Object{
      {"kernel", tinygltf::Value(std::string("ellipse"))},
      {"colorSpace", tinygltf::Value(std::string(splat_colour_space_name(s.colour_space)))},
      {"projection", tinygltf::Value(std::string("perspective"))},
      {"sortingMethod", tinygltf::Value(std::string("cameraDistance"))}});
  model.extensionsUsed.push_back(kExtension);
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(std::move(p));
  return fit::write_single_mesh_gltf(model, std::move(mesh), binary);
}

}  // namespace shtool::interop
