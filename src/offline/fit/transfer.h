// Diffuse PRT transfer vectors per mesh vertex ([4] Sec. 4; Sloan et al. 2002):
//   t_p = (1/pi) integral over S^2 of V(p, s) max(n_p . s, 0) y(s) ds
// with V the visibility of the distant environment from p (shadowed) or 1
// (unshadowed); interreflected adds diffuse bounces with a constant albedo.
//
// Estimator: cosine-weighted directions (pdf max(n.s,0)/pi), so each ray contributes
// V(s) y(s) / rays and the unshadowed DC term is exact. The directions of a vertex are
// a spherical-Fibonacci set on the unit disk (Malley's method lifts it to the cosine-
// weighted hemisphere), rotated about the normal by an angle and shifted radially by a
// fraction taken from a hash of (seed, vertex index): stratified, deterministic, and
// without the correlated aliasing a set shared by all vertices would show.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "common/enum_names.h"
#include "common/input_error.h"
#include "fit/mesh.h"

namespace shtool::fit {

enum class TransferMode { unshadowed, shadowed, interreflected };
const EnumNames<TransferMode>& transfer_mode_names();

// Most diffuse bounces an interreflected simulation runs.
inline constexpr int kMaxBounces = 64;

struct TransferOptions {
  int order = 6;
  int rays = 1024;           // directions per vertex
  std::uint64_t seed = 1;
  TransferMode mode = TransferMode::shadowed;
  int bounces = 2;           // interreflected only
  double albedo = 0.8;       // interreflected only; in [0, 1)
  int threads = 0;           // 0: every core this process may use (usable_cores)
  // The rays of a vertex go to Embree as one stream (rtcOccluded1M for the shadow rays,
  // incoherent: 1.4x the rate of single rays on the bunny; rtcIntersect1M for the
  // bounces' closest hits); false: one rtcOccluded1 / rtcIntersect1 per ray, the
  // reference. The SH sums run in ray order either way and the tests hold the two to
  // the same bytes.
  bool ray_streams = true;
  // Ray origins move off the surface by offset_scale * bounding-box diagonal along the
  // vertex normal (avoids self-intersection with the vertex's own triangles).
  double offset_scale = 1e-4;
  // Only vertices [first_vertex, end_vertex) are simulated (a shard of a bake; the scene
  // is still the whole mesh). end_vertex past the mesh: up to its last vertex.
  std::size_t first_vertex = 0;
  std::size_t end_vertex = static_cast<std::size_t>(-1);
  // Interreflected transfer on a range: every bounce reads the previous bounce of every
  // vertex, which the other ranges computed. Called once after the direct pass and once
  // after each bounce but the last, with this range's rows of that pass (vertex-major);
  // returns the whole mesh's rows (e.g. every MPI rank's rows, gathered in vertex order).
  // Every process of a job calls it the same number of times. Without it an interreflected
  // range is refused.
  std::function<std::vector<double>(std::vector<double>)> gather_bounce{};
  // Called from worker 0 only with (vertices done by all workers, total); may be empty.
  std::function<void(std::size_t, std::size_t)> progress{};
};

// Transfer vectors, vertex-major: result[(v - first_vertex) * order^2 + i]. Bytes do not
// depend on the thread count or the range (each vertex's rays are drawn from (seed, v)
// and summed by one thread in a fixed order). Throws InputError on bad options, std::runtime_error if
// Embree fails.
std::vector<double> compute_transfer(const Mesh& mesh, const TransferOptions& options);

// The same at arbitrary surface points of the mesh (e.g. texel centres of its UV atlas):
// point p casts the rays a vertex would from (positions[p], unit normals[p]), rotated by
// a hash of (seed, ids[p]) (ids empty: p). The mesh is the scene; interreflected
// bounces gather the mesh's vertex bounces at their hits, as a vertex bake does. The
// vertex range options are ignored. compute_transfer is this with the mesh's vertices.
std::vector<double> compute_transfer_at(const Mesh& mesh, std::span<const Eigen::Vector3d> positions,
                                        std::span<const Eigen::Vector3d> normals, std::span<const std::uint64_t> ids,
                                        const TransferOptions& options);

// The rays vertex v casts in every pass: from just off the surface along the normal, in
// `count` cosine-weighted directions rotated by a hash of (seed, v).
class VertexRays {
 public:
  // offset: how far the origin moves along the normal.
  VertexRays(const Mesh& mesh, std::size_t v, std::uint64_t seed, int count, double offset);
  // Any surface point; `id` takes the vertex index's place in the hash. `normal` must
  // outlive the object.
  VertexRays(const Eigen::Vector3d& position, const Eigen::Vector3d& normal, std::uint64_t id, std::uint64_t seed,
             int count, double offset);
  const Eigen::Vector3d& origin() const { return origin_; }
  // Unit direction of ray k in [0, count).
  Eigen::Vector3d direction(int k) const;

 private:
  const Eigen::Vector3d& normal_;
  Eigen::Vector3d origin_, tangent_, bitangent_;
  int count_;
  double rotation_, shift_;
};

// The k-th of `count` cosine-weighted directions around +z before the per-vertex
// rotation: disk point (sqrt(u), 2 pi frac(k phi^-1 + a)) with u = (k + b) / count,
// lifted to the hemisphere. a, b in [0, 1) are the per-vertex rotation and shift.
Eigen::Vector3d cosine_fibonacci_direction(int k, int count, double a, double b);

// The same set uniform in solid angle on the hemisphere around +z: z = 1 - (k + b) / count
// and the same azimuths (the glossy transfer's rays, glossy/glossy_transfer.h).
Eigen::Vector3d uniform_fibonacci_direction(int k, int count, double a, double b);

// The same over the whole sphere: z = 1 - 2 (k + b) / count, the same azimuths (the
// probe directions of bake-probes, probes/probe_bake.h).
Eigen::Vector3d sphere_fibonacci_direction(int k, int count, double a, double b);

// Orthonormal basis (t, b) around unit n without a branch-dependent discontinuity at the
// poles (Duff et al., "Building an Orthonormal Basis, Revisited", JCGT 2017).
void orthonormal_basis(const Eigen::Vector3d& n, Eigen::Vector3d& t, Eigen::Vector3d& b);

}  // namespace shtool::fit
