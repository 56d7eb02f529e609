#include "glossy/glossy_transfer.h"

#include <cmath>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>

#include <embree3/rtcore.h>

#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/random.h"
#include "fit/transfer.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"

namespace shtool::glossy {

Eigen::MatrixXd transfer_matrix(const fit::Mesh& mesh, std::size_t v, const Eigen::Matrix3d& frame,
                                const GlossyTransferOptions& options, double offset, const fit::EmbreeScene* scene) {
  const int n2 = sh_count(options.order), rays = options.rays;
  // Unoccluded, T is the lighting seen from the local frame: y(F^T s) = T y(s). ShRotation
  // by F takes f to f(F^T s), so row j of T is the rotation of the unit vector e_j.
  Eigen::MatrixXd t(n2, n2);
  {
    thread_local std::vector<double> unit, turned;
    unit.assign(n2, 0.0);
    turned.resize(n2);
    ShRotation<double> rotation(options.order, nullptr);
    if (!rotation.set(frame, RotationMethod::reference)) throw std::logic_error("the reference rotation needs no table");
    for (int j = 0; j < n2; ++j) {
      unit[j] = 1.0;
      rotation.apply(unit, turned);
      unit[j] = 0.0;
      for (int k = 0; k < n2; ++k) t(j, k) = turned[k];
    }
  }
  if (!scene) return t;
  const RayTurn turn = ray_turn(options.seed, v);
  const double turn0 = turn.rotation, shift = turn.shift;
  const Eigen::Vector3d origin = mesh.positions[v] + offset * mesh.normals[v];
  // The rays and SH scratch live per worker thread (T, its rotation part and M' are
  // allocated per vertex: small beside the rays).
  thread_local std::vector<Eigen::Vector3d> local, scene_dir;
  thread_local std::vector<RTCRay> traced;
  thread_local Eigen::VectorXd y_local, y_scene;
  local.resize(rays);
  scene_dir.resize(rays);
  traced.resize(rays);
  y_local.resize(n2);
  y_scene.resize(n2);
  for (int k = 0; k < rays; ++k) {
    local[k] = fit::uniform_fibonacci_direction(k, rays, turn0, shift);
    scene_dir[k] = (frame * local[k]).normalized();
    traced[k] = scene->ray(origin, scene_dir[k]);
  }
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded1M(scene->scene, &context, traced.data(), static_cast<unsigned>(rays), sizeof(RTCRay));
  const double weight = 2.0 * std::numbers::pi / rays;
  for (int k = 0; k < rays; ++k) {
    if (!(traced[k].tfar < 0.0f)) continue;  // not blocked: Embree sets tfar to -inf on a hit
    eval_sh<double>(options.order, local[k], std::span<double>(y_local.data(), n2));
    eval_sh<double>(options.order, scene_dir[k], std::span<double>(y_scene.data(), n2));
    t.noalias() -= weight * y_local * y_scene.transpose();
  }
  return t;
}

GlossyTransfer glossy_transfer(const fit::Mesh& mesh, const std::vector<Eigen::Matrix3d>& frames,
                               const Eigen::MatrixXd& factors_rows, const Eigen::MatrixXd& brdf_gram,
                               const GlossyTransferOptions& options) {
  if (!is_supported_order(options.order))
    throw InputError("order " + std::to_string(options.order) + " is not supported");
  if (options.rays < 1) throw InputError("rays must be at least 1, got " + std::to_string(options.rays));
  const std::size_t count = mesh.positions.size();
  const int n2 = sh_count(options.order), nb = static_cast<int>(factors_rows.rows());
  std::unique_ptr<fit::EmbreeScene> scene;
  if (options.shadowed) scene = fit::build_scene(mesh);
  const double offset = options.offset_scale * mesh.bbox_diagonal();
  GlossyTransfer out;
  out.rows.assign(count * nb * n2, 0.0);
  std::vector<double> exit_norm2(count), rows_norm2(count);
  parallel_for(count, resolve_threads(options.threads), [&](std::size_t v) {
    const Eigen::MatrixXd t = transfer_matrix(mesh, v, frames[v], options, offset, scene.get());
    const Eigen::MatrixXd m = factors_rows * t;
    for (int j = 0; j < nb; ++j)
      for (int k = 0; k < n2; ++k) out.rows[(v * nb + j) * n2 + k] = m(j, k);
    exit_norm2[v] = (t.transpose() * brdf_gram * t).trace();
    rows_norm2[v] = m.squaredNorm();
  });
  // Summed in vertex order, whatever the thread count.
  for (std::size_t v = 0; v < count; ++v) {
    out.exit_norm2 += exit_norm2[v];
    out.rows_norm2 += rows_norm2[v];
  }
  return out;
}

}  // namespace shtool::glossy
