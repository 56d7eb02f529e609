#include "wrinkles/wrinkle_fit.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <nlopt.hpp>

#include "shtool/sh.h"

namespace shtool::wrinkles {

namespace {

// L-BFGS history: the problem has tens of thousands of parameters, and the curvature of
// ten recent steps is what quasi-Newton needs; a dense BFGS inverse Hessian would have
// their square (the reason [4] left BFGS for conjugate gradients).
constexpr unsigned kLbfgsMemory = 10;

// symmetric_start's price on the squared coefficients of a cone, against the squared
// residual: a wrinkle's cones (|g|^2 about 0.2) pay about 2e-4, the order of what they
// leave unfitted, while the pairs of lobes 1 degree apart with coefficients near 250
// that the scan picks without it pay about 100, far more than the whole transfer's
// |t|^2 (0.2 at most). 1e-4 let enough large cones through to quadruple the start's
// error at the defaults (0.38 against 0.09).
constexpr double kStartCoefficientPrice = 1e-3;

double normalized_rms(std::span<const double> residual2, std::span<const double> norm2) {
  const double r = std::accumulate(residual2.begin(), residual2.end(), 0.0);
  const double t = std::accumulate(norm2.begin(), norm2.end(), 0.0);
  return t > 0 ? std::sqrt(r / t) : std::sqrt(r);
}

}  // namespace

std::vector<double> fit_direct(const WrinkleGrid& grid, int order, std::span<const double> transfer) {
  const int n2 = sh_count(order);
  const int nodes = grid.nodes();
  std::vector<Eigen::Triplet<double>> entries;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nodes, kDirectCoefficients);
  for (int k = 0; k < grid.sample_rows(); ++k)
    for (int i = 0; i < grid.sample_columns(); ++i) {
      const BilinearWeights w = sample_weights(grid, i, k);
      const double* t = transfer.data() + grid.sample_index(i, k) * n2;
      for (int a = 0; a < 4; ++a) {
        for (int b = 0; b < 4; ++b) entries.emplace_back(w.node[a], w.node[b], w.weight[a] * w.weight[b]);
        for (int c = 0; c < kDirectCoefficients; ++c) rhs(w.node[a], c) += w.weight[a] * t[c];
      }
    }
  Eigen::SparseMatrix<double> normal(nodes, nodes);
  normal.setFromTriplets(entries.begin(), entries.end());
  // Every node is a sample with weight 1 on itself, so the normal matrix is positive definite.
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(normal);
  const Eigen::MatrixXd solution = solver.solve(rhs);
  std::vector<double> out(static_cast<std::size_t>(nodes) * kDirectCoefficients);
  for (int node = 0; node < nodes; ++node)
    for (int c = 0; c < kDirectCoefficients; ++c) out[static_cast<std::size_t>(node) * kDirectCoefficients + c] = solution(node, c);
  return out;
}

