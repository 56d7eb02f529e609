#include "fit/transfer.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <span>
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

// Azimuth of point k: 1/phi turns, consecutive points apart by the golden angle, the most
// irrational rotation.
double fibonacci_azimuth(int k, double a) {
  constexpr double kInvGolden = 0.61803398874989484820;
  double turn = k * kInvGolden + a;
  turn -= std::floor(turn);
  return 2.0 * std::numbers::pi * turn;
}

}  // namespace

Eigen::Vector3d uniform_fibonacci_direction(int k, int count, double a, double b) {
  const double z = 1.0 - (k + b) / count, phi = fibonacci_azimuth(k, a);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
}

Eigen::Vector3d sphere_fibonacci_direction(int k, int count, double a, double b) {
  const double z = 1.0 - 2.0 * (k + b) / count, phi = fibonacci_azimuth(k, a);
  const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z);
}

void orthonormal_basis(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b) {
  const double sign = std::copysign(1.0, n.z());
  const double a = -1.0 / (sign + n.z());
  const double c = n.x() * n.y() * a;
  t = Eigen::Vector3d(1.0 + sign * n.x() * n.x() * a, sign * c, -sign * n.x());
  b = Eigen::Vector3d(c, sign + n.y() * n.y() * a, -n.y());
}

Eigen::Vector3d cosine_fibonacci_direction(int k, int count, double a, double b) {
  const double u = (k + b) / count;
  const double phi = fibonacci_azimuth(k, a);
  const double r = std::sqrt(u);
  // Malley: uniform on the disk, lifted to the hemisphere, is cosine-weighted.
  return Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0, 1.0 - u)));
}

VertexRays::VertexRays(const Mesh& mesh, std::size_t v, std::uint64_t seed, int count, double offset)
    : VertexRays(mesh.positions[v], mesh.normals[v], v, seed, count, offset) {}

VertexRays::VertexRays(const Eigen::Vector3d& position, const Eigen::Vector3d& normal, std::uint64_t id,
                       std::uint64_t seed, int count, double offset)
    : normal_(normal), origin_(position + offset * normal), count_(count) {
  orthonormal_basis(normal_, tangent_, bitangent_);
  const RayTurn turn = ray_turn(seed, id);
  rotation_ = turn.rotation;
  shift_ = turn.shift;
}

Eigen::Vector3d VertexRays::direction(int k) const {
  const Eigen::Vector3d local = cosine_fibonacci_direction(k, count_, rotation_, shift_);
  return Eigen::Vector3d(local.x() * tangent_ + local.y() * bitangent_ + local.z() * normal_).normalized();
}

namespace {

void check_transfer_options(const TransferOptions& options) {
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
}

// Rows [first, first + count) of a set of surface points; row r casts the rays of point
// first + r, drawn from (seed, id), id the point's index or ids[index].
struct Points {
  std::span<const Eigen::Vector3d> positions, normals;
  std::span<const std::uint64_t> ids;  // empty: the index
  std::size_t first = 0, count = 0;

