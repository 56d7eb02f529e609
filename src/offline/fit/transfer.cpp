#include "fit/transfer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>

#include <embree3/rtcore.h>

#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/random.h"
#include "fit/embree_scene.h"
#include "shtool/sh.h"

namespace shtool::fit {
namespace {

// Orthonormal basis around n without a branch-dependent discontinuity at the poles
// (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 2017).
void orthonormal_basis(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

// Runs body(v) for every vertex (common/parallel_for.h: the partition never changes
// what is computed), reporting progress through the pass's share of the total.
template <class Body>
void parallel_vertices(std::size_t count, int threads, std::size_t progress_base, std::size_t progress_total,
                       const TransferOptions& options, Body body) {
  std::function<void(std::size_t, std::size_t)> progress;
  if (options.progress)
    progress = [&](std::size_t done, std::size_t) { options.progress(progress_base + done, progress_total); };
  parallel_for(count, threads, body, progress);
}

}  // namespace

Eigen::Vector3d cosine_fibonacci_direction(int k, int count, double a, double b) {
  // 1/phi: consecutive points turn by the golden angle, the most irrational rotation.
  constexpr double kInvGolden = 0.61803398874989484820;
  const double u = (k + b) / count;
  double turn = k * kInvGolden + a;
  turn -= std::floor(turn);
  const double phi = 2.0 * std::numbers::pi * turn;
  const double r = std::sqrt(u);
  // Malley: uniform on the disk, lifted to the hemisphere, is cosine-weighted.
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - u)));
}

VertexRays::VertexRays(const Mesh& mesh, std::size_t v, std::uint64_t seed, int count, double offset)
    : normal_(mesh.normals[v]), origin_(mesh.positions[v] + offset * mesh.normals[v]), count_(count) {
  orthonormal_basis(normal_, tangent_, bitangent_);
  const std::uint64_t h = splitmix64(seed ^ splitmix64(static_cast<std::uint64_t>(v)));
  rotation_ = unit_double(h);
  shift_ = unit_double(splitmix64(h));
}

Eigen::Vector3d VertexRays::direction(int k) const {
  const Eigen::Vector3d local = cosine_fibonacci_direction(k, count_, rotation_, shift_);
  return Eigen::Vector3d(local.x() * tangent_ + local.y() * bitangent_ + local.z() * normal_).normalized();
}

