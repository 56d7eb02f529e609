#include "probes/probe_bake.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <span>

#include <Eigen/Geometry>

#include "common/parallel_for.h"
#include "common/random.h"
#include "fit/transfer.h"
#include "shtool/sh.h"

namespace shtool::probes {
namespace {

constexpr double kPi = std::numbers::pi;
using scene::Rgb;

struct Hit {
  bool hit = false;
  std::size_t triangle = 0;
  double t = 0, u = 0, v = 0;
};

Hit intersect(const scene::Scene& s, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir) {
  RTCRayHit rh{};
  rh.ray = s.embree->ray(origin, dir);
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcIntersect1(s.embree->scene, &ctx, &rh);
  Hit h;
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return h;
  h.hit = true;
  h.triangle = rh.hit.primID;
  h.t = rh.ray.tfar;
  h.u = rh.hit.u;
  h.v = rh.hit.v;
  return h;
}

bool occluded(const scene::Scene& s, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double tfar) {
  RTCRay ray = s.embree->ray(origin, dir);
  if (std::isfinite(tfar)) ray.tfar = static_cast<float>(tfar);
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  rtcOccluded1(s.embree->scene, &ctx, &ray);
  return ray.tfar < 0;  // Embree sets -inf on a hit
}

// Radiance of the environment toward -dir, i.e. arriving from dir.
Rgb environment_radiance(const Environment& env, const Eigen::Vector3d& dir, std::vector<double>& y) {
  if (env.order == 0) return Rgb::Zero();
  eval_sh<double>(env.order, dir, y);
  Rgb l = Rgb::Zero();
  for (int k = 0; k < env.order * env.order; ++k)
    for (int c = 0; c < 3; ++c) l[c] += env.coefficients[k * 3 + c] * y[k];
  return l;
}

// The emissive triangles for next-event estimation, built once per bake: triangle t is
// chosen with probability P_t proportional to its area times its emitted power (the sum
// of R, G and B of its emitted radiance at four points: the centroid and the midpoints
// toward the corners), then a point uniformly on it, so the area density is P_t / A_t.
// A triangle whose four points emit nothing has P_t = 0: its light then comes only from
// the paths that hit it (their MIS weight is 1), so the estimate stays unbiased.
struct Emitters {
  std::vector<std::size_t> triangles;  // the emissive ones
  std::vector<double> cdf;             // cumulative P over `triangles`, last 1
  std::vector<double> area_density;    // per scene triangle: P_t / A_t (0: not sampled)

  explicit Emitters(const scene::Scene& s) {
    const std::size_t n = s.mesh.triangles.size();
    area_density.assign(n, 0.0);
    std::vector<double> weight;
    double total = 0;
    for (std::size_t t = 0; t < n; ++t) {
      const double area = triangle_area(s, t);
      if (!(area > 0)) continue;
      const Rgb e = s.emitted(t, 1.0 / 3, 1.0 / 3) + s.emitted(t, 1.0 / 6, 1.0 / 6) + s.emitted(t, 2.0 / 3, 1.0 / 6) +
                    s.emitted(t, 1.0 / 6, 2.0 / 3);
      const double w = area * std::max(0.0, e.sum());
      if (!(w > 0)) continue;
      triangles.push_back(t);
      weight.push_back(w);
      total += w;
    }
    double running = 0;
    for (std::size_t i = 0; i < triangles.size(); ++i) {
      running += weight[i];
      cdf.push_back(i + 1 == triangles.size() ? 1.0 : running / total);
      area_density[triangles[i]] = weight[i] / total / triangle_area(s, triangles[i]);
    }
  }

  static double triangle_area(const scene::Scene& s, std::size_t t) {
    const Eigen::Vector3i& i = s.mesh.triangles[t];
    const Eigen::Vector3d& a = s.mesh.positions[i[0]];
    return 0.5 * (s.mesh.positions[i[1]] - a).cross(s.mesh.positions[i[2]] - a).norm();
  }

  // The emitter index of uniform u in [0, 1).
  std::size_t pick(double u) const {
    const auto it = std::upper_bound(cdf.begin(), cdf.end(), u);
    return static_cast<std::size_t>(std::min<std::ptrdiff_t>(it - cdf.begin(), static_cast<std::ptrdiff_t>(cdf.size()) - 1));
  }
};

// The power heuristic (beta = 2) of a sample from density `a` against the other
// technique's density `b`, one sample each (Veach 1997, 9.2.1).
double power_heuristic(double a, double b) {
  const double a2 = a * a, b2 = b * b;
  return a2 + b2 > 0 ? a2 / (a2 + b2) : 0.0;
}

struct Tracer {
  const scene::Scene& s;
  const ProbeGridSpec& spec;
  const Environment& env;
  double eps;  // ray offset off surfaces: a few float ulps of the scene's extent
  const Emitters& emitters;

