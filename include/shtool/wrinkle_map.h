// The wrinkle map that `shtool fit-wrinkles` writes (table kind "wrinkle-zh",
// schemas/wrinkle-zh.schema.json; docs/table-format.md), loaded for shading: [4] Sec. 4.2's
// parametric groove as N ZH lobes plus the DC and linear band stored directly, at every
// node of a G x G map over the position across the groove x (period 1) and the groove
// depth d (in periods), blended bilinearly in between.
//
// Vectors are in the groove frame: +z the macro-surface normal, +x across the groove (the
// direction in which x grows), +y along it. Shading takes the rotation from that frame to
// the frame of the lighting (columns: across, along, normal).
//
// wrinkle_weights and blend_wrinkle_lobes are the blend fit-wrinkles evaluates its model
// with (the offline code calls them), so a map shades exactly as it was fitted. The
// per-point calls allocate nothing and throw nothing.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "shtool/result.h"
#include "shtool/sh.h"
#include "shtool/table.h"

namespace shtool {

inline constexpr std::string_view kWrinkleZhKind = "wrinkle-zh";
// Bounds of the model (the blended lobes live in fixed-size arrays, so that shading and
// the fit's inner loop never allocate).
inline constexpr int kMaxWrinkleOrder = 8;
inline constexpr int kMaxWrinkleLobes = 4;
// DC and the linear band are stored directly ([4] Sec. 4.2): 4 coefficients per node.
inline constexpr int kWrinkleDirect = 4;

// The four nodes (index k * G + j: row k of depth, column j of x) around a point and
// their bilinear weights.
template <class T>
struct WrinkleWeights {
  int node[4];
  T weight[4];
};

// At any finite x (wrapped into [0, 1): x is periodic) and depth (clamped to
// [0, max_depth]), on a grid of G >= 2 nodes per axis: x_j = j / G, d_k = max_depth k / (G - 1).
// Preconditions: grid >= 2, max_depth > 0 (a normal T). An infinite or NaN x is taken
// as x = 0, a NaN depth as 0: never an index outside the map.
template <class T>
WrinkleWeights<T> wrinkle_weights(int grid, T max_depth, T x, T depth) noexcept;

// The bilinear blend itself: out[i] = sum_c w.weight[c] values[w.node[c] * stride + offset + i]
// for i < count, summed in corner order from 0, so that every caller (the map, the fit's
// model and its objective) gets the same bits. Precondition: the reads are in range.
template <class T>
inline void blend_wrinkle_values(const WrinkleWeights<T>& w, const T* values, std::size_t stride, std::size_t offset,
                                 int count, T* out) noexcept {
  for (int i = 0; i < count; ++i) out[i] = T(0);
  for (int c = 0; c < 4; ++c) {
    const T* v = values + static_cast<std::size_t>(w.node[c]) * stride + offset;
    for (int i = 0; i < count; ++i) out[i] += w.weight[c] * v[i];
  }
}

// The lobes at one point: each blended axis normalised (h(s) of [4] Eq. 21: the node
// axes are not unit, and normalising after the blend is what the fit optimised).
template <class T>
struct WrinkleLobes {
  int order = 0;
  int lobes = 0;
  std::array<Vec3<T>, kMaxWrinkleLobes> axes;
  std::array<T, kMaxWrinkleLobes * kMaxWrinkleOrder> coeffs;  // lobe-major: coeffs[i * order + l] = g*_il
  std::array<T, kWrinkleDirect> direct;                       // DC, then y_1^-1, y_1^0, y_1^1

  std::span<const Vec3<T>> axis_span() const { return {axes.data(), static_cast<std::size_t>(lobes)}; }
  std::span<const T> coeff_span() const { return {coeffs.data(), static_cast<std::size_t>(lobes) * order}; }
};

// Blends node values laid out as the table stores them (axes [node][lobe][3], coeffs
// [node][lobe][order], direct [node][4]) with weights w. Preconditions: order in
// 1..kMaxWrinkleOrder, lobes in 1..kMaxWrinkleLobes, the spans cover w's nodes.
template <class T>
void blend_wrinkle_lobes(int order, int lobes, std::span<const T> axes, std::span<const T> coeffs,
                         std::span<const T> direct, const WrinkleWeights<T>& w, WrinkleLobes<T>& out) noexcept;

// Exit radiance of blended lobes under SH lighting e (order^2 values, in the frame
// `frame` maps the groove frame into; frame must be a rotation): [4] Eq. 13 with each
// axis turned to frame * s_i, plus the direct DC and linear band (the band turned as a
// vector: band 1 of f is c (-f_1, -f_-1, f_0) . w). NaN when light.size() != order^2.
template <class T>
T shade_wrinkle_lobes(std::span<const T> light, const Eigen::Matrix<T, 3, 3>& frame,
                      const WrinkleLobes<T>& lobes) noexcept;

template <class T>
struct WrinkleMap {
  int order = 0;   // n: each lobe has coefficients for bands 0..n-1 (0 and 1 are zero)
  int lobes = 0;   // N
  int grid = 0;    // G nodes per axis
  T max_depth = 0; // depth of the last row of nodes, in periods
  std::vector<T> axes;    // G * G * N * 3, node (k * G + j) major; not unit, never zero
  std::vector<T> coeffs;  // G * G * N * n
  std::vector<T> direct;  // G * G * 4

  WrinkleWeights<T> weights(T x, T depth) const noexcept { return wrinkle_weights<T>(grid, max_depth, x, depth); }
  // The blended lobes at (x, d). Precondition: x finite, d not NaN.
  void lobes_at(T x, T depth, WrinkleLobes<T>& out) const noexcept {
    blend_wrinkle_lobes<T>(order, lobes, axes, coeffs, direct, weights(x, depth), out);
  }
  // shade_wrinkle_lobes at (x, d); NaN when x or d is not finite.
  T shade(std::span<const T> light, const Eigen::Matrix<T, 3, 3>& frame, T x, T depth) const noexcept;

  // Checks kind, order (2..kMaxWrinkleOrder), meta (grid >= 2, lobes 1..kMaxWrinkleLobes,
  // max_depth finite and positive), every array's dtype and shape, the node positions
  // (x_j = j / G, d_k = max_depth k / (G - 1), to 1e-12), finiteness of every value,
  // bands 0 and 1 of the lobes zero (they are in `direct`), and that no node axis is zero
  // and no cell's four axes of a lobe can blend to zero (all within 90 degrees of their
  // sum, so every blended axis normalises). Values are read as double and stored as T.
  static Result<WrinkleMap> from_table(const Table& table);
  // read_table + from_table, the path prefixed to any message.
  static Result<WrinkleMap> load(const std::filesystem::path& path);
};

extern template struct WrinkleMap<float>;
extern template struct WrinkleMap<double>;

}  // namespace shtool