std::vector<fit::ZhFit> symmetric_start(const WrinkleGrid& grid, int order, int lobes, std::span<const double> transfer) {
  const int n2 = sh_count(order);
  const int nodes = grid.nodes();
  std::vector<bool> mask(order, true);
  mask[0] = mask[1] = false;
  std::vector<fit::ZhFit> best_fits;
  double best_total = std::numeric_limits<double>::infinity();
  std::vector<Eigen::Vector3d> axes(lobes);
  std::vector<double> coeffs(static_cast<std::size_t>(lobes) * order), best_coeffs(coeffs.size());
  for (int reference = 0; reference < 2; ++reference) {
    std::vector<fit::ZhFit> fits(nodes);
    double total = 0;
    for (int node = 0; node < nodes; ++node) {
      const int j = node % grid.grid, k = node / grid.grid;
      const std::span<const double> full =
          transfer.subspan(grid.sample_index(j * grid.samples, k * grid.samples) * n2, n2);
      const Eigen::Vector3d a = fit::optimal_linear_axis(full);
      // The lobes' share: bands 2..n-1 (DC and linear are stored directly).
      std::array<double, kMaxWrinkleOrder * kMaxWrinkleOrder> high{};
      std::copy(full.begin() + kDirectCoefficients, full.end(), high.begin() + kDirectCoefficients);
      const std::span<const double> t(high.data(), n2);
      Eigen::Vector3d perp = reference == 0 ? Eigen::Vector3d::UnitY() - a.y() * a : a.cross(Eigen::Vector3d::UnitY());
      // The linear axis along y itself (never for this height field, which is symmetric in y).
      if (perp.norm() < 1e-9) perp = a.unitOrthogonal();
      perp.normalize();
      const Eigen::Vector3d third = a.cross(perp);
      double best = std::numeric_limits<double>::infinity();
      std::vector<Eigen::Vector3d> best_axes;
      for (int degrees = 1; degrees < 90; ++degrees) {
        const double theta = degrees * std::numbers::pi / 180;
        axes[0] = a;
        for (int i = 1; i < lobes; ++i) {
          const double phi = 2 * std::numbers::pi * (i - 1) / (lobes - 1);
          axes[i] = std::cos(theta) * a + std::sin(theta) * (std::cos(phi) * perp + std::sin(phi) * third);
        }
        double r2 = 0;
        fit::zh_varpro_objective(order, t, mask, axes, {}, coeffs, &r2);
        // Nearly coincident lobes with large opposite coefficients fit one node a little
        // better but blend into nonsense between nodes; a small price on |g|^2 keeps the
        // cone open.
        for (double c : coeffs) r2 += kStartCoefficientPrice * c * c;
        if (r2 < best) {
          best = r2;
          best_axes = axes;
          best_coeffs = coeffs;
        }
        if (lobes == 1) break;  // no cone to scan
      }
      total += best;
      fits[node].lobes.resize(lobes);
      for (int i = 0; i < lobes; ++i) {
        fits[node].lobes[i].axis = best_axes[i];
        fits[node].lobes[i].coeffs.assign(best_coeffs.begin() + i * order, best_coeffs.begin() + (i + 1) * order);
      }
    }
    if (total < best_total) {
      best_total = total;
      best_fits = std::move(fits);
    }
  }
  return best_fits;
}

void set_model_lobes(WrinkleModel& model, const std::vector<fit::ZhFit>& fits) {
  model.axes.assign(static_cast<std::size_t>(model.grid.nodes()) * model.lobes * 3, 0.0);
  model.coeffs.assign(static_cast<std::size_t>(model.grid.nodes()) * model.lobes * model.order, 0.0);
  for (int node = 0; node < model.grid.nodes(); ++node)
    for (int i = 0; i < model.lobes; ++i) {
      const fit::ZhLobe& lobe = fits[node].lobes[i];
      const std::size_t base = static_cast<std::size_t>(node) * model.lobes + i;
      for (int a = 0; a < 3; ++a) model.axes[base * 3 + a] = lobe.axis[a];
      // Bands 0 and 1 belong to the direct part.
      for (int l = 2; l < model.order; ++l) model.coeffs[base * model.order + l] = lobe.coeffs[l];
    }
}

struct GlobalObjective::Impl {
  WrinkleGrid grid;
  int order, lobes, per_lobe;
  std::vector<double> target;          // per sample, bands 0 and 1 zeroed
  std::vector<BilinearWeights> weights;  // per sample
  ThreadPool pool;
  std::vector<std::vector<fit::ZhLobe>> scratch;  // per worker
  std::vector<double> sample_value, sample_grad;  // per sample
  std::span<const double> params;                 // of the evaluation under way
  bool with_grad = false;

  // Samples [begin, end) on one worker: the blended lobes, then Eq. 17 and its gradient
  // into the samples' own slots.
  void samples(int worker, std::size_t begin, std::size_t end) {
    const int n2 = sh_count(order), full = 3 + order, nl = lobes, per = per_lobe;
    std::vector<fit::ZhLobe>& blended = scratch[worker];
    for (std::size_t p = begin; p < end; ++p) {
      const BilinearWeights& w = weights[p];
      // The map's own blend (shtool/wrinkle_map.h) over the parameter layout: per node and
      // lobe, the axis then g*_2..g*_{n-1}; the axis stays unnormalised, zh_objective
      // differentiates through h(s).
      const std::size_t stride = static_cast<std::size_t>(nl) * per;
      for (int i = 0; i < nl; ++i) {
        fit::ZhLobe& lobe = blended[i];
        const std::size_t offset = static_cast<std::size_t>(i) * per;
        blend_wrinkle_values<double>(w, params.data(), stride, offset, 3, lobe.axis.data());
        lobe.coeffs[0] = lobe.coeffs[1] = 0.0;
        blend_wrinkle_values<double>(w, params.data(), stride, offset + 3, order - 2, lobe.coeffs.data() + 2);
      }
      std::span<double> g = with_grad ? std::span<double>(sample_grad.data() + p * nl * full, nl * full)
                                      : std::span<double>();
      sample_value[p] = fit::zh_objective(order, std::span<const double>(target.data() + p * n2, n2), blended, g);
    }
  }

