#include "fit/zh_fit.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <string>
#include <thread>

#include <Eigen/Dense>
#include <nlopt.hpp>

#include "common/input_error.h"
#include "common/parallel_for.h"
#include "common/random.h"
#include "shtool/sh.h"
#include "shtool/zh.h"

namespace shtool::fit {
namespace {

// The multi-start axes: uniform on the sphere from a splitmix64 stream.
struct Rng : SplitMixStream {
  Eigen::Vector3d unit_vector() {
    const double z = 2.0 * uniform() - 1.0, phi = 2.0 * std::numbers::pi * uniform();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
  }
};

double squared_norm(std::span<const double> v) {
  double s = 0;
  for (double x : v) s += x * x;
  return s;
}

// ||v|| without underflow or overflow in the squares (a transfer vector of 1e-160 has
// squares below the smallest double). Not Eigen's stableNorm: its blocked sum differs in
// the last bit, which moves the searches' paths (the fixture's effort-3 ratio 1.059 ->
// 1.061), and the figures of docs/fit-zh.md are measured with this one.
double scaled_norm(std::span<const double> v) {
  double largest = 0;
  for (double x : v) largest = std::max(largest, std::abs(x));
  if (largest == 0) return 0;
  double s = 0;
  for (double x : v) s += (x / largest) * (x / largest);
  return largest * std::sqrt(s);
}

void check_options(const ZhFitOptions& o) {
  if (!is_supported_order(o.order)) throw InputError("fit_zh: unsupported order " + std::to_string(o.order));
  if (o.lobes < 1) throw InputError("fit_zh: need at least one lobe");
}

std::vector<bool> free_bands(const ZhFitOptions& o) {
  std::vector<bool> mask(o.order, true);
  if (o.direct) {
    mask[0] = false;
    if (o.lobes >= 3 && o.order > 1) mask[1] = false;
  }
  return mask;
}

// Bands with mask[l] false are frozen at 0 and left out of the BFGS variables.
struct Packing {
  int order;
  std::vector<int> bands;  // free bands
  int per_lobe() const { return 3 + static_cast<int>(bands.size()); }
};

void pack(const Packing& p, const std::vector<ZhLobe>& lobes, std::vector<double>& x) {
  x.assign(lobes.size() * p.per_lobe(), 0.0);
  for (std::size_t k = 0; k < lobes.size(); ++k) {
    double* o = x.data() + k * p.per_lobe();
    for (int c = 0; c < 3; ++c) o[c] = lobes[k].axis[c];
    for (std::size_t j = 0; j < p.bands.size(); ++j) o[3 + j] = lobes[k].coeffs[p.bands[j]];
  }
}

void unpack(const Packing& p, const std::vector<double>& x, std::vector<ZhLobe>& lobes) {
  for (std::size_t k = 0; k < lobes.size(); ++k) {
    const double* o = x.data() + k * p.per_lobe();
    lobes[k].axis = Eigen::Vector3d(o[0], o[1], o[2]);
    std::fill(lobes[k].coeffs.begin(), lobes[k].coeffs.end(), 0.0);
    for (std::size_t j = 0; j < p.bands.size(); ++j) lobes[k].coeffs[p.bands[j]] = o[3 + j];
  }
}

// s / |s|, or +z where that is undefined (a zero or non-finite axis from a failed step).
Eigen::Vector3d unit_or_z(const Eigen::Vector3d& s) {
  const double len = s.norm();
  return len > 0 && std::isfinite(len) ? Eigen::Vector3d(s / len) : Eigen::Vector3d::UnitZ();
}

void normalize_axes(std::vector<ZhLobe>& lobes) {
  for (ZhLobe& lobe : lobes) lobe.axis = unit_or_z(lobe.axis);
}

constexpr unsigned kLbfgsMemory = 6;

// Minimises from x with NLopt's L-BFGS until a relative change of the value below
// ftol_rel or max_evaluations; the objective keeps its own best point, since NLopt may
// end with an exception (roundoff_limited) after a good step.
void run_lbfgs(nlopt::vfunc objective, void* data, std::vector<double>& x, double ftol_rel, int max_evaluations) {
  nlopt::opt opt(nlopt::LD_LBFGS, static_cast<unsigned>(x.size()));
  opt.set_min_objective(objective, data);
  opt.set_ftol_rel(ftol_rel);
  // ftol_abs lets a vector that is exactly representable (N >= order) stop at rounding
  // level.
  opt.set_ftol_abs(1e-28);
  opt.set_xtol_rel(1e-10);
  opt.set_maxeval(max_evaluations);
  // NLopt's default L-BFGS memory is sized from available RAM and made its own
  // bookkeeping 75% of the run time here; a short history converges as well on this
  // smooth, small problem.
  opt.set_vector_storage(kLbfgsMemory);
  double value = 0;
  try {
    opt.optimize(x, value);
  } catch (const std::exception&) {
    // roundoff_limited and friends: the caller falls back to the best point evaluated.
  }
}

struct BfgsData {
  int order;
  std::span<const double> t;
  const Packing* packing;
  std::vector<ZhLobe> lobes;
  std::vector<double> full_grad;
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> best_x;
};

// Stopping rules of the variable-projection runs, as a relative change of psi. Starts
// stop at 1e-3: which start wins is mostly settled by then (in a trial on the benchmark's
// random vectors, N = 4 and 64 starts, stopping them at 1e-6 instead lowered the mean best
// residual by 0.7 % for 1.7x the evaluations, where twice the starts lowered it by 5 %). The
// winner is polished to options.polish_ftol_rel (default 1e-3: a few tenths of a percent
// of psi are worth less than the evaluations a tighter stop costs), or to 1e-10 when an
// exact fit exists (N >= order), so that it is found; for 3 <= lobes < order to
// options.split_polish_ftol_rel within split_polish_evaluations (on the fit fixture's
// transfer vectors at N = 4, 1e-4 within 30 evaluations lowers the mean residual over the
// best known from 1.358 to 1.352 for 3 % more evaluations on the bunny; within 40, 1.346
// for 9 %; within 300, 1.336 for 24 %; with the low-order start as well, within 50 (the
// default) 1.331 and within 300 1.322, for 28 % and 41 % more evaluations on the bunny
// than 30 without it).
constexpr double kVarProStartFtolRel = 1e-3;
constexpr double kVarProExactFtolRel = 1e-10;
// The greedy stages before the last: 1e-2, at most 30 evaluations.
constexpr double kVarProStageFtolRel = 1e-2;
constexpr int kVarProStageEvaluations = 30;
// The split start (3 <= lobes < order, see varpro_search): the greedy start and the split
// start are each grown with stages of at most 10 evaluations and a last stage stopped at
// 1e-2 or 15 evaluations, and only the better of the two is polished. Two starts at these
// stops cost about 1.3 times the evaluations of the one greedy start at the stops above
// (90 against 70 a vector on the bunny's transfer), the greedy start alone less (about
// 60), so with the split start skipped where the greedy start is already good
// (split_above) the fit of a mesh costs about what it did with the greedy start alone
// (docs/fit-zh.md, "Measured figures").
constexpr int kSplitStageEvaluations = 10;
constexpr int kSplitLastEvaluations = 15;
constexpr double kSplitLastFtolRel = 1e-2;
// The two axes of the split start lie this far (radians, to first order) either side of
// the single-lobe axis.
constexpr double kSplitAngle = 0.1;
// The re-seated last lobe (see varpro_search): the next grid maxima of what the other
// lobes leave, at least kReseatMinAngle (radians) from every lobe, each polished for at
// most kReseatEvaluations. How many depends on the residual (a fraction of ||t||) the
// better start leaves: one above split_above, a second above kSecondReseatAbove, a third
// above kThirdReseatAbove. On the fit fixture's transfer vectors at N = 4 this lowers the
// mean residual over the best known from 1.427 (one re-seat of 15 evaluations) to 1.358,
// for 7 % more fit time on the bunny (its normalized RMS 0.00925 -> 0.00909); three
// re-seats wherever the first runs reach 1.354 for 18-26 % more, two 1.364 for 10-14 %,
// too much of the bunny's budget (fit no dearer than simulation).
constexpr int kMaxReseats = 3;
constexpr double kSecondReseatAbove = 0.0035;
constexpr double kThirdReseatAbove = 0.01;
constexpr int kReseatEvaluations = 10;
constexpr double kReseatMinAngle = 0.25;
// The low-order start (see varpro_search): grown like the greedy start on bands
// 0..order-2, then polished on every band for at most kLowOrderPolishEvaluations; run
// where the fit so far leaves more than kLowOrderStartAbove of ||t||. With one band fewer
// the axes have fewer constraints to meet (bands 0 and 1 are exact with 4 lobes), so the
// landscape has fewer local minima and the growth lands in other basins than the greedy
// and split starts. On the fit fixture's transfer vectors at N = 4 (with the polish
// within 300 evaluations) it lowers the mean residual over the best known from 1.336 to
// 1.322 for 26 % more evaluations a vector there and 14 % more on the bunny; run above
// 0.75 % or 1 % of ||t|| instead, 1.333. Started on bands 0..order-3 instead it finds
// nothing the other starts miss; started from the best axes so far (band order-1
// dropped, then restored) it moves them too little.
constexpr double kLowOrderStartAbove = 0.005;
constexpr int kLowOrderPolishEvaluations = 20;
// A single lobe's refinement from a grid peak: two angles, converged in far fewer.
constexpr int kSingleLobeEvaluations = 200;

double bfgs_objective(const std::vector<double>& x, std::vector<double>& grad, void* raw) {
  auto* d = static_cast<BfgsData*>(raw);
  const Packing& p = *d->packing;
  unpack(p, x, d->lobes);
  const int per_full = 3 + d->order;
  d->full_grad.assign(d->lobes.size() * per_full, 0.0);
  const double psi = zh_objective(d->order, d->t, d->lobes, grad.empty() ? std::span<double>() : d->full_grad);
  if (!grad.empty()) {
    for (std::size_t k = 0; k < d->lobes.size(); ++k) {
      for (int c = 0; c < 3; ++c) grad[k * p.per_lobe() + c] = d->full_grad[k * per_full + c];
      for (std::size_t j = 0; j < p.bands.size(); ++j)
        grad[k * p.per_lobe() + 3 + j] = d->full_grad[k * per_full + 3 + p.bands[j]];
    }
  }
  // NLopt may end with an exception (roundoff_limited) after a good step; keep the
  // best point seen so that work is never lost.
  if (psi < d->best) {
    d->best = psi;
    d->best_x = x;
  }
  return psi;
}

// Joint BFGS over all lobe parameters (Sec. 4.1). Returns psi; lobes are updated with
// unit axes.
double bfgs(int order, std::span<const double> t, const Packing& packing, std::vector<ZhLobe>& lobes,
            int max_evaluations) {
  normalize_axes(lobes);
  if (packing.bands.empty()) return zh_objective(order, t, lobes, {});
  BfgsData data{order, t, &packing, lobes, {}, std::numeric_limits<double>::infinity(), {}};
  std::vector<double> x;
  pack(packing, lobes, x);
  // ftol_rel 1e-12: below that the gains are invisible in the normalised RMS, and
  // the evaluation budget is the cost of the whole job.
  run_lbfgs(bfgs_objective, &data, x, 1e-12, max_evaluations);
  if (!data.best_x.empty()) unpack(packing, data.best_x, lobes);
  normalize_axes(lobes);
  return zh_objective(order, t, lobes, {});
}

// Coefficients with axes frozen: per band an independent least-squares problem
// t_l ~ sum_k g*_kl y_l(s_k) (bands do not interact, Sec. 4.1 note 2), solved with
// the minimum-norm solution (band 0 has identical columns).
void refit_coefficients(int order, std::span<const double> t, const std::vector<bool>& mask,
                        std::vector<ZhLobe>& lobes) {
  const int n = static_cast<int>(lobes.size());
  std::vector<std::vector<double>> y(n, std::vector<double>(sh_count(order)));
  for (int k = 0; k < n; ++k) eval_sh<double>(order, lobes[k].axis, y[k]);
  for (int l = 0; l < order; ++l) {
    if (!mask[l]) {
      for (ZhLobe& lobe : lobes) lobe.coeffs[l] = 0.0;
      continue;
    }
    Eigen::MatrixXd a(2 * l + 1, n);
    Eigen::VectorXd b(2 * l + 1);
    for (int m = -l; m <= l; ++m) {
      b[m + l] = t[sh_index(l, m)];
      for (int k = 0; k < n; ++k) a(m + l, k) = y[k][sh_index(l, m)];
    }
    const Eigen::VectorXd g = a.completeOrthogonalDecomposition().solve(b);
    for (int k = 0; k < n; ++k) lobes[k].coeffs[l] = g[k];
  }
}

ZhLobe fit_one_lobe(int order, std::span<const double> t, const std::vector<bool>& mask,
                    const std::vector<Eigen::Vector3d>& axes, const Packing& packing, const ZhFitOptions& o) {
  // Dense scan with the closed form (Eq. 18): psi(s) for every axis of the set.
  std::vector<std::pair<double, int>> scored;
  std::vector<double> coeffs(order);
  for (std::size_t i = 0; i < axes.size(); ++i)
    scored.emplace_back(single_lobe_closed_form(order, t, axes[i], coeffs, mask), static_cast<int>(i));
  const int keep = std::min<int>(o.single_lobe_refinements, static_cast<int>(scored.size()));
  std::partial_sort(scored.begin(), scored.begin() + keep, scored.end());
  std::vector<Eigen::Vector3d> starts;
  for (int i = 0; i < keep; ++i) starts.push_back(axes[scored[i].second]);
  starts.push_back(optimal_linear_axis(t));

  ZhLobe best;
  double best_psi = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& s : starts) {
    std::vector<ZhLobe> lobe(1);
    lobe[0].axis = s;
    lobe[0].coeffs.assign(order, 0.0);
    single_lobe_closed_form(order, t, s, lobe[0].coeffs, mask);
    double psi = bfgs(order, t, packing, lobe, o.max_evaluations);
    // BFGS moves axis and coefficients together; re-solving Eq. 18 at its final axis
    // can only lower psi.
    std::vector<double> c(order);
    const double closed = single_lobe_closed_form(order, t, lobe[0].axis, c, mask);
    if (closed < psi) {
      lobe[0].coeffs = c;
      psi = closed;
    }
    if (psi < best_psi) {
      best_psi = psi;
      best = lobe[0];
    }
  }
  // Every candidate non-finite (inputs near the end of the double range): a zero lobe
  // along the first start, so that callers always get `order` coefficients.
  if (best.coeffs.size() != static_cast<std::size_t>(order)) {
    best.axis = starts.front();
    best.coeffs.assign(order, 0.0);
  }
  return best;
}

// [4] Sec. 4.1 as printed: greedy lobes, coefficient refit, joint BFGS over axes and
// coefficients, then random axis sets each refit and BFGS-refined.
std::vector<ZhLobe> joint_search(int order, std::span<const double> t, const std::vector<bool>& mask,
                                 const ZhFitOptions& o, std::uint64_t stream, double good) {
  const int n2 = sh_count(order);
  Packing packing{order, {}};
  for (int l = 0; l < order; ++l)
    if (mask[l]) packing.bands.push_back(l);
  const std::vector<Eigen::Vector3d> axes = hemisphere_axes(o.axis_samples);

  // Greedy: each lobe fitted to what the previous ones left (Sec. 4.1).
  std::vector<ZhLobe> lobes;
  std::vector<double> residual(t.begin(), t.end()), approx(n2);
  for (int k = 0; k < o.lobes; ++k) {
    lobes.push_back(fit_one_lobe(order, residual, mask, axes, packing, o));
    lobes_to_sh(order, lobes, approx);
    for (int i = 0; i < n2; ++i) residual[i] = t[i] - approx[i];
  }
  double best_psi;
  if (o.lobes > 1) {
    refit_coefficients(order, t, mask, lobes);
    best_psi = bfgs(order, t, packing, lobes, o.max_evaluations);
  } else {
    best_psi = zh_objective(order, t, lobes, {});
  }
  std::vector<ZhLobe> best = lobes;

  // Multi-start from random axis sets (Sec. 4.1, "additional searching").
  Rng rng{splitmix64(o.seed ^ splitmix64(stream ^ 0x5A17C0DEull))};
  for (int s = 0; s < o.starts && best_psi > good; ++s) {
    std::vector<ZhLobe> trial(o.lobes);
    for (ZhLobe& lobe : trial) {
      lobe.axis = rng.unit_vector();
      lobe.coeffs.assign(order, 0.0);
    }
    refit_coefficients(order, t, mask, trial);
    const double psi = bfgs(order, t, packing, trial, o.max_evaluations);
    if (psi < best_psi) {
      best_psi = psi;
      best = trial;
    }
  }
  return best;
}

// ---- variable projection: L-BFGS over the axes alone

struct VarProData {
  int order;
  std::span<const double> t;
  const std::vector<bool>* mask;
  std::vector<Eigen::Vector3d> axes;
  double best = std::numeric_limits<double>::infinity();
  double best_residual = std::numeric_limits<double>::infinity();  // ||t~ - t||^2 there
  std::vector<double> best_x;
};

double varpro_bfgs_objective(const std::vector<double>& x, std::vector<double>& grad, void* raw) {
  auto* d = static_cast<VarProData*>(raw);
  for (std::size_t k = 0; k < d->axes.size(); ++k) d->axes[k] = Eigen::Vector3d(x[3 * k], x[3 * k + 1], x[3 * k + 2]);
  double residual = 0;
  const double psi = zh_varpro_objective(d->order, d->t, *d->mask, d->axes,
                                         grad.empty() ? std::span<double>() : std::span<double>(grad), {}, &residual);
  if (psi < d->best) {
    d->best = psi;
    d->best_residual = residual;
    d->best_x = x;
  }
  return psi;
}

// L-BFGS over the axes; returns the (ridged) psi of the best point, leaves `axes` there,
// unit length, and its ||t~ - t||^2 without the ridge in `squared_residual`.
double varpro_bfgs(int order, std::span<const double> t, const std::vector<bool>& mask,
                   std::vector<Eigen::Vector3d>& axes, int max_evaluations, double ftol_rel,
                   double& squared_residual) {
  for (Eigen::Vector3d& s : axes) s = unit_or_z(s);
  VarProData data{order, t, &mask, axes, std::numeric_limits<double>::infinity(),
                  std::numeric_limits<double>::infinity(), {}};
  std::vector<double> x(3 * axes.size());
  for (std::size_t k = 0; k < axes.size(); ++k)
    for (int c = 0; c < 3; ++c) x[3 * k + c] = axes[k][c];
  run_lbfgs(varpro_bfgs_objective, &data, x, ftol_rel, max_evaluations);
  if (data.best_x.empty()) return zh_varpro_objective(order, t, mask, axes, {}, {}, &squared_residual);
  for (std::size_t k = 0; k < axes.size(); ++k) {
    axes[k] = unit_or_z(Eigen::Vector3d(data.best_x[3 * k], data.best_x[3 * k + 1], data.best_x[3 * k + 2]));
  }
  squared_residual = data.best_residual;
  return data.best;
}

// The scan set's SH values, computed once per (order, count) and shared by every vector
// and thread: a scan is then a dot product per axis and band. `neighbours` lists, per
// axis, the axes within kNeighbourSpacings mean spacings (s and -s count as one point,
// so axes near the equator see those across it), which is what makes a grid local
// maximum of the single-lobe energy.
struct AxisScan {
  std::vector<Eigen::Vector3d> axes;
  std::vector<double> y;  // y[a * order^2 + i]
  std::vector<int> first_neighbour, neighbours;  // axis a: neighbours[first_neighbour[a] .. first_neighbour[a + 1])
};

constexpr double kNeighbourSpacings = 2.2;

const AxisScan& axis_scan(int order, int count) {
  static std::mutex mutex;
  static std::map<std::pair<int, int>, std::unique_ptr<const AxisScan>> cache;
  const std::lock_guard<std::mutex> lock(mutex);
  std::unique_ptr<const AxisScan>& entry = cache[{order, count}];
  if (!entry) {
    auto scan = std::make_unique<AxisScan>();
    scan->axes = hemisphere_axes(count);
    const int n2 = sh_count(order);
    scan->y.resize(scan->axes.size() * n2);
    for (std::size_t a = 0; a < scan->axes.size(); ++a)
      eval_sh<double>(order, scan->axes[a], std::span<double>(scan->y.data() + a * n2, n2));
    // The set's z falls by 1/count per index, and |p - q| >= |z_p - z_q|, so the axes
    // within chord r of axis a lie within r count indices of a; those within r of -a
    // (|p + q| >= z_p + z_q) are among the last ones, near the equator.
    const double r = kNeighbourSpacings * std::sqrt(2.0 * std::numbers::pi / count);
    const int window = static_cast<int>(std::ceil(r * count)) + 1;
    const std::vector<Eigen::Vector3d>& p = scan->axes;
    for (int a = 0; a < count; ++a) {
      scan->first_neighbour.push_back(static_cast<int>(scan->neighbours.size()));
      for (int b = std::max(0, a - window); b < std::min(count, a + window + 1); ++b)
        if (b != a && (p[a] - p[b]).norm() < r) scan->neighbours.push_back(b);
      for (int b = count - 1; b >= 0 && p[a].z() + p[b].z() < r; --b)
        if (b != a && (p[a] + p[b]).norm() < r && (p[a] - p[b]).norm() >= r) scan->neighbours.push_back(b);
    }
    scan->first_neighbour.push_back(static_cast<int>(scan->neighbours.size()));
    entry = std::move(scan);
  }
  return *entry;
}

// The grid local maxima of the energy a single lobe captures with its Eq. 18
// coefficients, sum_l (y_l(s) . t_l)^2 / sum_m y_lm(s)^2 (psi(s) is ||t||^2 minus it),
// as (-energy, axis index), the best `keep` first (keep <= 0: all sorted). Ties between
// neighbours go to the lower index.
void grid_peaks(int order, std::span<const double> t, const std::vector<bool>& mask, const AxisScan& scan, int keep,
                std::vector<std::pair<double, int>>& peaks, std::vector<double>& energy) {
  const int n2 = sh_count(order), count = static_cast<int>(scan.axes.size());
  energy.resize(count);
  for (int a = 0; a < count; ++a) {
    const double* y = scan.y.data() + static_cast<std::size_t>(a) * n2;
    double captured = 0;
    for (int l = 0; l < order; ++l) {
      if (!mask.empty() && !mask[l]) continue;
      double dot = 0;
      for (int i = l * l; i < (l + 1) * (l + 1); ++i) dot += y[i] * t[i];
      captured += dot * dot * (4.0 * std::numbers::pi / (2 * l + 1));
    }
    energy[a] = captured;
  }
  peaks.clear();
  for (int a = 0; a < count; ++a) {
    bool peak = true;
    for (int j = scan.first_neighbour[a]; j < scan.first_neighbour[a + 1] && peak; ++j) {
      const int b = scan.neighbours[j];
      peak = energy[b] < energy[a] || (energy[b] == energy[a] && b > a);
    }
    if (peak) peaks.emplace_back(-energy[a], a);
  }
  const int sorted = keep <= 0 ? static_cast<int>(peaks.size()) : std::min<int>(keep, peaks.size());
  std::partial_sort(peaks.begin(), peaks.begin() + sorted, peaks.end());
  peaks.resize(sorted);
}

void grid_peaks(int order, std::span<const double> t, const std::vector<bool>& mask, const AxisScan& scan, int keep,
                std::vector<std::pair<double, int>>& peaks) {
  thread_local std::vector<double> energy;
  grid_peaks(order, t, mask, scan, keep, peaks, energy);
}

// The axis whose single lobe (Eq. 18) best fits `t`, among the scan set and the optimal
// linear axis: the one that captures the most energy, sum over bands of
// (y_l(s) . t_l)^2 / sum_m y_lm(s)^2.
Eigen::Vector3d best_scanned_axis(int order, std::span<const double> t, const std::vector<bool>& mask,
                                  const AxisScan& scan) {
  double coeffs[kMaxOrder];
  Eigen::Vector3d best = optimal_linear_axis(t);
  const double linear_psi = single_lobe_closed_form(order, t, best, std::span<double>(coeffs, order), mask);
  double best_captured = squared_norm(t.first(sh_count(order))) - linear_psi;
  const int n2 = sh_count(order);
  for (std::size_t a = 0; a < scan.axes.size(); ++a) {
    const double* y = scan.y.data() + a * n2;
    double captured = 0;
    for (int l = 0; l < order; ++l) {
      if (!mask[l]) continue;
      double dot = 0;
      for (int i = l * l; i < (l + 1) * (l + 1); ++i) dot += y[i] * t[i];
      captured += dot * dot * (4.0 * std::numbers::pi / (2 * l + 1));
    }
    if (captured > best_captured) {
      best_captured = captured;
      best = scan.axes[a];
    }
  }
  return best;
}

// t minus the lobes along `axes` with their variable-projection coefficients.
void residual_after(int order, std::span<const double> t, const std::vector<bool>& mask,
                    const std::vector<Eigen::Vector3d>& axes, std::span<double> residual) {
  const int n2 = sh_count(order);
  thread_local std::vector<double> coeffs, y;
  coeffs.resize(axes.size() * order);
  y.resize(n2);
  zh_varpro_objective(order, t, mask, axes, {}, coeffs);
  std::copy(t.begin(), t.begin() + n2, residual.begin());
  for (std::size_t k = 0; k < axes.size(); ++k) {
    eval_sh<double>(order, axes[k], y);
    for (int l = 0; l < order; ++l)
      for (int i = l * l; i < (l + 1) * (l + 1); ++i) residual[i] -= coeffs[k * order + l] * y[i];
  }
}

// Grows `axes` greedily to `lobes` axes: each new axis is the scan axis whose single
// lobe best fits what the axes so far leave, then all axes are polished together (at
// most stage_evaluations at kVarProStageFtolRel; the last stage at most last_evaluations
// at last_ftol_rel). Returns the last stage's psi and its residual.
double grow_greedy(int order, std::span<const double> t, const std::vector<bool>& mask, const AxisScan& scan,
                   int lobes, std::vector<Eigen::Vector3d>& axes, int stage_evaluations, int last_evaluations,
                   double last_ftol_rel, double& squared_residual) {
  thread_local std::vector<double> r;
  r.assign(t.begin(), t.end());
  if (axes.empty()) axes.push_back(best_scanned_axis(order, r, mask, scan));
  while (true) {
    const bool last = static_cast<int>(axes.size()) >= lobes;
    const double psi = varpro_bfgs(order, t, mask, axes, last ? last_evaluations : stage_evaluations,
                                   last ? last_ftol_rel : kVarProStageFtolRel, squared_residual);
    if (last) return psi;
    residual_after(order, t, mask, axes, r);
    axes.push_back(best_scanned_axis(order, r, mask, scan));
  }
}

// The direction, tangent at the unit axis `a`, along which the band-2 part of t falls off
// slowest from a: band 2 of t is the quadratic form w^T M w on the sphere (M symmetric
// and traceless, read from its values at the 3 axes and the 3 diagonals between them),
// and the direction is the eigenvector of M restricted to the tangent plane with the
// larger eigenvalue: the long axis of the lobe t has around a.
Eigen::Vector3d elongation_direction(std::span<const double> t, const Eigen::Vector3d& a) {
  const auto band2 = [&](const Eigen::Vector3d& w) {
    double y[9];
    eval_sh<double>(3, w.normalized(), std::span<double>(y, 9));
    double v = 0;
    for (int m = -2; m <= 2; ++m) v += y[sh_index(2, m)] * t[sh_index(2, m)];
    return v;
  };
  Eigen::Matrix3d form;
  for (int i = 0; i < 3; ++i) form(i, i) = band2(Eigen::Vector3d::Unit(i));
  for (int i = 0; i < 3; ++i)
    for (int j = i + 1; j < 3; ++j)
      form(i, j) = form(j, i) =
          band2(Eigen::Vector3d::Unit(i) + Eigen::Vector3d::Unit(j)) - (form(i, i) + form(j, j)) / 2;
  const Eigen::Vector3d u =
      (std::abs(a.z()) < 0.9 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX()).cross(a).normalized();
  const Eigen::Vector3d v = a.cross(u);
  Eigen::Matrix2d tangent;
  tangent << u.dot(form * u), u.dot(form * v), v.dot(form * u), v.dot(form * v);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(tangent);
  const Eigen::Vector2d c = eigen.eigenvectors().col(1);  // eigenvalues ascending
  return (c[0] * u + c[1] * v).normalized();
}

// The last lobe a greedy growth adds is the single best lobe for what the others leave,
// judged before they move; once all are polished together another grid maximum of that
// remainder often ends lower (on transfer vectors the last lobe often mends the shadow's
// edge near the horizon, where several maxima compete). So the better start's last lobe
// is re-seated at the next `reseats` grid maxima of what the other lobes leave (each at
// least kReseatMinAngle from every lobe: a maximum beside a kept lobe only duplicates
// it), each polished briefly, and the lowest psi is kept. Deterministic, like the starts
// it follows.
void reseat_last_lobe(int order, std::span<const double> t, const std::vector<bool>& mask, const AxisScan& scan,
                      int reseats, std::vector<Eigen::Vector3d>& axes, double& best_psi, double& best_residual) {
  const std::vector<Eigen::Vector3d> others(axes.begin(), axes.end() - 1);
  const Eigen::Vector3d last = axes.back();
  thread_local std::vector<double> left;
  left.resize(sh_count(order));
  residual_after(order, t, mask, others, left);
  thread_local std::vector<std::pair<double, int>> peaks;
  grid_peaks(order, left, mask, scan, reseats + static_cast<int>(axes.size()), peaks);
  const double near = std::cos(kReseatMinAngle);
  int tried = 0;
  for (const auto& peak : peaks) {
    const Eigen::Vector3d& candidate = scan.axes[peak.second];
    // s and -s are one lobe.
    bool taken = std::abs(candidate.dot(last)) > near;
    for (const Eigen::Vector3d& other : others) taken = taken || std::abs(candidate.dot(other)) > near;
    if (taken) continue;
    if (tried++ == reseats) break;
    std::vector<Eigen::Vector3d> trial = others;
    trial.push_back(candidate);
    double residual = 0;
    const double psi = varpro_bfgs(order, t, mask, trial, kReseatEvaluations, kSplitLastFtolRel, residual);
    if (psi < best_psi) {
      best_psi = psi;
      best_residual = residual;
      axes = trial;
    }
  }
}

// Greedy axes (and, for 3 <= lobes < order, the split start), then random axis sets, each
// run of varpro_bfgs stopped at a loose tolerance (where starts are told apart); the best
// is then polished to the tight one.
//
// The split start: the greedy start puts its first lobe on the best single-lobe axis a
// and fits what is left with the others, which on transfer vectors (one broad, shadowed
// lobe) often ends in a local minimum far above the best known; the best known fits
// there mostly shape that lobe with two lobes either side of a instead. So a second start
// begins from the pair a +- kSplitAngle d, d the lobe's long axis
// (elongation_direction), and grows greedily from there, where the greedy start's residual
// is above options.split_above x ||t||. Both are deterministic and run at every effort;
// where the better of them is still above that, its last lobe is re-seated
// (reseat_last_lobe).
std::vector<Eigen::Vector3d> varpro_search(int order, std::span<const double> t, const std::vector<bool>& mask,
                                           const ZhFitOptions& o, std::uint64_t stream, double good) {
  const AxisScan& scan = axis_scan(order, o.axis_samples);
  // psi (with the ridge) ranks the starts; the residual without it is what `good`, a
  // fraction of ||t||, is compared with (the ridge alone would keep an exact fit above
  // kExactFitResidual).
  double best_psi = std::numeric_limits<double>::infinity(), best_residual = best_psi, residual = 0;
  std::vector<Eigen::Vector3d> axes;
  const bool split = o.lobes >= 3 && o.lobes < order && mask[2];
  if (!split) {
    // The axes of the stages before the last only seed the next scan: a rougher polish
    // serves: the last stage and the starts do the real search.
    best_psi = grow_greedy(order, t, mask, scan, o.lobes, axes, kVarProStageEvaluations, o.max_evaluations,
                           kVarProStartFtolRel, best_residual);
  } else {
    // The first stage, shared: the single-lobe axis a.
    axes.push_back(best_scanned_axis(order, t, mask, scan));
    varpro_bfgs(order, t, mask, axes, kSplitStageEvaluations, kVarProStageFtolRel, residual);
    const Eigen::Vector3d a = axes[0];
    best_psi = grow_greedy(order, t, mask, scan, o.lobes, axes, kSplitStageEvaluations, kSplitLastEvaluations,
                           kSplitLastFtolRel, best_residual);
    // A greedy start already within split_above of ||t|| (0.2 % by default, half a step
    // of an 8-bit display) keeps it: a better fit would not show.
    const double norm2 = squared_norm(t.first(sh_count(order)));
    const double split_good = o.split_above * o.split_above * norm2;
    if (best_residual > split_good) {
      const Eigen::Vector3d d = elongation_direction(t, a);
      std::vector<Eigen::Vector3d> pair{(a + kSplitAngle * d).normalized(), (a - kSplitAngle * d).normalized()};
      const double psi = grow_greedy(order, t, mask, scan, o.lobes, pair, kSplitStageEvaluations,
                                     kSplitLastEvaluations, kSplitLastFtolRel, residual);
      if (psi < best_psi) {
        best_psi = psi;
        best_residual = residual;
        axes = pair;
      }
    }
    if (best_residual > split_good) {
      const int reseats = best_residual > kThirdReseatAbove * kThirdReseatAbove * norm2    ? kMaxReseats
                          : best_residual > kSecondReseatAbove * kSecondReseatAbove * norm2 ? 2
                                                                                             : 1;
      reseat_last_lobe(order, t, mask, scan, reseats, axes, best_psi, best_residual);
    }
    // The low-order start (where the better fit so far is still above kLowOrderStartAbove
    // of ||t||): grown greedily with the highest band left out, then polished with it.
    if (best_residual > kLowOrderStartAbove * kLowOrderStartAbove * norm2) {
      std::vector<bool> low = mask;
      low[order - 1] = false;
      std::vector<Eigen::Vector3d> c;
      grow_greedy(order, t, low, scan, o.lobes, c, kSplitStageEvaluations, kSplitLastEvaluations, kSplitLastFtolRel,
                  residual);
      const double psi = varpro_bfgs(order, t, mask, c, kLowOrderPolishEvaluations, kSplitLastFtolRel, residual);
      if (psi < best_psi) {
        best_psi = psi;
        best_residual = residual;
        axes = c;
      }
    }
  }
  std::vector<Eigen::Vector3d> best = axes;

  // Multi-start (Sec. 4.1, "additional searching"): random axis sets.
  Rng rng{splitmix64(o.seed ^ splitmix64(stream ^ 0x5A17C0DEull))};
  for (int s = 0; s < o.starts && best_residual > good; ++s) {
    for (Eigen::Vector3d& a : axes) a = rng.unit_vector();
    const double psi = varpro_bfgs(order, t, mask, axes, o.max_evaluations, kVarProStartFtolRel, residual);
    if (psi < best_psi) {
      best_psi = psi;
      best_residual = residual;
      best = axes;
    }
  }
  if (split)
    varpro_bfgs(order, t, mask, best, o.split_polish_evaluations, o.split_polish_ftol_rel, residual);
  else
    varpro_bfgs(order, t, mask, best, o.max_evaluations,
                o.lobes >= order ? std::min(kVarProExactFtolRel, o.polish_ftol_rel) : o.polish_ftol_rel, residual);
  return best;
}

void canonicalize(std::vector<ZhLobe>& lobes) {
  for (ZhLobe& lobe : lobes) {
    const Eigen::Vector3d& s = lobe.axis;
    const bool flip = s.z() < 0 || (s.z() == 0 && (s.y() < 0 || (s.y() == 0 && s.x() < 0)));
    if (!flip) continue;
    // y_l^m(-s) = (-1)^l y_l^m(s): the lobe along -s with odd bands negated is the same.
    lobe.axis = -s;
    for (std::size_t l = 1; l < lobe.coeffs.size(); l += 2) lobe.coeffs[l] = -lobe.coeffs[l];
  }
}

}  // namespace

