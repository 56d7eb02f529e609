#include "tensors/rotation_helpers_gen.h"

#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/table_writer.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Dense>

#include "shtool/euler.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

constexpr double kStructuralZero = 1e-13;

}  // namespace

std::shared_ptr<const RotationHelpers> rotation_helpers_for(int order, const std::filesystem::path& table) {
  if (table.empty()) return shipped_rotation_helpers_for(order, default_rotation_helpers_path());
  Result<RotationHelpers> loaded = RotationHelpers::load(table);
  if (!loaded) throw InputError(loaded.error().message);
  if (loaded.value().order < order)
    throw InputError(table.string() + ": rotation-helpers table covers order " + std::to_string(loaded.value().order) +
                     ", order " + std::to_string(order) + " was asked for");
  return std::make_shared<const RotationHelpers>(std::move(loaded).value());
}

std::shared_ptr<const RotationHelpers> shipped_rotation_helpers_for(int order, const std::filesystem::path& shipped) {
  if (!shipped.empty()) {
    Result<RotationHelpers> loaded = RotationHelpers::load(shipped);
    if (!loaded) throw InputError(loaded.error().message);  // a damaged table is not skipped
    if (loaded.value().order >= order) return std::make_shared<const RotationHelpers>(std::move(loaded).value());
  }
  return std::make_shared<const RotationHelpers>(compute_rotation_helpers(order));
}

RotationHelpers compute_rotation_helpers(int order, int threads) {
  if (!is_supported_order(order)) throw InputError("unsupported order " + std::to_string(order));
  const int n = sh_count(order);
  // Rx(+90): y -> z, z -> -y. g(w) = f(R^-1 w) gives X[i][j] = integral y_i(w) y_j(R^-1 w).
  Mat3<double> rx;
  rx << 1, 0, 0, 0, 0, -1, 0, 1, 0;
  const Mat3<double> rx_inv = rx.transpose();
  const SphereQuadrature q = sphere_quadrature(2 * order - 2);
  // Accumulated in long double: the sums run over ~2 N^2 nodes and a double sum would
  // leave errors of ~1e-14 on exact values such as X90[0][0] = 1. The bands' sums are
  // independent, so groups of bands of about equal cost ((2l+1)^2 a node) run on separate
  // threads, each over every node in node order: every sum, and so every value, is the
  // same whatever the thread count.
  std::vector<std::vector<long double>> sums(order);  // sums[l][a * (2l+1) + b]
  for (int l = 0; l < order; ++l) sums[l].assign(static_cast<std::size_t>(2 * l + 1) * (2 * l + 1), 0.0L);
  const int workers = std::min(resolve_threads(threads), order);
  std::vector<std::vector<int>> groups(workers);
  std::vector<long long> load(workers, 0);
  for (int l = order - 1; l >= 0; --l) {  // largest first, each to the least-loaded group
    const int w = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
    groups[w].push_back(l);
    load[w] += static_cast<long long>(2 * l + 1) * (2 * l + 1);
  }
  parallel_for(groups.size(), workers, [&](std::size_t w) {
    const int top = groups[w].empty() ? 0 : groups[w].front() + 1;  // the group's highest band + 1
    std::vector<double> yw(sh_count(top)), yr(sh_count(top));
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
      eval_sh<double>(top, q.directions[k], yw);
      eval_sh<double>(top, rx_inv * q.directions[k], yr);
      for (const int l : groups[w]) {
        const int size = 2 * l + 1;
        const double* const r = yr.data() + l * l;
        long double* row = sums[l].data();
        for (int a = 0; a < size; ++a, row += size) {
          const long double wa = q.weights[k] * yw[l * l + a];
          for (int b = 0; b < size; ++b) row[b] += wa * r[b];
        }
      }
    }
  });
  std::vector<Eigen::MatrixXd> x90(order);
  for (int l = 0; l < order; ++l) {
    const int size = 2 * l + 1;
    x90[l].resize(size, size);
    for (int a = 0; a < size; ++a)
      for (int b = 0; b < size; ++b) x90[l](a, b) = static_cast<double>(sums[l][a * size + b]);
  }

  RotationHelpers h;
  h.order = order;
  h.x90_row.assign(n + 1, 0);
  h.dy_sub.assign(n, 0.0);
  h.ddy_diag.assign(n, 0.0);
  h.ddy_off2.assign(n, 0.0);
  for (int l = 0; l < order; ++l) {
    const int size = 2 * l + 1, first = l * l;
    for (int a = 0; a < size; ++a) {
      for (int b = 0; b < size; ++b) {
        const double v = x90[l](a, b);
        if (std::abs(v) < kStructuralZero) continue;
        h.x90_col.push_back(first + b);
        h.x90_val.push_back(v);
      }
      h.x90_row[first + a + 1] = static_cast<int>(h.x90_col.size());
    }
    // Generator of z-rotations in band l: d/da of (f_m, f_-m) -> (-m f_-m, m f_m).
    Eigen::MatrixXd gz = Eigen::MatrixXd::Zero(size, size);
    for (int m = 1; m <= l; ++m) {
      gz(l + m, l - m) = -m;
      gz(l - m, l + m) = m;
    }
    // D1 from the X90 table carries the quadrature's rounding (~1e-15 relative, more on
    // the l^2-sized entries of D2 = D1^2). It is only the check; the stored values come
    // from the closed form of D1's sub-diagonal in our basis (docs/rotation.md), squared
    // in long double, so each is correctly rounded or 1 ulp off.
    const Eigen::MatrixXd d1_check = x90[l].transpose() * gz * x90[l];
    using LMat = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
    LMat d1 = LMat::Zero(size, size);
    for (int a = 1; a < size; ++a) {
      const int m = a - l;  // D1[m][m-1]
      const long double lm = l;
      long double v;
      if (m <= -1) v = 0.5L * std::sqrt((lm + m) * (lm - m + 1));
      else if (m == 0) v = 0.0L;
      else if (m == 1) v = -std::sqrt(lm * (lm + 1) / 2);
      else v = -0.5L * std::sqrt((lm + m) * (lm - m + 1));
      d1(a, a - 1) = v;
      d1(a - 1, a) = -v;  // antisymmetric
    }
    const LMat d2 = d1 * d1;
    const double scale = std::max(1.0, double(l) * l);
    for (int a = 0; a < size; ++a)
      for (int b = 0; b < size; ++b)
        if (std::abs(d1_check(a, b) - static_cast<double>(d1(a, b))) > 1e-12 * scale)
          throw std::logic_error("D1 closed form disagrees with X90^T G_z X90 in band " +
                                 std::to_string(l));
    for (int a = 0; a < size; ++a) {
      if (a > 0) h.dy_sub[first + a] = static_cast<double>(d1(a, a - 1));
      h.ddy_diag[first + a] = static_cast<double>(d2(a, a));
      if (a > 1) h.ddy_off2[first + a] = static_cast<double>(d2(a, a - 2));
    }
  }
  return h;
}