  VertexRays rays(std::size_t row, const TransferOptions& options, double offset) const {
    const std::size_t p = first + row;
    return VertexRays(positions[p], normals[p], ids.empty() ? p : ids[p], options.seed, options.rays, offset);
  }
};

// Rays are made and traced in chunks of this many, in order, so memory stays bounded
// whatever --rays asks (2^31 rays at once would need 200 GB of Embree records) and the
// sums keep the one order that makes results identical for any chunking of the work.
constexpr int kRayChunk = 4096;

// Directions first .. first + count - 1 of a point's rays, and for each the Embree record
// make(origin, direction) that one stream call (or one call per ray) traces.
template <class Record, class Make>
void point_rays(const VertexRays& cast, int first, int count, std::vector<Eigen::Vector3d>& dirs,
                std::vector<Record>& records, Make make) {
  dirs.resize(count);
  records.resize(count);
  for (int k = 0; k < count; ++k) {
    dirs[k] = cast.direction(first + k);
    records[k] = make(cast.origin(), dirs[k]);
  }
}

// Pass 0: direct transfer of every row.
std::vector<double> direct_pass(const EmbreeScene* scene, const Points& points, const TransferOptions& options,
                                int threads, double offset, std::size_t progress_base, std::size_t progress_total) {
  const int n2 = sh_count(options.order);
  const int rays = options.rays;
  std::vector<double> result(points.count * n2, 0.0);
  parallel_vertices(points.count, threads, progress_base, progress_total, options, [&](std::size_t row) {
    const VertexRays cast = points.rays(row, options, offset);
    // Each worker's scratch lives as long as its thread: nothing is allocated per vertex.
    thread_local std::vector<double> y, sum;
    thread_local std::vector<Eigen::Vector3d> dirs;
    thread_local std::vector<RTCRay> traced;
    y.resize(n2);
    sum.assign(n2, 0.0);
    for (int first = 0; first < rays; first += kRayChunk) {
      const int count = std::min(kRayChunk, rays - first);
      point_rays(cast, first, count, dirs, traced, [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
        return scene ? scene->ray(origin, dir) : embree_ray(origin, dir);
      });
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      if (scene && options.ray_streams)
        rtcOccluded1M(scene->scene, &context, traced.data(), static_cast<unsigned>(count), sizeof(RTCRay));
      else if (scene)
        for (RTCRay& ray : traced) rtcOccluded1(scene->scene, &context, &ray);
      for (int k = 0; k < count; ++k) {
        if (scene && traced[k].tfar < 0.0f) continue;  // blocked: Embree sets tfar to -inf
        eval_sh<double>(options.order, dirs[k], y);
        for (int i = 0; i < n2; ++i) sum[i] += y[i];
      }
    }
    for (int i = 0; i < n2; ++i) result[row * n2 + i] = sum[i] / rays;
  });
  return result;
}

// One bounce (Sloan et al. 2002, interreflected transfer): light leaving a hit point q
// after b-1 bounces is albedo * T_{b-1}(q) . L, so with cosine-weighted rays
// T_b(p) = albedo * mean over rays of [hit front face] T_{b-1}(q), with T_{b-1}(q)
// interpolated from the hit triangle's vertices (`previous`, every mesh vertex).
// Back-face hits (inside of the surface) contribute nothing.
std::vector<double> bounce_pass(const Mesh& mesh, const EmbreeScene& scene, const Points& points,
                                const std::vector<double>& previous, const TransferOptions& options, int threads,
                                double offset, std::size_t progress_base, std::size_t progress_total) {
  const int n2 = sh_count(options.order);
  const int rays = options.rays;
  std::vector<double> current(points.count * n2);
  parallel_vertices(points.count, threads, progress_base, progress_total, options, [&](std::size_t row) {
    const VertexRays cast = points.rays(row, options, offset);
    thread_local std::vector<double> sum;
    thread_local std::vector<Eigen::Vector3d> dirs;
    thread_local std::vector<RTCRayHit> hits;
    sum.assign(n2, 0.0);
    for (int first = 0; first < rays; first += kRayChunk) {
      const int count = std::min(kRayChunk, rays - first);
      point_rays(cast, first, count, dirs, hits, [&](const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
        RTCRayHit hit{};
        hit.ray = scene.ray(origin, dir);
        hit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        return hit;
      });
      RTCIntersectContext context;
      rtcInitIntersectContext(&context);
      if (options.ray_streams)
        rtcIntersect1M(scene.scene, &context, hits.data(), static_cast<unsigned>(count), sizeof(RTCRayHit));
      else
        for (RTCRayHit& hit : hits) rtcIntersect1(scene.scene, &context, &hit);
      for (int k = 0; k < count; ++k) {
        const RTCRayHit& hit = hits[k];
        if (hit.hit.geomID == RTC_INVALID_GEOMETRY_ID) continue;
        const Eigen::Vector3i& tri = mesh.triangles[hit.hit.primID];
        const Eigen::Vector3d ng =
            (mesh.positions[tri[1]] - mesh.positions[tri[0]]).cross(mesh.positions[tri[2]] - mesh.positions[tri[0]]);
        if (ng.dot(dirs[k]) >= 0.0) continue;
        const double w1 = hit.hit.u, w2 = hit.hit.v, w0 = 1.0 - w1 - w2;
        for (int i = 0; i < n2; ++i)
          sum[i] += w0 * previous[tri[0] * n2 + i] + w1 * previous[tri[1] * n2 + i] + w2 * previous[tri[2] * n2 + i];
      }
    }
    for (int i = 0; i < n2; ++i) current[row * n2 + i] = options.albedo * sum[i] / rays;
  });
  return current;
}

}  // namespace