void apply_effort(ZhFitOptions& o, int effort) {
  if (effort < kMinEffort || effort > kMaxEffort)
    throw InputError("effort must be in " + std::to_string(kMinEffort) + ".." + std::to_string(kMaxEffort) +
                     ", got " + std::to_string(effort));
  struct Level {
    int starts_per_lobe_squared;
    double restart_above;
  };
  static constexpr Level kLevels[] = {{0, 0.05}, {5, 0.05}, {12, 0.0}, {40, 0.0}};
  o.starts = kLevels[effort - kMinEffort].starts_per_lobe_squared * o.lobes * o.lobes;
  o.restart_above = kLevels[effort - kMinEffort].restart_above;
}

double single_lobe_closed_form(int order, std::span<const double> t, const Eigen::Vector3d& axis,
                               std::span<double> coeffs, const std::vector<bool>& mask) {
  double y[kMaxOrder * kMaxOrder];
  eval_sh<double>(order, axis, std::span<double>(y, sh_count(order)));
  double psi = squared_norm(t.first(sh_count(order)));
  for (int l = 0; l < order; ++l) {
    if (!mask.empty() && !mask[l]) {
      coeffs[l] = 0.0;
      continue;
    }
    double dot = 0;
    for (int m = -l; m <= l; ++m) dot += y[sh_index(l, m)] * t[sh_index(l, m)];
    const double inv_sum_sq = 4.0 * std::numbers::pi / (2 * l + 1);  // 1 / sum_m y_lm^2
    coeffs[l] = dot * inv_sum_sq;
    // ||t_l - g y_l||^2 = ||t_l||^2 - dot^2 / sum_m y_lm^2 at the optimum.
    psi -= dot * dot * inv_sum_sq;
  }
  return std::max(0.0, psi);
}

