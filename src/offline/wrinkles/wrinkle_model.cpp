#include "wrinkles/wrinkle_model.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "common/parallel_for.h"
#include "common/random.h"
#include "fit/transfer.h"
#include "shtool/sh.h"

namespace shtool::wrinkles {

namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// Cross-section pieces per sample interval: a chord of length 1/segments departs from
// the sinusoid (curvature at most 2 pi^2 d) by at most 2 pi^2 d / (8 segments^2), under
// 4e-5 of the period at d = 1 with the default 64 samples (256 pieces) per period.
constexpr int kSegmentsPerSample = 4;
// How far the groove runs along y, in periods: a ray rising at elevation e above the
// horizontal escapes the groove within d / tan e along it, so only rays within
// atan(d / 256) (0.22 degrees at d = 1) of the horizontal could have been blocked
// further away.
constexpr double kGrooveLength = 256.0;
// Ray origins leave the surface by this much (in periods) along the normal.
constexpr double kRayOffset = 1e-4;

}  // namespace

double groove_height(double x, double depth) { return -0.5 * depth * (1.0 - std::cos(kTwoPi * x)); }

Eigen::Vector3d groove_normal(double x, double depth) {
  const double slope = -std::numbers::pi * depth * std::sin(kTwoPi * x);
  return Eigen::Vector3d(-slope, 0.0, 1.0).normalized();
}

BilinearWeights bilinear_weights(const WrinkleGrid& grid, double x, double depth) {
  return wrinkle_weights<double>(grid.grid, grid.max_depth, x, depth);
}

BilinearWeights sample_weights(const WrinkleGrid& grid, int i, int k) {
  const int g = grid.grid, s = grid.samples;
  const int j0 = i / s, j1 = (j0 + 1) % g;
  // The last row of samples lies on the last row of nodes: blend it from the cell below.
  const int k0 = std::min(k / s, g - 2);
  const double fx = static_cast<double>(i - j0 * s) / s;
  const double fd = static_cast<double>(k - k0 * s) / s;
  return {{k0 * g + j0, k0 * g + j1, (k0 + 1) * g + j0, (k0 + 1) * g + j1},
          {(1 - fx) * (1 - fd), fx * (1 - fd), (1 - fx) * fd, fx * fd}};
}

void evaluate_model(const WrinkleModel& m, const BilinearWeights& w, std::span<double> out) {
  const int n2 = sh_count(m.order);
  WrinkleLobes<double> blended;
  blend_wrinkle_lobes<double>(m.order, m.lobes, m.axes, m.coeffs, m.direct, w, blended);
  std::fill(out.begin(), out.begin() + n2, 0.0);
  for (int i = 0; i < kDirectCoefficients; ++i) out[i] = blended.direct[i];
  std::array<double, kMaxWrinkleOrder * kMaxWrinkleOrder> y{};
  for (int lobe = 0; lobe < m.lobes; ++lobe) {
    const double* g = blended.coeffs.data() + static_cast<std::size_t>(lobe) * m.order;
    eval_sh<double>(m.order, blended.axes[lobe], std::span<double>(y.data(), n2));
    for (int l = 0; l < m.order; ++l)
      for (int mm = -l; mm <= l; ++mm) out[sh_index(l, mm)] += g[l] * y[sh_index(l, mm)];
  }
}

fit::Mesh groove_mesh(double depth, int sample_columns, int segments, double length) {
  const int step = segments / sample_columns;
  const int columns = 3 * segments + 1;  // x from -1 to 2
  std::vector<double> ys{0.0};
  for (double y = 1.0 / segments;; y *= 2) {
    const double row = std::min(y, length);
    ys.push_back(row);
    ys.insert(ys.begin(), -row);
    if (row >= length) break;
  }
  const int rows = static_cast<int>(ys.size());
  const int centre_row = rows / 2;
  // Vertex ids: the sample points first (compute_transfer simulates a leading range).
  std::vector<int> id(static_cast<std::size_t>(rows) * columns, -1);
  int next = 0;
  for (int i = 0; i < sample_columns; ++i) id[static_cast<std::size_t>(centre_row) * columns + segments + i * step] = next++;
  for (int& v : id)
    if (v < 0) v = next++;
  fit::Mesh mesh;
  mesh.positions.resize(id.size());
  mesh.normals.resize(id.size());
  mesh.source_index.resize(id.size());
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      const int v = id[static_cast<std::size_t>(r) * columns + c];
      const double x = static_cast<double>(c - segments) / segments;
      mesh.positions[v] = Eigen::Vector3d(x, ys[r], groove_height(x, depth));
      mesh.normals[v] = groove_normal(x, depth);
      mesh.source_index[v] = static_cast<std::uint32_t>(v);
    }
  for (int r = 0; r + 1 < rows; ++r)
    for (int c = 0; c + 1 < columns; ++c) {
      const int a = id[static_cast<std::size_t>(r) * columns + c], b = id[static_cast<std::size_t>(r) * columns + c + 1];
      const int d = id[static_cast<std::size_t>(r + 1) * columns + c], e = id[static_cast<std::size_t>(r + 1) * columns + c + 1];
      mesh.triangles.emplace_back(a, b, e);
      mesh.triangles.emplace_back(a, e, d);
    }
  return mesh;
}

std::vector<double> simulate_transfer(const WrinkleGrid& grid, const SimulationOptions& options) {
  const int n2 = sh_count(options.order);
  const int columns = grid.sample_columns();
  const std::size_t row_values = static_cast<std::size_t>(columns) * n2;
  std::vector<double> out(grid.sample_count() * n2);
  // One depth per task, each simulated on one thread: the rows are independent, and each
  // row's bytes depend only on (seed, row).
  parallel_for(static_cast<std::size_t>(grid.sample_rows()), resolve_threads(options.threads), [&](std::size_t k) {
    const fit::Mesh mesh = groove_mesh(grid.sample_depth(static_cast<int>(k)), columns,
                                       columns * kSegmentsPerSample, kGrooveLength);
    fit::TransferOptions t;
    t.order = options.order;
    t.rays = options.rays;
    // Each depth its own directions: the noise of neighbouring depths is independent.
    t.seed = splitmix64(options.seed ^ splitmix64(k));
    t.mode = fit::TransferMode::shadowed;
    t.threads = 1;
    t.offset_scale = kRayOffset / mesh.bbox_diagonal();
    t.first_vertex = 0;
    t.end_vertex = static_cast<std::size_t>(columns);
    const std::vector<double> row = fit::compute_transfer(mesh, t);
    std::copy(row.begin(), row.end(), out.begin() + static_cast<std::ptrdiff_t>(k * row_values));
  });
  return out;
}

}  // namespace shtool::wrinkles