  // The shading normal at a hit on the side of the oriented geometric normal n: the
  // vertex normals of the file interpolated at (u, v), or n itself when the file has none
  // (flat shading) or they cancel.
  Eigen::Vector3d shading_normal(std::size_t triangle, double u, double v, const Eigen::Vector3d& n) const {
    if (!s.mesh.normals_from_file) return n;
    const Eigen::Vector3i& i = s.mesh.triangles[triangle];
    Eigen::Vector3d ns = (1 - u - v) * s.mesh.normals[i[0]] + u * s.mesh.normals[i[1]] + v * s.mesh.normals[i[2]];
    const double length = ns.norm();
    if (!(length > 0)) return n;
    ns /= length;
    return ns.dot(n) < 0 ? Eigen::Vector3d(-ns) : ns;
  }

  // Next-event estimation toward one point on an emissive triangle from x (shading normal
  // n, geometric normal ng on the same side, ray origin xo), the contribution of light arriving at x weighted against the cosine
  // sampling of the continuation that could have found the same point.
  Rgb emitter_sample(const Eigen::Vector3d& xo, const Eigen::Vector3d& n, const Eigen::Vector3d& ng,
                     SplitMixStream& rng, std::uint64_t& rays) const {
    const double u0 = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
    const std::size_t t = emitters.triangles[emitters.pick(u0)];
    // Uniform on the triangle: Embree's barycentrics (u, v) of p = (1-u-v) p0 + u p1 + v p2.
    const double r = std::sqrt(u1), bu = r * (1 - u2), bv = r * u2;
    const Eigen::Vector3i& i = s.mesh.triangles[t];
    const Eigen::Vector3d y =
        (1 - bu - bv) * s.mesh.positions[i[0]] + bu * s.mesh.positions[i[1]] + bv * s.mesh.positions[i[2]];
    const Eigen::Vector3d d = y - xo;
    const double dist2 = d.squaredNorm(), dist = std::sqrt(dist2);
    if (!(dist > 2 * eps)) return Rgb::Zero();
    const Eigen::Vector3d wi = d / dist;
    const double cos_x = n.dot(wi), cos_y = -s.face_normals[t].dot(wi);
    if (!(cos_x > 0) || !(ng.dot(wi) > 0) || cos_y == 0 || (cos_y < 0 && !s.material_of(t).double_sided)) return Rgb::Zero();
    const Rgb le = s.emitted(t, bu, bv);
    if (!(le.maxCoeff() > 0)) return Rgb::Zero();
    const double light_pdf = emitters.area_density[t] * dist2 / std::abs(cos_y);  // per solid angle
    const double weight = power_heuristic(light_pdf, cos_x / kPi);
    ++rays;
    if (occluded(s, xo, wi, dist - 2 * eps)) return Rgb::Zero();
    return le * (cos_x / kPi * weight / light_pdf);
  }