  Impl(const WrinkleGrid& g, int n, int nl, std::span<const double> transfer, int threads)
      : grid(g), order(n), lobes(nl), per_lobe(3 + n - 2), pool(threads) {
    const int n2 = sh_count(n);
    target.assign(transfer.begin(), transfer.end());
    for (std::size_t p = 0; p < grid.sample_count(); ++p)
      std::fill(target.begin() + static_cast<std::ptrdiff_t>(p * n2),
                target.begin() + static_cast<std::ptrdiff_t>(p * n2 + kDirectCoefficients), 0.0);
    for (int k = 0; k < grid.sample_rows(); ++k)
      for (int i = 0; i < grid.sample_columns(); ++i) weights.push_back(sample_weights(grid, i, k));
    scratch.assign(pool.threads(), std::vector<fit::ZhLobe>(nl));
    for (auto& s : scratch)
      for (auto& lobe : s) lobe.coeffs.assign(n, 0.0);
    sample_value.resize(grid.sample_count());
    sample_grad.resize(grid.sample_count() * static_cast<std::size_t>(nl) * (3 + n));
  }
};

GlobalObjective::GlobalObjective(const WrinkleGrid& grid, int order, int lobes, std::span<const double> transfer,
                                 int threads)
    : impl_(std::make_unique<Impl>(grid, order, lobes, transfer, threads)) {}
GlobalObjective::~GlobalObjective() = default;

std::size_t GlobalObjective::parameter_count() const {
  return static_cast<std::size_t>(impl_->grid.nodes()) * impl_->lobes * impl_->per_lobe;
}

double GlobalObjective::value(std::span<const double> params, std::span<double> grad) {
  Impl& s = *impl_;
  const int full = 3 + s.order, nl = s.lobes, per = s.per_lobe;
  const bool with_grad = !grad.empty();
  s.params = params;
  s.with_grad = with_grad;
  // One pointer captured: std::function keeps it without allocating, every evaluation.
  s.pool.run(s.grid.sample_count(), [impl = &s](int worker, std::size_t begin, std::size_t end) {
    impl->samples(worker, begin, end);
  });
  double total = 0;
  for (double v : s.sample_value) total += v;
  if (with_grad) {
    std::fill(grad.begin(), grad.end(), 0.0);
    for (std::size_t p = 0; p < s.grid.sample_count(); ++p) {
      const BilinearWeights& w = s.weights[p];
      const double* gp = s.sample_grad.data() + p * nl * full;
      for (int c = 0; c < 4; ++c) {
        if (w.weight[c] == 0) continue;
        for (int i = 0; i < nl; ++i) {
          double* q = grad.data() + (static_cast<std::size_t>(w.node[c]) * nl + i) * per;
          const double* gi = gp + i * full;
          for (int a = 0; a < 3; ++a) q[a] += w.weight[c] * gi[a];
          for (int l = 2; l < s.order; ++l) q[3 + l - 2] += w.weight[c] * gi[3 + l];
        }
      }
    }
  }
  return total;
}

std::vector<double> GlobalObjective::pack(const WrinkleModel& m) const {
  std::vector<double> params(parameter_count());
  const int per = impl_->per_lobe;
  for (std::size_t b = 0; b < static_cast<std::size_t>(m.grid.nodes()) * m.lobes; ++b) {
    for (int a = 0; a < 3; ++a) params[b * per + a] = m.axes[b * 3 + a];
    for (int l = 2; l < m.order; ++l) params[b * per + 3 + l - 2] = m.coeffs[b * m.order + l];
  }
  return params;
}

void GlobalObjective::unpack(std::span<const double> params, WrinkleModel& m) const {
  const int per = impl_->per_lobe;
  m.axes.assign(static_cast<std::size_t>(m.grid.nodes()) * m.lobes * 3, 0.0);
  m.coeffs.assign(static_cast<std::size_t>(m.grid.nodes()) * m.lobes * m.order, 0.0);
  for (std::size_t b = 0; b < static_cast<std::size_t>(m.grid.nodes()) * m.lobes; ++b) {
    for (int a = 0; a < 3; ++a) m.axes[b * 3 + a] = params[b * per + a];
    for (int l = 2; l < m.order; ++l) m.coeffs[b * m.order + l] = params[b * per + 3 + l - 2];
  }
}

