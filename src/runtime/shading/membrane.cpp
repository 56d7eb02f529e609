#include "shtool/membrane.h"

#include <numbers>

#include "shtool/irradiance.h"

namespace shtool {

void membrane_lobe(double alpha, std::span<double> g) noexcept {
  for (std::size_t l = 0; l < g.size(); ++l)
    g[l] = clamped_cosine_band(static_cast<int>(l)) * (1.0 + (l % 2 ? -alpha : alpha)) / std::numbers::pi;
}

}  // namespace shtool