int single_lobe_axes_for(int order) {
  const double degrees = (order - 1) / 5.0;  // the energy's degree 2(n - 1) over order 6's 10
  return std::max(kSingleLobeAxes, static_cast<int>(std::lround(kSingleLobeAxes * degrees * degrees)));
}

double best_single_lobe(int order, std::span<const double> t, const std::vector<bool>& mask, int axis_count,
                        int maxima, Eigen::Vector3d& axis, std::span<double> coeffs) {
  const AxisScan& scan = axis_scan(order, axis_count > 0 ? axis_count : single_lobe_axes_for(order));
  const int n2 = sh_count(order);
  thread_local std::vector<std::pair<double, int>> peaks, highest;
  thread_local std::vector<double> energy;
  grid_peaks(order, t, mask, scan, maxima, peaks, energy);
  if (maxima > 0) {
    // Two maxima closer than about three grid spacings, with energies a few 1e-5 apart,
    // can share one grid maximum (the neighbourhood that defines one spans 2.2 spacings):
    // so the highest grid axes are refined too, whether or not they are maxima.
    highest.clear();
    for (int a = 0; a < static_cast<int>(energy.size()); ++a) highest.emplace_back(-energy[a], a);
    const int top = std::min<int>(kSingleLobeHighestAxes, highest.size());
    std::partial_sort(highest.begin(), highest.begin() + top, highest.end());
    for (int k = 0; k < top; ++k)
      if (std::none_of(peaks.begin(), peaks.end(), [&](const auto& p) { return p.second == highest[k].second; }))
        peaks.push_back(highest[k]);
  }
  const int refine = static_cast<int>(peaks.size());
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> c(order);
  std::vector<Eigen::Vector3d> start(1);
  for (int k = 0; k < refine; ++k) {
    start[0] = scan.axes[peaks[k].second];
    double squared_residual = 0;
    varpro_bfgs(order, t, mask, start, kSingleLobeEvaluations, kVarProExactFtolRel, squared_residual);
    // The closed form at the refined axis, without the ridge the search carries.
    const double psi = single_lobe_closed_form(order, t, start[0], c, mask);
    if (psi < best) {
      best = psi;
      axis = start[0];
      std::copy(c.begin(), c.end(), coeffs.begin());
    }
  }
  if (!(best < std::numeric_limits<double>::infinity())) {
    // Every refinement non-finite (inputs near the end of the double range): a zero lobe.
    axis = Eigen::Vector3d::UnitZ();
    std::fill(coeffs.begin(), coeffs.begin() + order, 0.0);
    best = squared_norm(t.first(n2));
  }
  return best;
}

