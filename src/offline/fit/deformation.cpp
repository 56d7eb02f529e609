#include "fit/deformation.h"

#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include <Eigen/Dense>

#include "common/input_error.h"
#include "common/job_outputs.h"
#include "shtool/rotation.h"

namespace shtool::fit {
namespace {

// For every vertex, the first triangle that uses it (-1: none).
std::vector<int> first_triangles(const Mesh& mesh) {
  std::vector<int> first(mesh.positions.size(), -1);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int c = 0; c < 3; ++c) {
      int& f = first[mesh.triangles[t][c]];
      if (f < 0) f = static_cast<int>(t);
    }
  return first;
}

}  // namespace

namespace {

// The corner (1 or 2 steps from v in its first triangle) whose edge makes the larger angle
// with the rest normal; refused below sin = 1e-3 (a tangent that ill-conditioned would
// turn with rounding).
int tangent_step(const Mesh& rest, std::size_t v, const std::vector<int>& first_triangle) {
  const Eigen::Vector3d n = rest.normals[v];
  const Eigen::Vector3i tri = rest.triangles[first_triangle[v]];
  const int corner = tri[0] == int(v) ? 0 : tri[1] == int(v) ? 1 : 2;
  int best = 0;
  double best_sine = 0;
  for (int step : {1, 2}) {
    const Eigen::Vector3d e = rest.positions[tri[(corner + step) % 3]] - rest.positions[v];
    const double length = e.norm();
    const double sine = length > 0 ? (e - e.dot(n) * n).norm() / length : 0;
    if (sine > best_sine) {
      best_sine = sine;
      best = step;
    }
  }
  if (best_sine < 1e-3)
    throw InputError("vertex " + std::to_string(rest.source_index[v]) +
                     ": both edges of its first triangle are (nearly) parallel to its normal; no tangent frame");
  return best;
}

}  // namespace

Eigen::Matrix3d vertex_frame(const Mesh& mesh, std::size_t v, int first_triangle, int step) {
  const Eigen::Vector3d n = mesh.normals[v];
  const Eigen::Vector3i tri = mesh.triangles[first_triangle];
  const int corner = tri[0] == int(v) ? 0 : tri[1] == int(v) ? 1 : 2;
  const Eigen::Vector3d e = mesh.positions[tri[(corner + step) % 3]] - mesh.positions[v];
  const Eigen::Vector3d t = e - e.dot(n) * n;
  if (!(t.norm() > 1e-6 * e.norm()))
    throw InputError("vertex " + std::to_string(mesh.source_index[v]) +
                     ": its tangent edge is parallel to its normal in the pose; no tangent frame");
  Eigen::Matrix3d f;
  f.col(0) = t.normalized();
  f.col(1) = n.cross(f.col(0));
  f.col(2) = n;
  return f;
}

std::vector<Eigen::Matrix3d> rest_to_pose_rotations(const Mesh& rest, const Mesh& posed) {
  if (rest.positions.size() != posed.positions.size() || rest.triangles.size() != posed.triangles.size() ||
      rest.source_index != posed.source_index)
    throw InputError("--pose: " + std::to_string(posed.positions.size()) + " vertices and " +
                     std::to_string(posed.triangles.size()) + " triangles against the rest mesh's " +
                     std::to_string(rest.positions.size()) + " and " + std::to_string(rest.triangles.size()) +
                     ": a pose must have the rest mesh's topology" +
                     (rest.positions.size() == posed.positions.size()
                          ? " (a triangle the pose collapses to zero area is dropped when it is read)"
                          : ""));
  for (std::size_t t = 0; t < rest.triangles.size(); ++t)
    if (rest.triangles[t] != posed.triangles[t])
      throw InputError("--pose: triangle " + std::to_string(t) + " differs from the rest mesh's");
  const std::vector<Eigen::Matrix3d> from = vertex_frames(rest, rest), to = vertex_frames(rest, posed);
  std::vector<Eigen::Matrix3d> r(rest.positions.size());
  for (std::size_t v = 0; v < r.size(); ++v) r[v] = to[v] * from[v].transpose();
  return r;
}

