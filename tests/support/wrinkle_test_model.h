// Wrinkle models for the tests: every array sized for the grid, order and lobes, filled
// with zeros or with random values.
#pragma once

#include <cstddef>
#include <random>
#include <vector>

#include <Eigen/Dense>

#include "wrinkles/wrinkle_model.h"

namespace shtool::test {

// All zeros: the tests fill in the values they need.
inline wrinkles::WrinkleModel zero_wrinkle_model(const wrinkles::WrinkleGrid& grid, int order, int lobes) {
  wrinkles::WrinkleModel m;
  m.grid = grid;
  m.order = order;
  m.lobes = lobes;
  const std::size_t cells = static_cast<std::size_t>(grid.nodes()) * lobes;
  m.axes.assign(cells * 3, 0.0);
  m.coeffs.assign(cells * order, 0.0);
  m.direct.assign(static_cast<std::size_t>(grid.nodes()) * wrinkles::kDirectCoefficients, 0.0);
  return m;
}

// How random_wrinkle_model draws the node axes: each component uniform in [-1, 1] (random
// length and direction), or within about 35 degrees of a random direction per lobe with
// length 0.5..1.5, as a fitted map's corresponding lobes are, so that every cell's blend
// is defined (smooth).
enum class WrinkleAxes { random, smooth };

// Random node values from `seed`: the axes as `axes` says, the coefficients of bands
// 2..order-1 uniform in [-0.3, 0.3], the direct ones in [-1, 1].
inline wrinkles::WrinkleModel random_wrinkle_model(const wrinkles::WrinkleGrid& grid, int order, int lobes,
                                                   unsigned seed, WrinkleAxes axes) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  wrinkles::WrinkleModel m = zero_wrinkle_model(grid, order, lobes);
  const std::size_t cells = static_cast<std::size_t>(grid.nodes()) * lobes;
  auto draw_coeffs = [&](std::size_t cell) {
    for (int l = 2; l < order; ++l) m.coeffs[cell * order + l] = 0.3 * u(rng);
  };
  if (axes == WrinkleAxes::random) {
    for (double& a : m.axes) a = u(rng);
    for (std::size_t cell = 0; cell < cells; ++cell) draw_coeffs(cell);
  } else {
    std::vector<Eigen::Vector3d> base(lobes);
    for (Eigen::Vector3d& b : base) b = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    for (std::size_t cell = 0; cell < cells; ++cell) {
      const Eigen::Vector3d a =
          (base[cell % lobes] + 0.4 * Eigen::Vector3d(u(rng), u(rng), u(rng))).normalized() * (1.0 + 0.5 * u(rng));
      for (int c = 0; c < 3; ++c) m.axes[cell * 3 + c] = a[c];
      draw_coeffs(cell);
    }
  }
  for (double& d : m.direct) d = u(rng);
  return m;
}

}  // namespace shtool::test