std::vector<double> model_residuals(const WrinkleModel& m, std::span<const double> transfer) {
  const int n2 = sh_count(m.order);
  std::vector<double> out(m.grid.sample_count());
  std::array<double, kMaxWrinkleOrder * kMaxWrinkleOrder> v{};
  for (int k = 0; k < m.grid.sample_rows(); ++k)
    for (int i = 0; i < m.grid.sample_columns(); ++i) {
      const std::size_t p = m.grid.sample_index(i, k);
      evaluate_model(m, sample_weights(m.grid, i, k), v);
      double r = 0;
      for (int c = 0; c < n2; ++c) r += (v[c] - transfer[p * n2 + c]) * (v[c] - transfer[p * n2 + c]);
      out[p] = r;
    }
  return out;
}

namespace {

struct LbfgsState {
  GlobalObjective* objective;
  std::vector<double> best;
  double best_value = std::numeric_limits<double>::infinity();
  int evaluations = 0;
};

double lbfgs_callback(const std::vector<double>& x, std::vector<double>& grad, void* data) {
  auto* s = static_cast<LbfgsState*>(data);
  const double v = s->objective->value(x, grad);
  ++s->evaluations;
  if (v < s->best_value) {
    s->best_value = v;
    std::copy(x.begin(), x.end(), s->best.begin());
  }
  return v;
}

}  // namespace

namespace {

double dot(std::span<const double> a, std::span<const double> b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += a[i] * b[i];
  return s;
}

}  // namespace

int minimize_conjugate_gradient(GlobalObjective& objective, std::vector<double>& x, int max_evaluations,
                                double ftol_rel) {
  constexpr double c1 = 1e-4, c2 = 0.1;
  const std::size_t n = x.size();
  std::vector<double> g(n), d(n), trial(n), g_trial(n);
  int evaluations = 1;
  double f = objective.value(x, g);
  for (std::size_t i = 0; i < n; ++i) d[i] = -g[i];
  double slope0 = dot(g, d);
  // First step: a move of 1e-2 in the largest parameter change.
  double step_guess = 0;
  for (double v : d) step_guess = std::max(step_guess, std::abs(v));
  step_guess = step_guess > 0 ? 1e-2 / step_guess : 1.0;
  while (evaluations < max_evaluations && slope0 < 0) {
    // Line search along d: bracket, then zoom (Nocedal and Wright, Alg. 3.5 and 3.6),
    // the zoom by the minimiser of a quadratic kept inside the middle 80 % of the bracket.
    double f_a = 0;
    const auto eval_at = [&](double a) {
      for (std::size_t i = 0; i < n; ++i) trial[i] = x[i] + a * d[i];
      f_a = objective.value(trial, g_trial);
      ++evaluations;
      return dot(g_trial, d);
    };
    const auto armijo = [&](double a) { return f_a <= f + c1 * a * slope0; };
    const auto curvature = [&](double slope) { return std::abs(slope) <= -c2 * slope0; };
    // The bracket: lo, the lowest point so far that meets the sufficient decrease, and hi.
    double lo = 0, f_lo = f, slope_lo = slope0, hi = 0, f_hi = 0;
    const auto move_hi = [&](double to, double f_to) {
      hi = to;
      f_hi = f_to;
    };
    const auto move_lo = [&](double to, double f_to, double slope_to) {
      lo = to;
      f_lo = f_to;
      slope_lo = slope_to;
    };
    double a = step_guess;
    bool accepted = false, zoom = false;
    for (int i = 0; evaluations < max_evaluations; ++i) {
      const double slope_a = eval_at(a);
      if (!armijo(a) || (i > 0 && f_a >= f_lo)) {
        move_hi(a, f_a);
        zoom = true;
        break;
      }
      if (curvature(slope_a)) {
        accepted = true;
        break;
      }
      if (slope_a >= 0) {
        move_hi(lo, f_lo);
        move_lo(a, f_a, slope_a);
        zoom = true;
        break;
      }
      move_lo(a, f_a, slope_a);
      a *= 2;
    }
    while (zoom && !accepted && evaluations < max_evaluations) {
      const double w = hi - lo;
      if (std::abs(w) <= 1e-14 * std::max(1.0, std::abs(lo))) break;
      const double curv = f_hi - f_lo - slope_lo * w;
      double frac = curv > 0 ? -slope_lo * w / (2 * curv) : 0.5;
      frac = std::clamp(frac, 0.1, 0.9);
      a = lo + frac * w;
      const double slope_a = eval_at(a);
      if (!armijo(a) || f_a >= f_lo) {
        move_hi(a, f_a);
        continue;
      }
      if (curvature(slope_a)) {
        accepted = true;
        break;
      }
      if (slope_a * w >= 0) move_hi(lo, f_lo);
      move_lo(a, f_a, slope_a);
    }
    if (!accepted) {
      // Out of evaluations or a collapsed bracket: keep the best point found.
      if (lo > 0 && f_lo < f)
        for (std::size_t i = 0; i < n; ++i) x[i] += lo * d[i];
      break;
    }
    const double f_old = f;
    std::copy(trial.begin(), trial.end(), x.begin());
    // Polak-Ribiere+: beta = max(0, g1 . (g1 - g0) / |g0|^2).
    const double g0 = dot(g, g);
    const double beta = std::max(0.0, (dot(g_trial, g_trial) - dot(g_trial, g)) / g0);
    for (std::size_t i = 0; i < n; ++i) d[i] = -g_trial[i] + beta * d[i];
    std::copy(g_trial.begin(), g_trial.end(), g.begin());
    f = f_a;
    double slope = dot(g, d);
    if (slope >= 0) {
      for (std::size_t i = 0; i < n; ++i) d[i] = -g[i];
      slope = dot(g, d);
    }
    step_guess = a * slope0 / slope;  // the same first-order change as the last step
    slope0 = slope;
    if (f_old - f <= ftol_rel * std::abs(f)) break;
  }
  return evaluations;
}