Table to_table(const RotationHelpers& h, const nlohmann::json& generator) {
  const std::int64_t n = sh_count(h.order);
  const std::int64_t nnz = static_cast<std::int64_t>(h.x90_val.size());
  const nlohmann::json meta = {{"x90_nonzeros", nnz}, {"description",
            "X90 = M(Rx(+90 deg)) in CSR; D1 = dM(Ry(b))/db(0) sub-diagonal; D2 = D1^2 diagonal "
            "and distance-2 diagonal"}};
  Table t = new_table(kRotationHelpersKind, h.order, generator, meta);
  t.arrays.push_back(TableArray::from<std::int32_t>("x90_row", {n + 1}, h.x90_row));
  t.arrays.push_back(TableArray::from<std::int32_t>("x90_col", {nnz}, h.x90_col));
  t.arrays.push_back(TableArray::from<double>("x90_val", {nnz}, h.x90_val));
  t.arrays.push_back(TableArray::from<double>("dy_sub", {n}, h.dy_sub));
  t.arrays.push_back(TableArray::from<double>("ddy_diag", {n}, h.ddy_diag));
  t.arrays.push_back(TableArray::from<double>("ddy_off2", {n}, h.ddy_off2));
  return t;
}

std::vector<std::vector<double>> x90_band_block(const RotationHelpers& h, int l) {
  const int size = 2 * l + 1, first = l * l;
  std::vector<std::vector<double>> b(size, std::vector<double>(size, 0.0));
  for (int i = 0; i < size; ++i)
    for (int k = h.x90_row[first + i]; k < h.x90_row[first + i + 1]; ++k)
      b[i][h.x90_col[k] - first] = h.x90_val[k];
  return b;
}

}  // namespace shtool