std::vector<double> compute_transfer(const Mesh& mesh, const TransferOptions& options) {
  check_transfer_options(options);
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
  const double offset = options.offset_scale * mesh.bbox_diagonal();
  std::unique_ptr<EmbreeScene> scene;
  if (options.mode != TransferMode::unshadowed) scene = build_scene(mesh);
  const Points points{mesh.positions, mesh.normals, {}, first, nv};

  const int passes = options.mode == TransferMode::interreflected ? 1 + options.bounces : 1;
  const std::size_t progress_total = nv * passes;

  std::vector<double> result = direct_pass(scene.get(), points, options, threads, offset, 0, progress_total);
  if (passes == 1) return result;

  // A range reads the whole mesh's previous bounce from the gather step; its rows are the
  // ones one process computes, so the sums are too.
  auto whole = [&](std::vector<double> rows) {
    if (whole_mesh) return rows;
    std::vector<double> all = options.gather_bounce(std::move(rows));
    if (all.size() != mesh.positions.size() * n2)
      throw std::runtime_error("the gather step returned " + std::to_string(all.size()) + " values, not " +
                               std::to_string(mesh.positions.size() * n2));
    return all;
  };
  std::vector<double> previous = whole(result);
  for (int bounce = 1; bounce < passes; ++bounce) {
    const std::vector<double> current =
        bounce_pass(mesh, *scene, points, previous, options, threads, offset, nv * bounce, progress_total);
    for (std::size_t i = 0; i < result.size(); ++i) result[i] += current[i];
    if (bounce + 1 < passes) previous = whole(current);
  }
  return result;
}

std::vector<double> compute_transfer_at(const Mesh& mesh, std::span<const Eigen::Vector3d> positions,
                                        std::span<const Eigen::Vector3d> normals, std::span<const std::uint64_t> ids,
                                        const TransferOptions& options) {
  check_transfer_options(options);
  if (positions.size() != normals.size() || (!ids.empty() && ids.size() != positions.size()))
    throw InputError("sample points: " + std::to_string(positions.size()) + " positions, " +
                     std::to_string(normals.size()) + " normals and " + std::to_string(ids.size()) + " ids");
  if (positions.empty()) throw InputError("no sample points to simulate");
  const int threads = resolve_threads(options.threads);
  const double offset = options.offset_scale * mesh.bbox_diagonal();
  std::unique_ptr<EmbreeScene> scene;
  if (options.mode != TransferMode::unshadowed) scene = build_scene(mesh);
  const Points points{positions, normals, ids, 0, positions.size()};
  const int passes = options.mode == TransferMode::interreflected ? 1 + options.bounces : 1;
  const std::size_t progress_total = points.count * passes;
  std::vector<double> result = direct_pass(scene.get(), points, options, threads, offset, 0, progress_total);
  if (passes == 1) return result;
  // Bounce b at the points gathers bounce b-1 of the mesh's vertices, which the vertex
  // passes compute alongside: the same light a vertex bake interpolates at its hits.
  const Points vertices{mesh.positions, mesh.normals, {}, 0, mesh.positions.size()};
  TransferOptions quiet = options;
  quiet.progress = nullptr;
  std::vector<double> previous = direct_pass(scene.get(), vertices, quiet, threads, offset, 0, 0);
  for (int bounce = 1; bounce < passes; ++bounce) {
    const std::vector<double> current = bounce_pass(mesh, *scene, points, previous, options, threads, offset,
                                                    points.count * bounce, progress_total);
    for (std::size_t i = 0; i < result.size(); ++i) result[i] += current[i];
    if (bounce + 1 < passes) previous = bounce_pass(mesh, *scene, vertices, previous, quiet, threads, offset, 0, 0);
  }
  return result;
}

const EnumNames<TransferMode>& transfer_mode_names() {
  using enum TransferMode;
  static const EnumNames<TransferMode> names = {
      {"unshadowed", unshadowed},
      {"shadowed", shadowed},
      {"interreflected", interreflected}};
  return names;
}

}  // namespace shtool::fit