namespace {

Eigen::Map<Eigen::Vector3d> node_axis(WrinkleModel& m, int node, int lobe) {
  return Eigen::Map<Eigen::Vector3d>(m.axes.data() + (static_cast<std::size_t>(node) * m.lobes + lobe) * 3);
}

// |g| of a node's lobe over the bands it stores (2..n-1).
double lobe_strength(const WrinkleModel& m, int node, int lobe) {
  const double* c = m.coeffs.data() + (static_cast<std::size_t>(node) * m.lobes + lobe) * m.order;
  double s = 0;
  for (int l = 2; l < m.order; ++l) s += c[l] * c[l];
  return std::sqrt(s);
}

// A lobe and its reverse with the odd bands negated are the same lobe at a node, but the
// bilinear blend between nodes sees the axis: where a lobe carries next to nothing (the
// flat groove at depth 0) the search leaves its axis pointing anywhere, and neighbours
// pointing apart blend through zero, which the runtime refuses. The signs are chosen as a
// maximum spanning tree of the grid (x periodic) agrees: edges taken strongest first
// (|g| at both ends times |cos| of their axes), each joining two groups of nodes with the
// relative sign it wants (union-find with parity), so that a weak lobe with an arbitrary
// axis cannot set the signs of the strong ones beyond it.
void align_lobe_signs(WrinkleModel& m) {
  const int g = m.grid.grid, nodes = g * g;
  struct Edge {
    double weight;
    int a, b;
    bool flip;
  };
  for (int lobe = 0; lobe < m.lobes; ++lobe) {
    std::vector<Edge> edges;
    auto add = [&](int a, int b) {
      const double c = node_axis(m, a, lobe).normalized().dot(node_axis(m, b, lobe).normalized());
      edges.push_back({lobe_strength(m, a, lobe) * lobe_strength(m, b, lobe) * std::abs(c), a, b, c < 0});
    };
    for (int k = 0; k < g; ++k)
      for (int j = 0; j < g; ++j) {
        add(k * g + j, k * g + (j + 1) % g);
        if (k + 1 < g) add(k * g + j, (k + 1) * g + j);
      }
    // Ties (equal weights) in the order made: the signs do not depend on the sort.
    std::stable_sort(edges.begin(), edges.end(), [](const Edge& x, const Edge& y) { return x.weight > y.weight; });
    std::vector<int> parent(nodes);
    std::vector<char> parity(nodes, 0);  // relative to the parent
    std::iota(parent.begin(), parent.end(), 0);
    // Root of n and n's parity relative to it (paths compressed).
    auto find = [&](auto&& self, int n) -> std::pair<int, char> {
      if (parent[n] == n) return {n, 0};
      const auto [root, p] = self(self, parent[n]);
      parent[n] = root;
      parity[n] = static_cast<char>(parity[n] ^ p);
      return {root, parity[n]};
    };
    for (const Edge& e : edges) {
      const auto ra = find(find, e.a), rb = find(find, e.b);
      if (ra.first == rb.first) continue;
      parent[rb.first] = ra.first;
      parity[rb.first] = static_cast<char>(ra.second ^ rb.second ^ (e.flip ? 1 : 0));
    }
    for (int node = 0; node < nodes; ++node) {
      if (!find(find, node).second) continue;
      node_axis(m, node, lobe) = -node_axis(m, node, lobe);
      double* coeffs = m.coeffs.data() + (static_cast<std::size_t>(node) * m.lobes + lobe) * m.order;
      for (int l = 1; l < m.order; l += 2) coeffs[l] = -coeffs[l];
    }
  }
}

// A map the runtime would refuse (a lobe's axes around a cell spread past 90 degrees of
// their sum) is mended: first every node's lobe is turned to agree with its neighbours
// (align_lobe_signs); where a cell still spreads (a lobe weak at one node and strong at
// its neighbours turns freely at the weak one), the weakest of the four is moved to its
// neighbours' mean axis, weighted by their coefficients, and that node's coefficients are
// solved again for its axes (its own sample, bands 2..n-1). The fit's error is measured
// afterwards on the mended model; a map that still spreads is refused by the job.
void repair_spread_cells(WrinkleModel& m, std::span<const double> transfer) {
  const int g = m.grid.grid, n2 = sh_count(m.order);
  auto axis = [&](int node, int lobe) { return node_axis(m, node, lobe); };
  auto strength = [&](int node, int lobe) { return lobe_strength(m, node, lobe); };
  auto spread = [&](const int (&cell)[4], int lobe) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int q : cell) sum += axis(q, lobe).normalized();
    bool out = false;
    for (int q : cell) out = out || !(axis(q, lobe).normalized().dot(sum) > 0);
    return out;
  };
  auto cell_at = [&](int k, int j, int (&cell)[4]) {
    cell[0] = k * g + j;
    cell[1] = k * g + (j + 1) % g;
    cell[2] = (k + 1) * g + j;
    cell[3] = (k + 1) * g + (j + 1) % g;
  };
  // A map the runtime loads is left as the search made it, bit for bit.
  bool any = false;
  for (int lobe = 0; lobe < m.lobes && !any; ++lobe)
    for (int k = 0; k + 1 < g && !any; ++k)
      for (int j = 0; j < g && !any; ++j) {
        int cell[4];
        cell_at(k, j, cell);
        any = spread(cell, lobe);
      }
  if (!any) return;
  align_lobe_signs(m);
  std::vector<bool> mask(m.order, true);
  mask[0] = mask[1] = false;
  // Each pass fixes every spread cell it finds; a move can spread a neighbouring cell,
  // so a few passes, bounded.
  for (int pass = 0; pass < 4 * g; ++pass) {
    bool moved = false;
    for (int lobe = 0; lobe < m.lobes; ++lobe)
      for (int k = 0; k + 1 < g; ++k)
        for (int j = 0; j < g; ++j) {
          int cell[4];
          cell_at(k, j, cell);
          if (!spread(cell, lobe)) continue;
          const int weak = *std::min_element(std::begin(cell), std::end(cell),
                                             [&](int a, int b) { return strength(a, lobe) < strength(b, lobe); });
          const int wj = weak % g, wk = weak / g;
          Eigen::Vector3d mean = Eigen::Vector3d::Zero();
          const int around[4] = {wk * g + (wj + 1) % g, wk * g + (wj + g - 1) % g, wk > 0 ? weak - g : -1,
                                 wk + 1 < g ? weak + g : -1};
          for (int q : around)
            if (q >= 0) {
              const Eigen::Vector3d a = axis(q, lobe).normalized();
              // Sign-free: a lobe's axis and its reverse are the same lobe.
              mean += strength(q, lobe) * (a.dot(mean) < 0 ? -a : a);
            }
          if (!(mean.norm() > 0)) continue;
          axis(weak, lobe) = mean.normalized();
          std::vector<Eigen::Vector3d> axes(m.lobes);
          for (int i = 0; i < m.lobes; ++i) axes[i] = axis(weak, i);
          std::array<double, kMaxWrinkleOrder * kMaxWrinkleOrder> high{};
          const std::span<const double> full =
              transfer.subspan(m.grid.sample_index(wj * m.grid.samples, wk * m.grid.samples) * n2, n2);
          std::copy(full.begin() + kDirectCoefficients, full.end(), high.begin() + kDirectCoefficients);
          std::vector<double> coeffs(static_cast<std::size_t>(m.lobes) * m.order);
          fit::zh_varpro_objective(m.order, std::span<const double>(high.data(), n2), mask, axes, {}, coeffs);
          for (int i = 0; i < m.lobes; ++i)
            for (int l = 2; l < m.order; ++l)
              m.coeffs[(static_cast<std::size_t>(weak) * m.lobes + i) * m.order + l] = coeffs[i * m.order + l];
          moved = true;
        }
    if (!moved) return;
    align_lobe_signs(m);
  }
}

}  // namespace

