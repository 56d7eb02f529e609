// The per-vertex ZH lobe fits that `shtool fit-zh` writes (table kind "zh-fit",
// schemas/zh-fit.schema.json), loaded for shading ([4] Eq. 13 and Eq. 24-25 through
// shtool/zh_shading.h): for V vertices, N lobes each, SH order n,
//   lobe k of vertex v has unit axis axes_of(v)[k] and convolved coefficients
//   coeffs_of(v)[k * n + l] = g*_l, l < n, so it adds g*_l y_l^m(axis) to coefficient (l, m).
// The spans have exactly the layout zh_shade_exact and ZhLightTable::shade take.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "shtool/result.h"
#include "shtool/sh.h"
#include "shtool/table.h"

namespace shtool {

inline constexpr std::string_view kZhFitKind = "zh-fit";

template <class T>
struct ZhFitTable {
  int order = 0;              // n: each lobe has coefficients for bands 0..n-1
  int lobes = 0;              // N lobes per vertex
  std::size_t vertices = 0;   // V
  std::vector<Vec3<T>> axes;  // V * N unit axes, vertex-major
  std::vector<T> coeffs;      // V * N * n, vertex-major then lobe-major
  std::vector<T> residual;    // V: ||fit - t|| of the transfer vector
  std::vector<T> norm;        // V: ||t||
  int direct_count = 0;       // D = 0, 1 (DC) or 4 (DC and linear) coefficients stored directly
  std::vector<T> direct;      // V * D
  std::vector<std::uint32_t> vertex_index;  // V (may be empty): 0-based OBJ vertex of each row

  std::span<const Vec3<T>> axes_of(std::size_t v) const {
    return {axes.data() + v * lobes, static_cast<std::size_t>(lobes)};
  }
  std::span<const T> coeffs_of(std::size_t v) const {
    return {coeffs.data() + v * lobes * order, static_cast<std::size_t>(lobes) * order};
  }
  std::span<const T> direct_of(std::size_t v) const {
    return {direct.data() + v * direct_count, static_cast<std::size_t>(direct_count)};
  }

  // Checks kind, order, every shape against V, N and n, finiteness of every value, unit
  // axes (to 1e-6) and non-negative residuals and norms; values are read as double and
  // stored as T.
  static Result<ZhFitTable> from_table(const Table& table);
  // read_table + from_table, the path prefixed to any message.
  static Result<ZhFitTable> load(const std::filesystem::path& path);
};

extern template struct ZhFitTable<float>;
extern template struct ZhFitTable<double>;

}  // namespace shtool