std::vector<Eigen::Matrix3d> vertex_frames(const Mesh& rest, const Mesh& mesh) {
  const std::vector<int> first = first_triangles(rest);
  std::vector<Eigen::Matrix3d> f(mesh.positions.size());
  // One edge per vertex, chosen on the rest mesh, so that a pose's frames follow the rest ones.
  for (std::size_t v = 0; v < f.size(); ++v) f[v] = vertex_frame(mesh, v, first[v], tangent_step(rest, v, first));
  return f;
}

ZhFitTable<double> deform_fit(const ZhFitTable<double>& fit, const std::vector<Eigen::Matrix3d>& rotations) {
  ZhFitTable<double> out = fit;
  const std::size_t lobes = static_cast<std::size_t>(fit.lobes);
  ShRotation<double> band1(2, nullptr);
  for (std::size_t v = 0; v < fit.vertices; ++v) {
    for (std::size_t k = 0; k < lobes; ++k) {
      const Eigen::Vector3d a = rotations[v] * fit.axes[v * lobes + k];
      out.axes[v * lobes + k] = a.normalized();
    }
    if (fit.direct_count == 4) {
      if (!band1.set(rotations[v], RotationMethod::reference))
        throw std::logic_error("the reference rotation needs no table");
      const std::span<const double> in(fit.direct.data() + v * 4, 4);
      band1.apply(in, std::span<double>(out.direct.data() + v * 4, 4));
    }
  }
  return out;
}

ZhFitTable<double> fit_for_mesh(ZhFitTable<double> fit, const Mesh& mesh, const std::string& what) {
  const std::size_t v = mesh.positions.size();
  // fit-zh fits every vertex a triangle uses: one row each.
  if (fit.vertices != v)
    throw InputError(what + ": " + std::to_string(fit.vertices) + " rows for a mesh of " +
                     std::to_string(v) + " vertices (was it fitted on another mesh?)");
  if (fit.vertex_index.empty()) return fit;
  std::unordered_map<std::uint32_t, std::size_t> row_of;
  for (std::size_t r = 0; r < fit.vertices; ++r) row_of[fit.vertex_index[r]] = r;
  ZhFitTable<double> out = fit;
  const std::size_t n = static_cast<std::size_t>(fit.order), lobes = static_cast<std::size_t>(fit.lobes),
                    d = static_cast<std::size_t>(fit.direct_count);
  out.vertices = v;
  out.axes.resize(v * lobes);
  out.coeffs.resize(v * lobes * n);
  out.direct.resize(v * d);
  out.vertex_index.assign(mesh.source_index.begin(), mesh.source_index.end());
  for (std::size_t k = 0; k < v; ++k) {
    const auto it = row_of.find(mesh.source_index[k]);
    if (it == row_of.end())
      throw InputError(what + ": no row for OBJ vertex " + std::to_string(mesh.source_index[k]) +
                       " of the mesh (was it fitted on another mesh?)");
    const std::size_t r = it->second;
    std::copy_n(fit.axes.begin() + r * lobes, lobes, out.axes.begin() + k * lobes);
    std::copy_n(fit.coeffs.begin() + r * lobes * n, lobes * n, out.coeffs.begin() + k * lobes * n);
    std::copy_n(fit.direct.begin() + r * d, d, out.direct.begin() + k * d);
  }
  return out;
}

PosedMesh load_posed_mesh(JobOutputs& io, const std::filesystem::path& mesh, const std::filesystem::path& pose,
                          UpAxis up, NormalSource normals) {
  PosedMesh m{load_mesh(mesh, normals, up), std::nullopt, {}};
  io.inputs(m.rest.files, "a file of the mesh");
  if (!pose.empty()) {
    // A bake that required the file's normals still takes a pose without them (posing
    // tools drop them): the pose's own where it has them, computed otherwise.
    m.posed = load_mesh(pose, normals == NormalSource::file ? NormalSource::automatic : normals, up);
    io.inputs(m.posed->files, "a file of the --pose mesh");
    if (m.rest.normals_from_file == m.posed->normals_from_file) {
      m.rotations = rest_to_pose_rotations(m.rest, *m.posed);
    } else {
      const Mesh rest = load_mesh(mesh, NormalSource::computed, up),
                 posed = load_mesh(pose, NormalSource::computed, up);
      m.rotations = rest_to_pose_rotations(rest, posed);
    }
  }
  return m;
}

}  // namespace shtool::fit