std::vector<double> compute_transfer(const Mesh& mesh, const TransferOptions& options) {
  if (!is_supported_order(options.order))
    throw InputError("order " + std::to_string(options.order) + " is not supported");
  if (options.rays < 1) throw InputError("rays must be at least 1, got " + std::to_string(options.rays));
  if (options.mode == TransferMode::interreflected) {
    // Each bounce is a full pass over the mesh and the albedo^b terms vanish long before
    // this many; the cap also keeps 1 + bounces far from overflow.
    if (options.bounces < 1 || options.bounces > kMaxBounces)
      throw InputError("bounces must be in 1.." + std::to_string(kMaxBounces) + ", got " +
                       std::to_string(options.bounces));
    if (!(options.albedo >= 0.0 && options.albedo < 1.0))
      throw InputError("albedo must be in [0, 1), got " + std::to_string(options.albedo));
  }
  if (mesh.positions.size() != mesh.normals.size())
    throw InputError("mesh has " + std::to_string(mesh.positions.size()) + " positions but " +
                                std::to_string(mesh.normals.size()) + " normals");
  const int threads = resolve_threads(options.threads);

  const std::size_t first = options.first_vertex;
  const std::size_t end = std::min(options.end_vertex, mesh.positions.size());
  if (first >= end)
    throw InputError("vertex range [" + std::to_string(first) + ", " + std::to_string(end) + ") of a mesh of " +
                     std::to_string(mesh.positions.size()) + " vertices is empty");
  const bool whole_mesh = first == 0 && end == mesh.positions.size();
  if (options.mode == TransferMode::interreflected && !whole_mesh && !options.gather_bounce)
    throw InputError("interreflected transfer needs every vertex's previous bounce: it cannot simulate a range "
                     "without a gather step");
  const std::size_t nv = end - first;
  const int n2 = sh_count(options.order);
  const int rays = options.rays;
  const double offset = options.offset_scale * mesh.bbox_diagonal();
  std::unique_ptr<EmbreeScene> scene;
  if (options.mode != TransferMode::unshadowed) scene = build_scene(mesh);

  const int passes = options.mode == TransferMode::interreflected ? 1 + options.bounces : 1;
  const std::size_t progress_total = nv * passes;

  std::vector<double> result(nv * n2, 0.0);
  // Pass 0: direct transfer.
  parallel_vertices(nv, threads, 0, progress_total, options, [&](std::size_t row) {
    const VertexRays cast(mesh, first + row, options.seed, rays, offset);
    // Each worker's scratch lives as long as its thread: nothing is allocated per vertex.
    thread_local std::vector<double> y, sum;
    thread_local std::vector<Eigen::Vector3d> dirs;
    thread_local std::vector<RTCRay> traced;
    y.resize(n2);
    sum.assign(n2, 0.0);
    dirs.resize(rays);
    traced.resize(rays);
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int k = 0; k < rays; ++k) {
      dirs[k] = cast.direction(k);
      traced[k] = embree_ray(cast.origin(), dirs[k]);
    }
    if (scene && options.ray_streams)
      rtcOccluded1M(scene->scene, &context, traced.data(), static_cast<unsigned>(rays), sizeof(RTCRay));
    else if (scene)
      for (RTCRay& ray : traced) rtcOccluded1(scene->scene, &context, &ray);
    for (int k = 0; k < rays; ++k) {
      if (scene && traced[k].tfar < 0.0f) continue;  // blocked: Embree sets tfar to -inf
      eval_sh<double>(options.order, dirs[k], y);
      for (int i = 0; i < n2; ++i) sum[i] += y[i];
    }
    for (int i = 0; i < n2; ++i) result[row * n2 + i] = sum[i] / rays;
  });
  if (passes == 1) return result;

  // Bounces (Sloan et al. 2002, interreflected transfer): light leaving a hit point q
  // after b-1 bounces is albedo * T_{b-1}(q) . L, so with cosine-weighted rays
  // T_b(p) = albedo * mean over rays of [hit front face] T_{b-1}(q), with T_{b-1}(q)
  // interpolated from the hit triangle's vertices. Back-face hits (inside of the
  // surface) contribute nothing. A range reads the whole mesh's previous bounce from
  // the gather step; its rows are the ones one process computes, so the sums are too.
  auto whole = [&](std::vector<double> rows) {
    if (whole_mesh) return rows;
    std::vector<double> all = options.gather_bounce(std::move(rows));
    if (all.size() != mesh.positions.size() * n2)
      throw std::runtime_error("the gather step returned " + std::to_string(all.size()) + " values, not " +
                               std::to_string(mesh.positions.size() * n2));
    return all;
  };
  std::vector<double> previous = whole(result), current(nv * n2);
  for (int bounce = 1; bounce < passes; ++bounce) {
    parallel_vertices(nv, threads, nv * bounce, progress_total, options, [&](std::size_t row) {
      const VertexRays cast(mesh, first + row, options.seed, rays, offset);
      thread_local std::vector<double> sum;
      thread_local std::vector<Eigen::Vector3d> dirs;
      thread_local std::vector<RTCRayHit> hits;
      sum.assign(n2, 0.0);
      dirs.resize(rays);
      hits.resize(rays);
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      for (int k = 0; k < rays; ++k) {
        dirs[k] = cast.direction(k);
        hits[k] = RTCRayHit{};
        hits[k].ray = embree_ray(cast.origin(), dirs[k]);
        hits[k].hit.geomID = RTC_INVALID_GEOMETRY_ID;
      }
      if (options.ray_streams)
        rtcIntersect1M(scene->scene, &context, hits.data(), static_cast<unsigned>(rays), sizeof(RTCRayHit));
      else
        for (RTCRayHit& hit : hits) rtcIntersect1(scene->scene, &context, &hit);
      for (int k = 0; k < rays; ++k) {
        const RTCRayHit& hit = hits[k];
        if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        const Eigen::Vector3i& tri = mesh.triangles[hit.hit.primID];
        const Eigen::Vector3d ng = (mesh.positions[tri[1]] - mesh.positions[tri[0]])
                                       .cross(mesh.positions[tri[2]] - mesh.positions[tri[0]]);
        if (ng.dot(dirs[k]) >= 0.0) continue;
        const double w1 = hit.hit.u, w2 = hit.hit.v, w0 = 1.0 - w1 - w2;
        for (int i = 0; i < n2; ++i)
          sum[i] += w0 * previous[tri[0] * n2 + i] + w1 * previous[tri[1] * n2 + i] + w2 * previous[tri[2] * n2 + i];
      }
      for (int i = 0; i < n2; ++i) current[row * n2 + i] = options.albedo * sum[i] / rays;
    });
    for (std::size_t i = 0; i < result.size(); ++i) result[i] += current[i];
    if (bounce + 1 < passes) previous = whole(current);
  }
  return result;
}

}  // namespace shtool::fit
