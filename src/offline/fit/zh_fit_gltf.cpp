#include "fit/zh_fit_gltf.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "common/finite.h"
#include "common/input_error.h"
#include "common/mesh_frame.h"
#include "fit/gltf_model.h"
#include "shtool/orthogonal_map.h"
#include "shtool/zh_fit_table.h"

namespace shtool::fit {

double transfer_dc_grey(double t00) {
  const double y00 = 0.5 / std::sqrt(std::numbers::pi);
  return std::clamp(t00 / y00, 0.0, 1.0);
}

namespace {

// One buffer, one buffer view per accessor: no view is shared, so none needs a byteStride,
// and every view starts on a 4-byte boundary as float accessors require.
class ModelBuilder {
 public:
  explicit ModelBuilder(tinygltf::Model& model) : model_(model) { model_.buffers.emplace_back(); }

  int floats(const std::vector<float>& values, int type, bool bounds = false) {
    // A double beyond float's range (a node translation of 1e39) became inf here.
    check_finite(std::span<const float>(values), "--gltf: a vertex attribute's value");
    return append_float_accessor(model_, values, type, bounds);
  }

  template <typename Index>
  int indices(const std::vector<Eigen::Vector3i>& triangles, int component_type) {
    std::vector<Index> index;
    index.reserve(triangles.size() * 3);
    for (const Eigen::Vector3i& t : triangles)
      for (int c = 0; c < 3; ++c) index.push_back(static_cast<Index>(t[c]));
    tinygltf::Accessor a;
    a.bufferView = append_buffer_view(model_, index.data(), index.size() * sizeof(Index), TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    a.componentType = component_type;
    a.type = TINYGLTF_TYPE_SCALAR;
    a.count = index.size();
    model_.accessors.push_back(a);
    return static_cast<int>(model_.accessors.size()) - 1;
  }

 private:
  tinygltf::Model& model_;
};

// Directions and points in glTF's frame (to_y_up), as floats.
std::vector<float> y_up_vec3s(const std::vector<Eigen::Vector3d>& v) {
  std::vector<float> out;
  out.reserve(v.size() * 3);
  for (const Eigen::Vector3d& x : v) {
    const Eigen::Vector3d e = to_y_up(x);
    for (int c = 0; c < 3; ++c) out.push_back(static_cast<float>(e[c]));
  }
  return out;
}

// `count` values starting at `first` of each vertex's `source`, as VEC4 rows, zero past
// the end of the source.
template <typename Source>
std::vector<float> vec4_rows(std::size_t vertices, std::size_t first, const Source& source) {
  std::vector<float> out(vertices * 4, 0.0f);
  for (std::size_t v = 0; v < vertices; ++v) {
    const std::span<const double> values = source(v);
    for (std::size_t c = 0; c < 4 && first + c < values.size(); ++c)
      out[v * 4 + c] = static_cast<float>(values[first + c]);
  }
  return out;
}

}  // namespace

std::string zh_fit_glb(const Mesh& mesh, const ZhFitTable<double>& fits, std::span<const double> transfer_dc,
                       const std::string& generator) {
  const std::size_t n = mesh.positions.size();
  const int order = fits.order, lobes = fits.lobes;
  const bool direct = fits.direct_count > 0;
  if (fits.vertices != n || transfer_dc.size() != n)
    throw InputError("--gltf: " + std::to_string(fits.vertices) + " fits and " + std::to_string(transfer_dc.size()) +
                     " transfer vectors for a mesh of " + std::to_string(n) + " vertices");
  const std::size_t coeff_groups = (static_cast<std::size_t>(order) + 3) / 4;
  const std::size_t floats_per_vertex = 9 + lobes * (3 + 4 * coeff_groups) + (direct ? 4 : 0);
  // GLB lengths are 32-bit; the JSON chunk is far below the 1 MB margin.
  const double bytes = 4.0 * (double(n) * floats_per_vertex + 3.0 * double(mesh.triangles.size()));
  if (bytes > double(std::numeric_limits<std::uint32_t>::max()) - (1 << 20))
    throw InputError("--gltf: the mesh and its fit would take " + std::to_string(bytes / 1e9) +
                     " GB, past the 4 GB limit of a .glb");

  tinygltf::Model model;
  ModelBuilder b(model);
  tinygltf::Primitive p;
  p.mode = TINYGLTF_MODE_TRIANGLES;
  p.attributes["POSITION"] = b.floats(y_up_vec3s(mesh.positions), TINYGLTF_TYPE_VEC3, true);
  p.attributes["NORMAL"] = b.floats(y_up_vec3s(mesh.normals), TINYGLTF_TYPE_VEC3);
  std::vector<float> grey(n * 3);
  for (std::size_t v = 0; v < n; ++v)
    std::fill_n(grey.begin() + v * 3, 3, static_cast<float>(transfer_dc_grey(transfer_dc[v])));
  p.attributes["COLOR_0"] = b.floats(grey, TINYGLTF_TYPE_VEC3);
  for (int k = 0; k < lobes; ++k) {
    std::vector<Eigen::Vector3d> axis(n);
    for (std::size_t v = 0; v < n; ++v) {
      const auto& s = fits.axes_of(v)[k];
      axis[v] = Eigen::Vector3d(s[0], s[1], s[2]);
    }
    const std::string lobe = std::to_string(k);
    p.attributes["_ZH_AXIS_" + lobe] = b.floats(y_up_vec3s(axis), TINYGLTF_TYPE_VEC3);
    for (std::size_t j = 0; j < coeff_groups; ++j)
      p.attributes["_ZH_COEFFS_" + lobe + "_" + std::to_string(j)] = b.floats(
          vec4_rows(n, 4 * j, [&](std::size_t v) { return fits.coeffs_of(v).subspan(std::size_t(k) * order, order); }),
          TINYGLTF_TYPE_VEC4);
  }
  if (direct) {
    // The stored DC and linear terms are SH coefficients of a function of direction:
    // carried into glTF's frame by the same map as the axes (band 0 is unchanged).
    // One call for every vertex: coefficient i of vertex v at moved[i * n + v].
    const std::size_t d = static_cast<std::size_t>(fits.direct_count);
    std::vector<double> moved(n * d);
    for (std::size_t v = 0; v < n; ++v)
      for (std::size_t i = 0; i < d; ++i) moved[i * n + v] = fits.direct_of(v)[i];
    if (d == 4 && !apply_orthogonal_map(to_y_up_matrix(), static_cast<int>(n), moved))
      throw std::logic_error("to_y_up_matrix is orthogonal");
    std::vector<double> row(d);
    p.attributes["_ZH_DIRECT"] = b.floats(vec4_rows(n, 0,
                                                    [&](std::size_t v) {
                                                      for (std::size_t i = 0; i < d; ++i) row[i] = moved[i * n + v];
                                                      return std::span<const double>(row);
                                                    }),
                                          TINYGLTF_TYPE_VEC4);
  }
  // Indices above the type's maximum would be read as primitive restarts.
  p.indices = n < 0xFFFF ? b.indices<std::uint16_t>(mesh.triangles, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT)
                         : b.indices<std::uint32_t>(mesh.triangles, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT);

  tinygltf::Mesh m;
  m.name = std::string(kZhFitKind);
  m.primitives.push_back(std::move(p));
  // What an engine needs to read the attributes without counting them.
  tinygltf::Value::Object fit{
      {"order", tinygltf::Value(order)}, {"lobes", tinygltf::Value(lobes)}, {"direct", tinygltf::Value(direct)}};
  m.extras = tinygltf::Value(tinygltf::Value::Object{{"shtool_zh_fit", tinygltf::Value(std::move(fit))}});
  model.asset.version = "2.0";
  model.asset.generator = generator;
  return write_single_mesh_gltf(model, std::move(m), true);
}

}  // namespace shtool::fit