WrinkleFit fit_wrinkles(const WrinkleGrid& grid, std::span<const double> transfer, const WrinkleFitOptions& options) {
  const int n2 = sh_count(options.order);
  const int threads = resolve_threads(options.threads);
  WrinkleFit out;
  WrinkleModel& model = out.model;
  model.grid = grid;
  model.order = options.order;
  model.lobes = options.lobes;
  model.direct = fit_direct(grid, options.order, transfer);

  // Independent fits at every sample: the comparison, and at the nodes the start.
  fit::ZhFitOptions zo;
  zo.order = options.order;
  zo.lobes = options.lobes;
  zo.direct = true;
  zo.seed = options.seed;
  // One fit::fit_zh per sample, stream = sample index: results by index, whatever the
  // thread count.
  std::vector<fit::ZhFit> per_point(grid.sample_count());
  parallel_for(grid.sample_count(), threads, [&](std::size_t p) {
    per_point[p] = fit::fit_zh(transfer.subspan(p * n2, n2), zo, p);
  });
  out.norm2.resize(grid.sample_count());
  out.per_point_residual2.resize(grid.sample_count());
  for (std::size_t p = 0; p < grid.sample_count(); ++p) {
    double t2 = 0;
    for (int c = 0; c < n2; ++c) t2 += transfer[p * n2 + c] * transfer[p * n2 + c];
    out.norm2[p] = t2;
    out.per_point_residual2[p] = per_point[p].residual * per_point[p].residual;
  }
  out.errors.per_point = normalized_rms(out.per_point_residual2, out.norm2);

  // Independent node fits interpolated: what [4] warns against (lobes do not correspond).
  std::vector<fit::ZhFit> nodes;
  for (int k = 0; k < grid.grid; ++k)
    for (int j = 0; j < grid.grid; ++j) nodes.push_back(per_point[grid.sample_index(j * grid.samples, k * grid.samples)]);
  set_model_lobes(model, nodes);
  out.errors.node_fits = normalized_rms(model_residuals(model, transfer), out.norm2);
  set_model_lobes(model, symmetric_start(grid, options.order, options.lobes, transfer));
  out.errors.start = normalized_rms(model_residuals(model, transfer), out.norm2);

  GlobalObjective objective(grid, options.order, options.lobes, transfer, threads);
  std::vector<double> x = objective.pack(model);
  if (options.optimizer == WrinkleOptimizer::cg) {
    out.evaluations = minimize_conjugate_gradient(objective, x, options.max_evaluations, options.ftol_rel);
    objective.unpack(x, model);
  } else {
    LbfgsState state{&objective, x};
    nlopt::opt opt(nlopt::LD_LBFGS, static_cast<unsigned>(x.size()));
    opt.set_min_objective(lbfgs_callback, &state);
    opt.set_ftol_rel(options.ftol_rel);
    opt.set_maxeval(options.max_evaluations);
    opt.set_vector_storage(kLbfgsMemory);
    double value = 0;
    try {
      opt.optimize(x, value);
    } catch (const std::exception&) {
      // A failed line search (at the defaults after 645 evaluations; a fresh run from the
      // best point fails again within 12) or roundoff: the best point evaluated is kept.
    }
    objective.unpack(state.best, model);
    out.evaluations = state.evaluations;
  }
  repair_spread_cells(model, transfer);
  out.global_residual2 = model_residuals(model, transfer);
  out.errors.global = normalized_rms(out.global_residual2, out.norm2);
  return out;
}

}  // namespace shtool::wrinkles
