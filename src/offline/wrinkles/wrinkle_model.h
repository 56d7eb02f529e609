// The wrinkle model of [4] Sec. 4.2: a sinusoidal groove extruded into a height field,
// parameterised by the position x across the groove and the groove depth d; its diffuse
// shadowed transfer at (x, d) is fitted by N ZH lobes whose axes and coefficients are
// bilinear in (x, d) over a G x G grid of nodes. docs/ldprt.md, "Wrinkles".
//
// Frame of every vector here (the local frame of the macro surface the wrinkle is mapped
// on): +z the macro-surface normal, +x across the groove (increasing x), +y along it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "fit/mesh.h"
#include "shtool/wrinkle_map.h"

namespace shtool::wrinkles {

// Height of the groove of depth d at x (period 1): h(x) = -(d / 2) (1 - cos 2 pi x),
// so the ridges (x = 0, 1) are at 0 and the bottom (x = 1/2) at -d.
double groove_height(double x, double depth);
// Unit normal of the height field at x: (-h'(x), 0, 1) normalised, h' = -pi d sin 2 pi x.
Eigen::Vector3d groove_normal(double x, double depth);

// The model's bounds (kMaxWrinkleOrder, kMaxWrinkleLobes) and its 4 directly stored
// coefficients are the runtime's (shtool/wrinkle_map.h), which shades the same map.
inline constexpr int kDirectCoefficients = kWrinkleDirect;
// The most samples fit-wrinkles simulates (--grid 256 --samples 5 is 1.6 million): about
// 1 GB of transfer at order 8.
inline constexpr std::size_t kMaxWrinkleSamples = std::size_t(1) << 21;

// Nodes: x_j = j / G (j = 0..G-1, periodic: x = 1 is x = 0 again) and
// d_k = max_depth k / (G - 1) (k = 0..G-1). Samples, where the transfer is simulated and
// the fit measured, are `samples` times denser on each axis: x_i = i / (G S),
// i = 0..G S - 1, and d_k = max_depth k / ((G - 1) S), k = 0..(G - 1) S, so every node
// is a sample and each cell has S x S samples.
struct WrinkleGrid {
  int grid = 32;
  int samples = 2;
  double max_depth = 1.0;

  int nodes() const { return grid * grid; }
  int sample_columns() const { return grid * samples; }
  int sample_rows() const { return (grid - 1) * samples + 1; }
  std::size_t sample_count() const {
    return static_cast<std::size_t>(sample_columns()) * static_cast<std::size_t>(sample_rows());
  }
  double node_x(int j) const { return static_cast<double>(j) / grid; }
  double node_depth(int k) const { return max_depth * k / (grid - 1); }
  double sample_x(int i) const { return static_cast<double>(i) / sample_columns(); }
  double sample_depth(int k) const { return max_depth * k / (sample_rows() - 1); }
  // Sample index of (column i, row k): rows (depth) major.
  std::size_t sample_index(int i, int k) const {
    return static_cast<std::size_t>(k) * sample_columns() + static_cast<std::size_t>(i);
  }
};

// The four nodes (index k * G + j) around a point and their bilinear weights.
using BilinearWeights = WrinkleWeights<double>;
// At any (x, d): x wraps into [0, 1), d is clamped to [0, max_depth] (the runtime's
// wrinkle_weights, so that shading blends as the fit did).
BilinearWeights bilinear_weights(const WrinkleGrid& grid, double x, double depth);
// At sample (i, k), from integers: fractions are exactly (i mod S) / S and (k mod S) / S.
BilinearWeights sample_weights(const WrinkleGrid& grid, int i, int k);

// The fitted map: per node, N lobes (axis, order coefficients; bands 0 and 1 are 0, those
// are in `direct`) and the 4 direct coefficients. Axes are not unit: at (x, d) the lobe's
// axis is the bilinear blend of its nodes' vectors, normalised afterwards (h(s) of [4]
// Eq. 21), which is what the fit optimised.
struct WrinkleModel {
  WrinkleGrid grid;
  int order = 6;
  int lobes = 3;
  std::vector<double> axes;    // [node][lobe][3]
  std::vector<double> coeffs;  // [node][lobe][order]
  std::vector<double> direct;  // [node][4]
};

// The SH vector (order^2 values) the model gives at (x, d): the runtime's blend
// (blend_wrinkle_lobes), expanded into SH.
void evaluate_model(const WrinkleModel& model, const BilinearWeights& w, std::span<double> out);

// The height field of depth d as a triangle mesh whose first `sample_columns` vertices
// are the sample points x_i (y = 0) of the centre period, with the analytic normals.
// Cross-section: `segments` straight pieces per period (a multiple of sample_columns),
// over the centre period and one more on each side; along the groove, rows at y = 0 and
// +-2^r / segments up to +-length, so that the triangles near the sample points are
// small (Embree works in floats) while grazing rays along the groove still meet its walls.
fit::Mesh groove_mesh(double depth, int sample_columns, int segments, double length);

struct SimulationOptions {
  int order = 6;
  int rays = 1024;
  std::uint64_t seed = 1;
  int threads = 0;
};

// Diffuse shadowed transfer (fit/transfer.h) at every sample of the grid, sample-major
// (grid.sample_index), order^2 values each. Bytes do not depend on the thread count.
std::vector<double> simulate_transfer(const WrinkleGrid& grid, const SimulationOptions& options);

}  // namespace shtool::wrinkles
