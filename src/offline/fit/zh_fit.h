// Fitting sums of zonal-harmonic lobes to SH vectors ([4] Sec. 4.1).
//
// Model ([4] Eq. 7-11, docs/conventions.md): a lobe with unit axis s and convolved
// coefficients g*_l contributes g*_l y_l^m(s) to SH coefficient (l, m). The objective is
// psi = ||t~ - t||^2 (Eq. 17), minimised with NLopt's LD_LBFGS (a packaged quasi-Newton
// method; the problem is smooth and small) in one of two ways:
// - variable projection (the default): for fixed axes the best coefficients solve one
//   small linear least-squares problem per band, so L-BFGS searches the axes alone (3N
//   variables instead of N (3 + n)) and every start lands on coefficients that are
//   optimal for its axes ([16] Golub and Pereyra 1973);
// - joint: axes and coefficients together with the gradients of Eq. 19-21, as [4]
//   prints it; kept as the reference the default is tested against.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "common/enum_names.h"
#include "shtool/zh_fit_table.h"

namespace shtool::fit {

struct ZhLobe {
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // unit vector
  std::vector<double> coeffs;                       // g*_l, l = 0..order-1
};

struct ZhFit {
  std::vector<ZhLobe> lobes;
  std::vector<double> direct;  // stored SH coefficients (DC, then linear) when direct storage is on
  double residual = 0.0;       // ||t~ - t||, L2 over all order^2 coefficients
  double norm = 0.0;           // ||t||
};

enum class ZhFitMethod { varpro, joint };
const EnumNames<ZhFitMethod>& fit_method_names();

inline constexpr int kStartsByEffort = -1;

// The single-lobe search's defaults (best_single_lobe): a lobe's energy is a polynomial
// of degree 2(n - 1) on the sphere (10 at order 6), whose distinct maxima lie tenths of a
// radian apart; at order 6, 1024 axes are 0.08 rad apart, and higher orders get as many
// more as keep the spacing times the degree (single_lobe_axes_for). The best
// kSingleLobeMaxima grid maxima and the kSingleLobeHighestAxes highest axes are refined.
// Checked against every grid maximum of 16 times as many axes at order 6, and against
// 4 times as many at orders 8 to 16 (ZhFit.SingleLobeSearchFindsTheOptimumOfADenserGrid).
inline constexpr int kSingleLobeAxes = 1024;
inline constexpr int kSingleLobeMaxima = 4;
inline constexpr int kSingleLobeHighestAxes = 8;
// The axes best_single_lobe scans at `order`: kSingleLobeAxes up to order 6, then
// kSingleLobeAxes ((order - 1) / 5)^2 (2007 at order 8, 9216 at order 16).
int single_lobe_axes_for(int order);

struct ZhFitOptions {
  int order = 6;
  int lobes = 4;
  ZhFitMethod method = ZhFitMethod::varpro;
  // Store DC (and the linear band when lobes >= 3) directly, fit lobes to the rest
  // ([4] Sec. 3.3).
  bool direct = false;
  // Random axis sets tried after the deterministic starts (the greedy start, and for the
  // varpro method with 3 <= lobes < order the split and low-order starts as well; the
  // multi-start of Sec. 4.1); the effort/quality knob. kStartsByEffort: the default
  // level's count for `lobes` (apply_effort); 0: the deterministic starts only.
  int starts = kStartsByEffort;
  // Axes of the well-spread set scanned with the closed form of Eq. 18 for each greedy
  // stage of a multi-lobe fit (a spherical-Fibonacci set on the upper hemisphere: s and
  // -s give the same lobe).
  int axis_samples = 128;
  // Joint method, greedy stages: local refinements started from the best scanned axes
  // (plus the optimal linear lobe).
  int single_lobe_refinements = 2;
  // A single lobe (lobes == 1, both methods): best_single_lobe over this many axes (0:
  // single_lobe_axes_for(order)), refining this many grid maxima (<= 0: every one, the
  // slow reference).
  int single_lobe_axes = 0;
  int single_lobe_maxima = kSingleLobeMaxima;
  int max_evaluations = 300;  // per BFGS run
  // varpro: the relative change of psi at which the polish of the best start stops
  // (random starts themselves stop at 1e-3, the greedy and split starts of 3 <= lobes <
  // order at 1e-2). 1e-3 leaves psi within a few tenths of a percent of its local
  // minimum; with lobes >= order (an exact fit exists) 1e-10 is used whatever this says.
  double polish_ftol_rel = 1e-3;
  // varpro, 3 <= lobes < order: the polish stops at this relative change instead, after
  // at most split_polish_evaluations. The deterministic starts' fits of transfer vectors
  // often end in long, ill-conditioned valleys (near-coincident lobes with large
  // coefficients of opposite sign) where psi still falls slowly below 1e-3; a cap below
  // max_evaluations trades that for fit time (docs/fit-zh.md).
  double split_polish_ftol_rel = 1e-4;
  int split_polish_evaluations = 50;
  std::uint64_t seed = 1;
  // Multi-start runs only while the residual is above this fraction of ||t|| ("we apply
  // further computation when the fit error is high", Sec. 4.1): well-fitted vertices,
  // most of a mesh, stay cheap. 0: always run all starts.
  double restart_above = 0.05;
  // varpro, 3 <= lobes < order: the split start runs only where the greedy start's
  // residual is above this fraction of ||t|| (0.2 %: half a step of an 8-bit display;
  // about 60 % of the bunny's vertices, every vector of the fit fixture's `spot` set),
  // and the better start's last lobe is re-seated only where it is still above it.
  // 0: always.
  double split_above = 0.002;
};

// The --effort levels: each sets `starts` and `restart_above` for options.lobes (set
// lobes first). Local minima multiply with the lobe count, so the starts grow as N^2:
// 1: none (the deterministic starts only); 2, the default: 5 N^2 where the residual is above 5 %
// of ||t||; 3: 12 N^2 for every vector; 4: 40 N^2 for every vector. Measured quality and
// cost per level are in docs/fit-zh.md.
inline constexpr int kMinEffort = 1, kDefaultEffort = 2, kMaxEffort = 4;
void apply_effort(ZhFitOptions& options, int effort);

// Relative residual taken as "exact" when lobes >= order: BFGS stops at a relative
// change of 1e-12 in the squared residual, so fits that are exact in theory land near
// 1e-8..1e-7; 1e-6 separates them from the percent-level fits of fewer lobes.
inline constexpr double kExactFitResidual = 1e-6;

// Eq. 18: best coefficients for a single lobe with fixed unit axis s, using
// sum_m y_lm(s)^2 = (2l+1)/(4 pi). Writes `coeffs` (order values) and returns the
// squared residual ||t~ - t||^2. Bands with mask[l] false get coefficient 0 (empty
// mask: all bands free).
double single_lobe_closed_form(int order, std::span<const double> t, const Eigen::Vector3d& axis,
                               std::span<double> coeffs, const std::vector<bool>& mask = {});

// The globally best single lobe ([4] Eq. 18 leaves psi a function of the axis s alone,
// and psi(s) = psi(-s)): the closed form on `axis_count` spherical-Fibonacci axes of the
// upper hemisphere (<= 0: single_lobe_axes_for(order)), the grid's local maxima of
// captured energy ranked, and the best `maxima` of them and the kSingleLobeHighestAxes
// highest axes (maxima <= 0: every grid maximum, nothing else) refined by L-BFGS to a
// relative change of 1e-10 in psi. Writes the axis (unit) and its Eq. 18 coefficients
// (order values; bands with mask[l] false get 0) and returns the squared residual.
double best_single_lobe(int order, std::span<const double> t, const std::vector<bool>& mask, int axis_count,
                        int maxima, Eigen::Vector3d& axis, std::span<double> coeffs);

// Axis of symmetry of the linear band of t: normalise (-t_1^1, -t_1^-1, t_1^0)
// (Sec. 3.3, with y_1^-1 = -c y, y_1^0 = c z, y_1^1 = -c x). +z if that band is zero.
Eigen::Vector3d optimal_linear_axis(std::span<const double> t);

// `count` well-spread unit vectors with z >= 0 (spherical Fibonacci, upper hemisphere).
std::vector<Eigen::Vector3d> hemisphere_axes(int count);

// The SH vector of a sum of lobes: out[i] = sum over lobes of g*_l y_i(s).
void lobes_to_sh(int order, const std::vector<ZhLobe>& lobes, std::span<double> out);

// psi of Eq. 17 for lobes with (possibly non-unit) axes s_k evaluated at h(s_k) = s_k/|s_k|,
// and its gradient (Eq. 19-21) when grad is non-empty, packed per lobe as
// [ds_x, ds_y, ds_z, dg*_0 .. dg*_{order-1}].
double zh_objective(int order, std::span<const double> t, const std::vector<ZhLobe>& lobes,
                    std::span<double> grad);

// Variable projection ([16]): psi(S) = min over coefficients of ||t~ - t||^2 for the lobe
// axes S (possibly non-unit, evaluated at h(s_k) = s_k/|s_k|). Per band l the
// coefficients solve (Y_l^T Y_l + lambda_l I) g_l = Y_l^T t_l, Y_l the (2l+1) x N matrix
// of the axes' band-l values; the ridge lambda_l = kVarProRidge (2l+1)/(4 pi) keeps
// coincident axes (and band 0, whose columns are always equal) solvable and is included
// in the returned value so that the gradient is exact. The gradient in s_k is Eq. 20 at
// those coefficients: they are a minimiser, so their own change adds nothing (the
// envelope theorem). Writes the coefficients to coeffs[k * order + l] when non-empty and
// the gradient, packed [ds_x, ds_y, ds_z] per axis, when grad is non-empty. Bands with
// mask[l] false get coefficient 0 (empty mask: all free). `squared_residual`, when
// given, receives ||t~ - t||^2 alone (the value without the ridge term).
inline constexpr double kVarProRidge = 1e-10;
double zh_varpro_objective(int order, std::span<const double> t, const std::vector<bool>& mask,
                           std::span<const Eigen::Vector3d> axes, std::span<double> grad,
                           std::span<double> coeffs = {}, double* squared_residual = nullptr);
// The same objective with every size read at run time. zh_varpro_objective compiles the
// sizes a default fit uses (order 6, 1-4 axes) as constants with the same operations in
// the same order; this is the reference those instances are tested against bit for bit.
double zh_varpro_objective_any_size(int order, std::span<const double> t, const std::vector<bool>& mask,
                                    std::span<const Eigen::Vector3d> axes, std::span<double> grad,
                                    std::span<double> coeffs = {}, double* squared_residual = nullptr);

// Full fit of one vector (t.size() == order^2): single lobe = best_single_lobe (both
// methods, every effort); multi-lobe, varpro = the greedy start (and, for 3 <= lobes <
// order, the split start: the single-lobe axis split into a pair along the lobe's long
// axis, grown greedily, and the better start's last lobe re-seated at the next one to
// three grid maxima of what the others leave, more where the residual is higher, and
// where it is still high the low-order start: grown greedily on every band but the
// highest), then `starts` random axis sets (seeded by options.seed and `stream`), the best
// polished; multi-lobe, joint = greedy, coefficient refit with axes frozen, joint BFGS,
// then `starts` random axis sets each refit and BFGS-refined; the best is returned.
// Axes are returned unit length with z >= 0 (odd-band coefficients flipped with them).
ZhFit fit_zh(std::span<const double> t, const ZhFitOptions& options, std::uint64_t stream = 0);

// Fits vectors[v * order^2 ...] for every v on `threads` workers (fixed partition by
// index; stream = first_stream + v, so results depend on neither the thread count nor,
// when a shard passes the global index of its first vector, the shard count).
// The fits land in one flat set, the layout the runtime loads (shtool/zh_fit_table.h):
// a few contiguous arrays whatever the vertex count, no allocation kept per vertex.
// vertex_index is left empty. progress(done, total) is called from worker 0 only.
ZhFitTable<double> fit_zh_all(std::span<const double> vectors, const ZhFitOptions& options, int threads,
                              const std::function<void(std::size_t, std::size_t)>& progress = {},
                              std::uint64_t first_stream = 0);

// Coefficients a fit with these options stores directly per vector: 0, 1 (DC) or 4 (DC
// and the linear band).
int direct_count(const ZhFitOptions& options);

}  // namespace shtool::fit
