#include "shtool/sh_window.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <utility>

#include "lighting/coefficient_layout.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

constexpr std::pair<std::string_view, ShWindow> kNames[] = {
    {"none", ShWindow::none}, {"hann", ShWindow::hann}, {"lanczos", ShWindow::lanczos}, {"sinc4", ShWindow::sinc4}};

int order_of(std::size_t count, int channels) { return detail::order_of_layout(count, channels, "sh window"); }

// Spherical Fibonacci points: near-uniform, no poles favoured.
std::vector<Eigen::Vector3d> fibonacci_points(int count) {
  std::vector<Eigen::Vector3d> points(count);
  const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
  for (int k = 0; k < count; ++k) {
    const double z = 1 - (2 * k + 1.0) / count;
    const double r = std::sqrt(std::max(0.0, 1 - z * z));
    points[k] = {r * std::cos(golden * k), r * std::sin(golden * k), z};
  }
  return points;
}

int dense_count(int order) { return std::max(4096, 32 * order * order); }

// Projected gradient descent on the sphere from `start`, with a halving step: the
// local minimum of f(w) = sum_i f_i y_i(w) near it.
ShMinimum refine(std::span<const double> f, int order, const Eigen::Vector3d& start) {
  const int n = sh_count(order);
  std::vector<double> values(n), grad(3 * static_cast<std::size_t>(n));
  auto evaluate = [&](const Eigen::Vector3d& w, Eigen::Vector3d* g) {
    eval_sh_with_gradient<double>(order, w, values, grad);
    double v = 0;
    Eigen::Vector3d gr = Eigen::Vector3d::Zero();
    for (int i = 0; i < n; ++i) {
      v += f[i] * values[i];
      gr += f[i] * Eigen::Vector3d(grad[3 * i], grad[3 * i + 1], grad[3 * i + 2]);
    }
    if (g) *g = gr;
    return v;
  };
  Eigen::Vector3d w = start, g;
  double v = evaluate(w, &g);
  // A first step of about one band's angular scale; shrinks as the minimum is approached.
  double step = 1.0 / (order * (std::abs(v) + g.norm() + 1e-300));
  for (int it = 0; it < 200 && g.norm() > 1e-14 * (1 + std::abs(v)); ++it) {
    bool moved = false;
    for (int tries = 0; tries < 40; ++tries) {
      const Eigen::Vector3d trial = (w - step * g).normalized();
      Eigen::Vector3d tg;
      const double tv = evaluate(trial, &tg);
      if (tv < v) {
        w = trial, v = tv, g = tg;
        step *= 2;
        moved = true;
        break;
      }
      step /= 2;
    }
    if (!moved) break;
  }
  return {v, w};
}

// The lowest few dense points of channel `channel` (values precomputed), refined.
ShMinimum minimum_from(std::span<const double> f, int order, const std::vector<Eigen::Vector3d>& points,
                       const std::vector<double>& dense_values) {
  constexpr int kStarts = 8;
  std::vector<int> index(points.size());
  for (std::size_t k = 0; k < index.size(); ++k) index[k] = static_cast<int>(k);
  const int starts = std::min<int>(kStarts, static_cast<int>(index.size()));
  std::partial_sort(index.begin(), index.begin() + starts, index.end(),
                    [&](int a, int b) { return dense_values[a] < dense_values[b]; });
  ShMinimum best{dense_values[index[0]], points[index[0]]};
  for (int s = 0; s < starts; ++s) {
    const ShMinimum m = refine(f, order, points[index[s]]);
    if (m.value < best.value) best = m;
  }
  return best;
}

}  // namespace

std::string_view sh_window_name(ShWindow window) {
  for (const auto& [name, value] : kNames)
    if (value == window) return name;
  return "none";
}

std::optional<ShWindow> sh_window_from_name(std::string_view name) {
  for (const auto& [n, value] : kNames)
    if (n == name) return value;
  return std::nullopt;
}

