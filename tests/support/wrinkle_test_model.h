// A wrinkle model with every array sized for its grid, order and lobes, all zeros: the
// tests fill in the values they need.
#pragma once

#include <cstddef>

#include "wrinkles/wrinkle_model.h"

namespace shtool::test {

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

}  // namespace shtool::test
