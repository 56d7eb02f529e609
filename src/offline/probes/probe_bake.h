// The light transport of bake-probes: incident radiance at the centre of every cell of a
// grid, projected on RGB SH (docs/probes.md).
//
// Per probe p, S directions w_j (a spherical Fibonacci set turned about z by
// ray_turn(seed, probe), common/random.h) each start a path: the radiance L_j arriving at p from w_j is what
// the first surface hit emits plus what it reflects, estimated by a path of up to
// `bounces` Lambertian reflections with next-event estimation at each reflection: toward
// every punctual light, and toward one point on the emissive triangles (chosen by area x
// emitted power), combined with the cosine-weighted continuation's hits on emitters by
// multiple importance sampling with the power heuristic (Veach 1997). Each reflection
// multiplies the path's weight by the albedo. The environment is a control variate:
//   c_k = env_k + (4 pi / S) sum_j [L_j - L_env(w_j)] y_k(w_j),
// where the sum runs over the directions that hit a surface (for the others L_j is the
// environment itself), so an open scene gets the environment's coefficients exactly.
// Punctual lights seen from p unoccluded add their exact delta projection E y_k(s)
// (E: the irradiance they deliver at p, s: the direction toward them).
//
// A direction whose first hit is the back of a single-sided triangle brings no light and
// counts as a back-face hit; a probe with more than kInvalidBackFaceShare of them is
// inside geometry: invalid, and its coefficients are filled from its valid 6-neighbours
// (fill_invalid_probes).
//
// Deterministic: every random number derives from (seed, probe index, sample index), and
// each probe sums its samples in order; the bytes do not depend on the thread count.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "scene/scene.h"

namespace shtool::probes {

// More than a quarter of a probe's directions reaching back faces: inside geometry (a
// probe in open space sees at most the back faces of stray single-sided pieces).
inline constexpr double kInvalidBackFaceShare = 0.25;

struct ProbeGridSpec {
  std::array<int, 3> resolution{1, 1, 1};  // NX, NY, NZ
  Eigen::Vector3d lower = Eigen::Vector3d::Zero(), upper = Eigen::Vector3d::Ones();
  int order = 3;
  int samples = 1024;
  int bounces = 3;
  std::uint64_t seed = 1;
  int threads = 0;
  // Next-event estimation toward emissive triangles with multiple importance sampling
  // (on in every bake; off only to measure what it brings).
  bool sample_emitters = true;

  std::size_t probe_count() const {
    return static_cast<std::size_t>(resolution[0]) * resolution[1] * resolution[2];
  }
  // p = lower + (i + 1/2) (upper - lower) / n per axis; index ix fastest, then iy, then iz.
  Eigen::Vector3d position(std::size_t probe) const;
  std::array<int, 3> grid_index(std::size_t probe) const;
};

// A distant environment: radiance SH (RGB, any order) in shtool's frame; empty: none.
struct Environment {
  int order = 0;
  std::vector<double> coefficients;  // [k * 3 + c]
};

struct ProbeBake {
  std::vector<double> coefficients;    // probe-major, then SH index, then r, g, b
  std::vector<std::uint8_t> valid;     // 1: valid; 0: inside geometry (filled)
  std::vector<double> back_face_share; // per probe
  std::uint64_t rays = 0;              // rays cast (intersections and shadow rays)
  std::size_t unfilled = 0;            // invalid probes with no valid probe connected
};

ProbeBake bake_probe_grid(const scene::Scene& scene, const ProbeGridSpec& spec, const Environment& env);

// Probes [begin, end) only, as bake_probe_grid computes them before the invalid ones are
// filled (a shard of a bake: the fill needs every probe and runs when the parts are
// joined). Its arrays hold end - begin probes; `unfilled` is 0.
ProbeBake bake_probe_range(const scene::Scene& scene, const ProbeGridSpec& spec, const Environment& env,
                           std::size_t begin, std::size_t end);

// Fills each invalid probe (valid[p] == 0) from its 6-neighbours: in rounds, every
// still-empty probe with at least one neighbour holding values (valid or filled in an
// earlier round) takes their average, the neighbours in order -x, +x, -y, +y, -z, +z.
// Probes no valid probe reaches stay zero; returns their number.
std::size_t fill_invalid_probes(const std::array<int, 3>& resolution, int coefficients_per_probe,
                                const std::vector<std::uint8_t>& valid, std::vector<double>& coefficients);

}  // namespace shtool::probes