std::vector<double> sh_window_factors(ShWindow window, double cutoff, int order) {
  std::vector<double> w(order, 1.0);
  if (window == ShWindow::none) return w;
  for (int l = 0; l < order; ++l) {
    const double x = l / cutoff;
    if (x >= 1) {
      w[l] = 0;
      continue;
    }
    const double sinc = l == 0 ? 1 : std::sin(std::numbers::pi * x) / (std::numbers::pi * x);
    switch (window) {
      case ShWindow::hann: w[l] = (1 + std::cos(std::numbers::pi * x)) / 2; break;
      case ShWindow::lanczos: w[l] = sinc; break;
      case ShWindow::sinc4: w[l] = std::pow(sinc, 4); break;
      case ShWindow::none: break;
    }
  }
  return w;
}

ShMinimum sh_minimum(std::span<const double> coefficients, int channels, int channel) {
  const int order = order_of(coefficients.size(), channels);
  if (channel < 0 || channel >= channels) detail::precondition_failed("sh_minimum: channel out of range");
  std::vector<double> f(sh_count(order));
  for (int i = 0; i < sh_count(order); ++i) f[i] = coefficients[static_cast<std::size_t>(i) * channels + channel];
  const std::vector<Eigen::Vector3d> points = fibonacci_points(dense_count(order));
  std::vector<double> dense(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) dense[k] = reconstruct<double>(f, points[k]);
  return minimum_from(f, order, points, dense);
}

Result<AutoWindow> choose_auto_window(std::span<const double> coefficients, int channels) {
  const int order = order_of(coefficients.size(), channels);
  const std::vector<Eigen::Vector3d> points = fibonacci_points(dense_count(order));
  // band_values[(k * channels + c) * order + l]: band l's part of channel c at point k,
  // so that any window's dense values are a dot product with its factors.
  std::vector<double> band_values(points.size() * channels * order, 0.0);
  std::vector<double> y(sh_count(order));
  for (std::size_t k = 0; k < points.size(); ++k) {
    eval_sh<double>(order, points[k], y);
    for (int l = 0; l < order; ++l)
      for (int m = -l; m <= l; ++m)
        for (int c = 0; c < channels; ++c)
          band_values[(k * channels + c) * order + l] += coefficients[sh_index(l, m) * channels + c] * y[sh_index(l, m)];
  }
  std::vector<double> f(sh_count(order)), dense(points.size());
  auto minima = [&](const std::vector<double>& factors) {
    std::vector<double> result(channels);
    for (int c = 0; c < channels; ++c) {
      for (std::size_t k = 0; k < points.size(); ++k) {
        double v = 0;
        for (int l = 0; l < order; ++l) v += factors[l] * band_values[(k * channels + c) * order + l];
        dense[k] = v;
      }
      for (int i = 0; i < sh_count(order); ++i) f[i] = coefficients[i * channels + c] * factors[sh_band(i)];
      result[c] = minimum_from(f, order, points, dense).value;
    }
    return result;
  };
  auto non_negative = [](const std::vector<double>& m) {
    return std::all_of(m.begin(), m.end(), [](double v) { return v >= 0; });
  };
  for (int c = 0; c < channels; ++c)
    if (coefficients[c] < 0)
      return Error{"channel " + std::to_string(c) + " has a negative mean: no window makes it non-negative"};
  AutoWindow out;
  out.factors.assign(order, 1.0);
  out.minimum = minima(out.factors);
  if (non_negative(out.minimum)) return out;
  // sinc4 with a cutoff of 1 keeps band 0 alone, non-negative by the check above.
  double lo = 1, hi = 2.0 * order;
  while (non_negative(minima(sh_window_factors(ShWindow::sinc4, hi, order))) && hi < 1e6) lo = hi, hi *= 2;
  while (hi - lo > 1e-9 * lo) {
    const double mid = (lo + hi) / 2;
    (non_negative(minima(sh_window_factors(ShWindow::sinc4, mid, order))) ? lo : hi) = mid;
  }
  out.cutoff = lo;
  out.factors = sh_window_factors(ShWindow::sinc4, lo, order);
  out.minimum = minima(out.factors);
  return out;
}

}  // namespace shtool
