// Distant lighting as SH coefficients, as `shtool project-env` (an environment image) and
// `shtool light` (analytic lights) write it: table kind "env-sh",
// schemas/env-sh.schema.json, docs/lighting.md. Loaded for shading and rotation.
//
// Colour layout, as in analytic_lights.h, env_projection.h, orthogonal_map.h, irradiance.h
// and sh_window.h: interleaved, coefficients[i * channels + c] for SH index i and channel
// c (r, g, b), as the table stores it. Calls that take one channel (ShRotation::apply,
// zh_shade_exact, ZhLightTable) take that channel's N^2 coefficients; channel() copies
// them out.
#pragma once

#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "shtool/result.h"
#include "shtool/table.h"

namespace shtool {

// The table kind of projected lighting: coefficients [order^2, 3], RGB.
inline constexpr std::string_view kEnvShKind = "env-sh";

// What the coefficients are of: L itself, or the irradiance A_l L_lm (the clamped-cosine
// kernel of shtool/irradiance.h, no 1/pi).
enum class LightQuantity { radiance, irradiance };

template <class T>
struct ShLighting {
  static constexpr int kChannels = 3;

  int order = 0;
  LightQuantity quantity = LightQuantity::radiance;
  std::vector<T> coefficients;  // order^2 * 3, interleaved: [i * 3 + c]

  // Channel c (0, 1, 2: r, g, b) into out[i], i < order^2. Precondition:
  // out.size() >= order^2.
  void channel(int c, std::span<T> out) const noexcept {
    for (std::size_t i = 0; i * kChannels < coefficients.size(); ++i) out[i] = coefficients[i * kChannels + c];
  }

  // Checks kind, order (1..32), the array's dtype and shape [order^2, 3], finiteness and
  // meta.quantity; values are read as double and stored as T. load is read_table +
  // from_table, the path prefixed to any message.
  static Result<ShLighting> from_table(const Table& table);
  static Result<ShLighting> load(const std::filesystem::path& path);
};

extern template struct ShLighting<float>;
extern template struct ShLighting<double>;

}  // namespace shtool