Eigen::Vector3d optimal_linear_axis(std::span<const double> t) {
  if (t.size() < 4) return Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d a(-t[sh_index(1, 1)], -t[sh_index(1, -1)], t[sh_index(1, 0)]);
  const double len = a.norm();
  return len > 0 ? Eigen::Vector3d(a / len) : Eigen::Vector3d::UnitZ();
}

std::vector<Eigen::Vector3d> hemisphere_axes(int count) {
  constexpr double kInvGolden = 0.61803398874989484820;
  std::vector<Eigen::Vector3d> axes;
  axes.reserve(count);
  for (int i = 0; i < count; ++i) {
    const double z = 1.0 - (i + 0.5) / count;  // equal-area bands of the hemisphere
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    double turn = i * kInvGolden;
    turn -= std::floor(turn);
    const double phi = 2.0 * std::numbers::pi * turn;
    axes.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return axes;
}

void lobes_to_sh(int order, const std::vector<ZhLobe>& lobes, std::span<double> out) {
  std::fill(out.begin(), out.begin() + sh_count(order), 0.0);
  for (const ZhLobe& lobe : lobes) add_zh_lobe_to_sh(lobe.axis, lobe.coeffs, out);
}

double zh_objective(int order, std::span<const double> t, const std::vector<ZhLobe>& lobes,
                    std::span<double> grad) {
  const int n2 = sh_count(order);
  const std::size_t nl = lobes.size();
  // Scratch reused across calls: this is the inner loop of every BFGS run.
  thread_local std::vector<double> y, g, r, length;
  thread_local std::vector<Eigen::Vector3d> unit;
  y.resize(nl * n2);
  g.resize(grad.empty() ? 0 : nl * 3 * n2);
  r.resize(n2);
  unit.resize(nl);
  length.resize(nl);
  for (std::size_t k = 0; k < nl; ++k) {
    length[k] = lobes[k].axis.norm();
    unit[k] = lobes[k].axis / length[k];  // h(s) of Eq. 21
    if (grad.empty())
      eval_sh<double>(order, unit[k], std::span<double>(y.data() + k * n2, n2));
    else
      eval_sh_with_gradient<double>(order, unit[k], std::span<double>(y.data() + k * n2, n2),
                                    std::span<double>(g.data() + k * 3 * n2, 3 * n2));
  }
  // r = t~ - t (Eq. 11 and 17).
  for (int i = 0; i < n2; ++i) r[i] = -t[i];
  for (std::size_t k = 0; k < nl; ++k)
    for (int l = 0; l < order; ++l)
      for (int m = -l; m <= l; ++m) r[sh_index(l, m)] += lobes[k].coeffs[l] * y[k * n2 + sh_index(l, m)];
  const double psi = squared_norm(r);
  if (grad.empty()) return psi;
  const int per = 3 + order;
  for (std::size_t k = 0; k < nl; ++k) {
    double* out = grad.data() + k * per;
    Eigen::Vector3d ds = Eigen::Vector3d::Zero();
    for (int l = 0; l < order; ++l) {
      double dg = 0;
      for (int m = -l; m <= l; ++m) {
        const int i = sh_index(l, m);
        dg += y[k * n2 + i] * r[i];  // Eq. 19
        const double w = lobes[k].coeffs[l] * r[i];
        ds += w * Eigen::Vector3d(g[k * 3 * n2 + 3 * i], g[k * 3 * n2 + 3 * i + 1], g[k * 3 * n2 + 3 * i + 2]);
      }
      out[3 + l] = 2.0 * dg;
    }
    // Eq. 20 with Eq. 21: the surface gradient is tangent at h(s), and
    // J_h^T = (I - h h^T) / |s| maps a tangent vector v to v / |s|.
    ds *= 2.0 / length[k];
    for (int c = 0; c < 3; ++c) out[c] = ds[c];
  }
  return psi;
}

namespace {

// zh_varpro_objective for kOrder bands and kLobes axes known at compile time (0: read
// from the arguments), so that the small loops of the common cases unroll; the
// operations and their order are the same in every instance.
template <int kOrder, int kLobes>
double varpro_objective(int order_arg, std::span<const double> t, const std::vector<bool>& mask,
                        std::span<const Eigen::Vector3d> axes, std::span<double> grad, std::span<double> coeffs,
                        double* squared_residual) {
  const int order = kOrder > 0 ? kOrder : order_arg;
  const int n = kLobes > 0 ? kLobes : static_cast<int>(axes.size());
  const int n2 = order * order;
  // Scratch reused across calls: this is the inner loop of every start. The bands' N x N
  // systems are independent, so they are factored and solved side by side, band index
  // innermost (gram[(a * n + b) * order + l], g[a * order + l]): each band's operations
  // and their order are those of solving it alone, so the values are too, and the
  // divisions and square roots of the bands overlap instead of waiting on each other.
  thread_local std::vector<double> y, dy, gram, g, length, r, ridge, v;
  y.resize(static_cast<std::size_t>(n) * n2);
  r.resize(n2);
  dy.resize(grad.empty() ? 0 : static_cast<std::size_t>(n) * 3 * n2);
  gram.resize(static_cast<std::size_t>(n) * n * order);
  g.resize(static_cast<std::size_t>(n) * order);
  length.resize(n);
  ridge.resize(order);
  v.resize(order);
  for (int k = 0; k < n; ++k) {
    length[k] = axes[k].norm();
    const Eigen::Vector3d unit = axes[k] / length[k];  // h(s) of Eq. 21
    if (grad.empty())
      eval_sh<double>(order, unit, std::span<double>(y.data() + k * n2, n2));
    else
      eval_sh_with_gradient<double>(order, unit, std::span<double>(y.data() + k * n2, n2),
                                    std::span<double>(dy.data() + k * 3 * n2, 3 * n2));
  }
  if (!grad.empty()) std::fill(grad.begin(), grad.begin() + 3 * n, 0.0);
  // Normal equations of every band with the ridge (bands with mask[l] false too: solved
  // and ignored, which keeps the loops below uniform).
  for (int l = 0; l < order; ++l) {
    const int first = l * l, rows = 2 * l + 1;
    ridge[l] = kVarProRidge * rows / (4.0 * std::numbers::pi);
    for (int a = 0; a < n; ++a) {
      double rhs = 0;
      for (int i = first; i < first + rows; ++i) rhs += y[a * n2 + i] * t[i];
      g[a * order + l] = rhs;
      for (int b = 0; b <= a; ++b) {
        double dot = 0;
        for (int i = first; i < first + rows; ++i) dot += y[a * n2 + i] * y[b * n2 + i];
        gram[(a * n + b) * order + l] = dot;
      }
      gram[(a * n + a) * order + l] += ridge[l];
    }
  }
  // Cholesky in place (lower triangle), then the two triangular solves.
  double* const G = gram.data();
  double* const x = g.data();
  double* const w = v.data();
  const double* const lambda = ridge.data();
  for (int a = 0; a < n; ++a) {
    for (int b = 0; b < a; ++b) {
      for (int l = 0; l < order; ++l) w[l] = G[(a * n + b) * order + l];
      for (int c = 0; c < b; ++c)
        for (int l = 0; l < order; ++l) w[l] -= G[(a * n + c) * order + l] * G[(b * n + c) * order + l];
      for (int l = 0; l < order; ++l) G[(a * n + b) * order + l] = w[l] / G[(b * n + b) * order + l];
    }
    for (int l = 0; l < order; ++l) w[l] = G[(a * n + a) * order + l];
    for (int c = 0; c < a; ++c)
      for (int l = 0; l < order; ++l) w[l] -= G[(a * n + c) * order + l] * G[(a * n + c) * order + l];
    // The ridge keeps the pivot >= lambda_l in exact arithmetic; the floor only guards
    // rounding.
    for (int l = 0; l < order; ++l) G[(a * n + a) * order + l] = std::sqrt(std::max(w[l], lambda[l]));
  }
  for (int a = 0; a < n; ++a) {
    for (int l = 0; l < order; ++l) w[l] = x[a * order + l];
    for (int c = 0; c < a; ++c)
      for (int l = 0; l < order; ++l) w[l] -= G[(a * n + c) * order + l] * x[c * order + l];
    for (int l = 0; l < order; ++l) x[a * order + l] = w[l] / G[(a * n + a) * order + l];
  }
  for (int a = n - 1; a >= 0; --a) {
    for (int l = 0; l < order; ++l) w[l] = x[a * order + l];
    for (int c = a + 1; c < n; ++c)
      for (int l = 0; l < order; ++l) w[l] -= G[(c * n + a) * order + l] * x[c * order + l];
    for (int l = 0; l < order; ++l) x[a * order + l] = w[l] / G[(a * n + a) * order + l];
  }
  double psi = 0, ridge_sum = 0;
  for (int l = 0; l < order; ++l) {
    const int first = l * l, rows = 2 * l + 1;
    if (!mask.empty() && !mask[l]) {
      for (int i = first; i < first + rows; ++i) psi += t[i] * t[i];
      if (!coeffs.empty())
        for (int k = 0; k < n; ++k) coeffs[k * order + l] = 0.0;
      continue;
    }
    for (int k = 0; k < n; ++k) ridge_sum += ridge[l] * x[k * order + l] * x[k * order + l];
    if (!coeffs.empty())
      for (int k = 0; k < n; ++k) coeffs[k * order + l] = x[k * order + l];
    for (int i = first; i < first + rows; ++i) {
      double ri = -t[i];  // r = t~ - t (Eq. 11 and 17)
      for (int k = 0; k < n; ++k) ri += x[k * order + l] * y[k * n2 + i];
      r[i] = ri;
      psi += ri * ri;
    }
    if (grad.empty()) continue;
    // Eq. 20 at the solved coefficients: g*_kl sum_m r_lm grad y_l^m(s_k), summed in
    // locals (the output span could alias the scratch, which would keep every partial
    // sum in memory).
    for (int k = 0; k < n; ++k) {
      const double* d = dy.data() + k * 3 * n2;
      double gx = 0, gy = 0, gz = 0;
      for (int i = first; i < first + rows; ++i) {
        gx += r[i] * d[3 * i];
        gy += r[i] * d[3 * i + 1];
        gz += r[i] * d[3 * i + 2];
      }
      grad[3 * k] += x[k * order + l] * gx;
      grad[3 * k + 1] += x[k * order + l] * gy;
      grad[3 * k + 2] += x[k * order + l] * gz;
    }
  }
  // Eq. 21: J_h^T maps a tangent vector v to v / |s|.
  if (!grad.empty())
    for (int k = 0; k < n; ++k)
      for (int c = 0; c < 3; ++c) grad[3 * k + c] *= 2.0 / length[k];
  if (squared_residual) *squared_residual = psi;
  return psi + ridge_sum;
}

}  // namespace

double zh_varpro_objective(int order, std::span<const double> t, const std::vector<bool>& mask,
                           std::span<const Eigen::Vector3d> axes, std::span<double> grad,
                           std::span<double> coeffs, double* squared_residual) {
  // The default order with the lobe counts a default fit and its greedy stages use.
  if (order == 6) {
    switch (axes.size()) {
      case 1: return varpro_objective<6, 1>(order, t, mask, axes, grad, coeffs, squared_residual);
      case 2: return varpro_objective<6, 2>(order, t, mask, axes, grad, coeffs, squared_residual);
      case 3: return varpro_objective<6, 3>(order, t, mask, axes, grad, coeffs, squared_residual);
      case 4: return varpro_objective<6, 4>(order, t, mask, axes, grad, coeffs, squared_residual);
      default: break;
    }
  }
  return zh_varpro_objective_any_size(order, t, mask, axes, grad, coeffs, squared_residual);
}

double zh_varpro_objective_any_size(int order, std::span<const double> t, const std::vector<bool>& mask,
                                    std::span<const Eigen::Vector3d> axes, std::span<double> grad,
                                    std::span<double> coeffs, double* squared_residual) {
  return varpro_objective<0, 0>(order, t, mask, axes, grad, coeffs, squared_residual);
}

ZhFit fit_zh(std::span<const double> t_in, const ZhFitOptions& o, std::uint64_t stream) {
  check_options(o);
  const int order = o.order, n2 = sh_count(order);
  if (static_cast<int>(t_in.size()) != n2)
    throw InputError("fit_zh: vector has " + std::to_string(t_in.size()) + " values, order " +
                                std::to_string(order) + " needs " + std::to_string(n2));
  ZhFit fit;
  fit.norm = scaled_norm(t_in);
  if (!std::isfinite(fit.norm)) throw InputError("fit_zh: the vector's norm is beyond double's range");
  const std::vector<bool> mask = free_bands(o);
  // Target for the lobes: t without the directly stored bands.
  std::vector<double> t(t_in.begin(), t_in.end());
  for (int l = 0; l < order; ++l)
    if (!mask[l])
      for (int m = -l; m <= l; ++m) {
        fit.direct.push_back(t_in[sh_index(l, m)]);
        t[sh_index(l, m)] = 0.0;
      }
  // L-BFGS's first steps and the absolute tolerances see the size of psi, so the search
  // runs on the lobes' target at unit norm and its coefficients and residual are scaled
  // back: c t is fitted as c times t's fit (to rounding), whatever c (at 1e3 or 1e-3 the
  // raw vector's fit used to land in another local minimum, at 1e-20 to stop before its
  // first step).
  const double target_norm = scaled_norm(t);
  const double scale = target_norm > 0 ? target_norm : 1.0;
  for (double& x : t) x /= scale;
  // With at least as many lobes as bands an exact fit exists ([4] Fig. 2: six
  // lobes represent an order-6 vector), so "good enough" means the BFGS tolerance, not
  // the paper's few-percent level: keep restarting until the fit is exact, and no longer
  // (further starts could only move rounding).
  const double restart = o.lobes >= order ? kExactFitResidual : o.restart_above;
  // psi at the threshold, which is relative to the whole vector (direct bands included).
  const double threshold = target_norm > 0 ? restart * fit.norm / scale : 0.0;
  const double good = threshold * threshold;
  std::vector<ZhLobe> best;
  ZhFitOptions resolved = o;
  if (resolved.starts == kStartsByEffort) {
    apply_effort(resolved, kDefaultEffort);
    resolved.restart_above = o.restart_above;
  }
  if (o.lobes == 1) {
    // Exact at every effort: random starts could not improve on it.
    best.resize(1);
    best[0].coeffs.assign(order, 0.0);
    best_single_lobe(order, t, mask, o.single_lobe_axes, o.single_lobe_maxima, best[0].axis, best[0].coeffs);
  } else if (o.method == ZhFitMethod::joint) {
    best = joint_search(order, t, mask, resolved, stream, good);
  } else {
    const std::vector<Eigen::Vector3d> axes = varpro_search(order, t, mask, resolved, stream, good);
    best.resize(axes.size());
    for (std::size_t k = 0; k < axes.size(); ++k) {
      best[k].axis = axes[k];
      best[k].coeffs.assign(order, 0.0);
    }
    // The exact minimum-norm coefficients for the axes found (the search's own carry the
    // ridge).
    refit_coefficients(order, t, mask, best);
  }
  canonicalize(best);
  fit.residual = std::sqrt(zh_objective(order, t, best, {})) * scale;
  bool finite = std::isfinite(fit.residual);
  for (ZhLobe& lobe : best)
    for (double& g : lobe.coeffs) finite = finite && std::isfinite(g *= scale);
  // Lobes may cancel with coefficients tens of times ||t||: near double's largest values
  // they do not fit it.
  if (!finite) throw InputError("fit_zh: the fit's coefficients overflow double (the vector is too large)");
  fit.lobes = best;
  return fit;
}

ZhFitTable<double> fit_zh_all(std::span<const double> vectors, const ZhFitOptions& options, int threads,
                              const std::function<void(std::size_t, std::size_t)>& progress,
                              std::uint64_t first_stream) {
  check_options(options);
  const std::size_t n2 = sh_count(options.order);
  if (vectors.size() % n2 != 0) throw InputError("fit_zh_all: size is not a multiple of order^2");
  const std::size_t count = vectors.size() / n2, lobes = options.lobes, order = options.order;
  ZhFitTable<double> fits;
  fits.order = options.order;
  fits.lobes = options.lobes;
  fits.vertices = count;
  fits.direct_count = direct_count(options);
  fits.axes.resize(count * lobes);
  fits.coeffs.resize(count * lobes * order);
  fits.residual.resize(count);
  fits.norm.resize(count);
  fits.direct.resize(count * fits.direct_count);
  parallel_for(
      count, resolve_threads(threads),
      [&](std::size_t v) {
        const ZhFit f = fit_zh(vectors.subspan(v * n2, n2), options, first_stream + v);
        for (std::size_t k = 0; k < lobes; ++k) {
          fits.axes[v * lobes + k] = f.lobes[k].axis;
          std::copy_n(f.lobes[k].coeffs.begin(), order, fits.coeffs.begin() + (v * lobes + k) * order);
        }
        std::copy(f.direct.begin(), f.direct.end(), fits.direct.begin() + v * fits.direct_count);
        fits.residual[v] = f.residual;
        fits.norm[v] = f.norm;
      },
      progress);
  return fits;
}

int direct_count(const ZhFitOptions& options) {
  check_options(options);
  const std::vector<bool> mask = free_bands(options);
  int count = 0;
  for (int l = 0; l < options.order; ++l)
    if (!mask[l]) count += 2 * l + 1;
  return count;
}



const EnumNames<ZhFitMethod>& fit_method_names() {
  using enum ZhFitMethod;
  static const EnumNames<ZhFitMethod> names = {{"varpro", varpro}, {"joint", joint}};
  return names;
}

}  // namespace shtool::fit