  // Radiance arriving at `origin` from `dir`. escaped: the first ray left the scene;
  // back_face: it hit the back of a single-sided triangle.
  Rgb radiance(const Eigen::Vector3d& origin0, const Eigen::Vector3d& dir0, SplitMixStream& rng, bool& escaped,
               bool& back_face, std::uint64_t& rays, std::vector<double>& y) const {
    Eigen::Vector3d origin = origin0, dir = dir0;
    Rgb throughput = Rgb::Ones(), total = Rgb::Zero();
    escaped = back_face = false;
    const bool sample_emitters = spec.sample_emitters && !emitters.triangles.empty();
    double continuation_pdf = 0;  // solid-angle density of `dir` (after the first hit)
    for (int depth = 0;; ++depth) {
      const Hit h = intersect(s, origin, dir);
      ++rays;
      if (!h.hit) {
        if (depth == 0) escaped = true;
        else total += throughput.cwiseProduct(environment_radiance(env, dir, y));
        break;
      }
      const Eigen::Vector3d& ng = s.face_normals[h.triangle];
      const bool front = ng.dot(dir) < 0;
      const scene::Material& m = s.material_of(h.triangle);
      if (!front && !m.double_sided) {
        if (depth == 0) back_face = true;
        break;
      }
      const Eigen::Vector3d n = front ? ng : Eigen::Vector3d(-ng);
      // The probe's own directions are a fixed set: what they see counts whole. A
      // continuation's hit on an emitter shares it with the emitter sample of its vertex.
      double emission_weight = 1;
      if (depth > 0 && sample_emitters && emitters.area_density[h.triangle] > 0) {
        const double cos_y = std::abs(ng.dot(dir));
        const double light_pdf = cos_y > 0 ? emitters.area_density[h.triangle] * h.t * h.t / cos_y : 0.0;
        emission_weight = power_heuristic(continuation_pdf, light_pdf);
      }
      total += throughput.cwiseProduct(s.emitted(h.triangle, h.u, h.v)) * emission_weight;
      if (depth == spec.bounces) break;
      const Rgb albedo = s.albedo(h.triangle, h.u, h.v);
      if (!(albedo.maxCoeff() > 0)) break;
      const Eigen::Vector3d x = origin + h.t * dir;
      const Eigen::Vector3d xo = x + eps * n;
      // Shading uses the interpolated normal; visibility and sides the geometric one (a
      // direction below the triangle's own plane is blocked whatever the shading normal).
      const Eigen::Vector3d ns = shading_normal(h.triangle, h.u, h.v, n);
      for (const scene::PunctualLight& light : s.lights) {
        const scene::LightSample ls = scene::light_at(light, x);
        const double cosine = ns.dot(ls.to_light);
        if (!(cosine > 0) || !(n.dot(ls.to_light) > 0) || !(ls.irradiance.maxCoeff() > 0)) continue;
        ++rays;
        if (occluded(s, xo, ls.to_light, ls.distance - 2 * eps)) continue;
        total += throughput.cwiseProduct(albedo).cwiseProduct(ls.irradiance) * (cosine / kPi);
      }
      if (sample_emitters) total += throughput.cwiseProduct(albedo).cwiseProduct(emitter_sample(xo, ns, n, rng, rays));
      throughput = throughput.cwiseProduct(albedo);
      // Cosine-weighted continuation: pdf cos / pi against the BRDF albedo / pi times cos.
      const double u1 = rng.uniform(), u2 = rng.uniform();
      const double r = std::sqrt(u1), phi = 2 * kPi * u2;
      Eigen::Vector3d t, b;
      fit::orthonormal_basis(ns, t, b);
      dir = (r * std::cos(phi) * t + r * std::sin(phi) * b + std::sqrt(std::max(0.0, 1 - u1)) * ns).normalized();
      if (!(n.dot(dir) > 0)) break;  // into the surface: absorbed
      continuation_pdf = std::max(0.0, ns.dot(dir)) / kPi;
      origin = xo;
    }
    return total;
  }
};

}  // namespace

std::array<int, 3> ProbeGridSpec::grid_index(std::size_t probe) const {
  const std::size_t nx = resolution[0], ny = resolution[1];
  return {static_cast<int>(probe % nx), static_cast<int>(probe / nx % ny), static_cast<int>(probe / (nx * ny))};
}

Eigen::Vector3d ProbeGridSpec::position(std::size_t probe) const {
  const std::array<int, 3> i = grid_index(probe);
  Eigen::Vector3d p;
  for (int a = 0; a < 3; ++a) p[a] = lower[a] + (i[a] + 0.5) * (upper[a] - lower[a]) / resolution[a];
  return p;
}

std::size_t fill_invalid_probes(const std::array<int, 3>& res, int per_probe, const std::vector<std::uint8_t>& valid,
                                std::vector<double>& coefficients) {
  const std::size_t count = valid.size(), n = static_cast<std::size_t>(per_probe);
  std::vector<std::uint8_t> has(valid);
  for (;;) {
    std::vector<std::size_t> filled_now;
    std::vector<double> values;
    for (std::size_t p = 0; p < count; ++p) {
      if (has[p]) continue;
      const std::size_t nx = res[0], ny = res[1];
      const int ix = static_cast<int>(p % nx), iy = static_cast<int>(p / nx % ny), iz = static_cast<int>(p / (nx * ny));
      const int offsets[6][3] = {{-1, 0, 0}, {1, 0, 0}, {0, -1, 0}, {0, 1, 0}, {0, 0, -1}, {0, 0, 1}};
      std::vector<double> sum(n, 0.0);
      int neighbours = 0;
      for (const auto& o : offsets) {
        const int jx = ix + o[0], jy = iy + o[1], jz = iz + o[2];
        if (jx < 0 || jy < 0 || jz < 0 || jx >= res[0] || jy >= res[1] || jz >= res[2]) continue;
        const std::size_t q = (static_cast<std::size_t>(jz) * ny + jy) * nx + jx;
        if (!has[q]) continue;
        for (std::size_t k = 0; k < n; ++k) sum[k] += coefficients[q * n + k];
        ++neighbours;
      }
      if (neighbours == 0) continue;
      filled_now.push_back(p);
      for (std::size_t k = 0; k < n; ++k) values.push_back(sum[k] / neighbours);
    }
    if (filled_now.empty()) break;
    // Jacobi-style: a round reads only the probes that had values before it.
    for (std::size_t i = 0; i < filled_now.size(); ++i) {
      has[filled_now[i]] = 1;
      for (std::size_t k = 0; k < n; ++k) coefficients[filled_now[i] * n + k] = values[i * n + k];
    }
  }
  std::size_t unfilled = 0;
  for (std::size_t p = 0; p < count; ++p)
    if (!has[p]) {
      ++unfilled;
      for (std::size_t k = 0; k < n; ++k) coefficients[p * n + k] = 0;
    }
  return unfilled;
}

ProbeBake bake_probe_grid(const scene::Scene& s, const ProbeGridSpec& spec, const Environment& env) {
  ProbeBake out = bake_probe_range(s, spec, env, 0, spec.probe_count());
  const int per_probe = spec.order * spec.order * 3;
  out.unfilled = fill_invalid_probes(spec.resolution, per_probe, out.valid, out.coefficients);
  return out;
}

ProbeBake bake_probe_range(const scene::Scene& s, const ProbeGridSpec& spec, const Environment& env,
                           std::size_t begin, std::size_t end) {
  const std::size_t probes = end - begin;
  const int nn = spec.order * spec.order;
  const std::size_t per_probe = static_cast<std::size_t>(nn) * 3;
  double extent = 0;
  for (const Eigen::Vector3d& p : s.mesh.positions) extent = std::max(extent, p.cwiseAbs().maxCoeff());
  for (int a = 0; a < 3; ++a) extent = std::max({extent, std::abs(spec.lower[a]), std::abs(spec.upper[a])});
  const Emitters emitters(s);
  const Tracer tracer{s, spec, env, std::max(extent, 1e-30) * 1e-5, emitters};

  ProbeBake out;
  out.coefficients.assign(probes * per_probe, 0.0);
  out.valid.assign(probes, 1);
  out.back_face_share.assign(probes, 0.0);
  std::vector<std::uint64_t> rays(probes, 0);

  parallel_for(probes, resolve_threads(spec.threads), [&](std::size_t i) {
    const std::size_t p = begin + i;  // the probe's index in the whole grid: its draws
    const Eigen::Vector3d x = spec.position(p);
    const std::uint64_t probe_seed = splitmix64(spec.seed ^ splitmix64(p));
    const RayTurn turn = ray_turn(spec.seed, p);
    std::vector<double> y(static_cast<std::size_t>(nn)), env_y(static_cast<std::size_t>(env.order) * env.order);
    std::vector<double> sum(per_probe, 0.0);
    std::size_t back_faces = 0;
    std::uint64_t probe_rays = 0;
    const std::size_t S = static_cast<std::size_t>(spec.samples);
    for (std::size_t j = 0; j < S; ++j) {
      // Only the azimuths turn: the bands in z keep their midpoints (shift 1/2), so the set
      // stays symmetric about z = 0 and integrates the low bands far better than a
      // shifted one (whose z sum is off by 1 - 2 shift).
      const Eigen::Vector3d w = fit::sphere_fibonacci_direction(static_cast<int>(j), spec.samples, turn.rotation, 0.5);
      SplitMixStream rng{splitmix64(probe_seed + splitmix64(j + 1))};
      bool escaped = false, back_face = false;
      const Rgb l = tracer.radiance(x, w, rng, escaped, back_face, probe_rays, env_y);
      if (escaped) continue;  // the environment itself: in env_k exactly
      if (back_face) ++back_faces;
      const Rgb d = l - environment_radiance(env, w, env_y);
      eval_sh<double>(spec.order, w, y);
      for (int k = 0; k < nn; ++k)
        for (int c = 0; c < 3; ++c) sum[k * 3 + c] += d[c] * y[k];
    }
    double* c = out.coefficients.data() + i * per_probe;
    const double weight = 4 * kPi / static_cast<double>(S);
    for (std::size_t k = 0; k < per_probe; ++k) c[k] = sum[k] * weight;
    for (int k = 0; k < std::min(nn, env.order * env.order); ++k)
      for (int ch = 0; ch < 3; ++ch) c[k * 3 + ch] += env.coefficients[k * 3 + ch];
    // Punctual lights seen from the probe: deltas, projected exactly.
    for (const scene::PunctualLight& light : s.lights) {
      const scene::LightSample ls = scene::light_at(light, x);
      if (!(ls.irradiance.maxCoeff() > 0)) continue;
      ++probe_rays;
      if (occluded(s, x, ls.to_light, ls.distance)) continue;
      eval_sh<double>(spec.order, ls.to_light, y);
      for (int k = 0; k < nn; ++k)
        for (int ch = 0; ch < 3; ++ch) c[k * 3 + ch] += ls.irradiance[ch] * y[k];
    }
    out.back_face_share[i] = static_cast<double>(back_faces) / static_cast<double>(S);
    out.valid[i] = out.back_face_share[i] > kInvalidBackFaceShare ? 0 : 1;
    rays[i] = probe_rays;
  });
  for (const std::uint64_t r : rays) out.rays += r;
  return out;
}

}  // namespace shtool::probes
