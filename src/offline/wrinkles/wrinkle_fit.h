// The global ZH fit of the wrinkle model ([4] Sec. 4.2): lobe axes and coefficients at
// the nodes of the (x, d) grid, bilinear in between, optimised together against the
// transfer at every (denser) sample, so that a lobe keeps its identity from node to
// node. DC and the linear band are stored directly and fitted by linear least squares
// with the same bilinear basis; the lobes fit bands 2..n-1.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "common/parallel_for.h"
#include "fit/zh_fit.h"
#include "wrinkles/wrinkle_model.h"

namespace shtool::wrinkles {

// Node values of the direct coefficients (DC, linear band): per coefficient, the least-
// squares solution of sum over samples (bilinear blend of node values - t)^2.
std::vector<double> fit_direct(const WrinkleGrid& grid, int order, std::span<const double> transfer);

// The start of the global fit ([4] Sec. 4.2): at each node, lobe 0 on the optimal linear
// axis a of the node's transfer (Sec. 3.3) and the other N - 1 on a cone of half-angle
// theta around it, at azimuths 2 pi i / (N - 1) from a reference direction, theta scanned
// per node (1..89 degrees, 1-degree steps) for the least residual in bands 2..n-1 with the
// coefficients solved for those axes (fit::zh_varpro_objective). The reference is the
// same at every node, so lobe i means the same thing everywhere: y (along the groove) or
// a x y (across it, in the xz plane), whichever leaves the smaller total residual over
// the nodes. Returns one fit per node (rows k * G + j), unit axes, bands 0 and 1 zero.
std::vector<fit::ZhFit> symmetric_start(const WrinkleGrid& grid, int order, int lobes, std::span<const double> transfer);

// Node lobes of a model from per-node fits (unit axes); direct left untouched.
void set_model_lobes(WrinkleModel& model, const std::vector<fit::ZhFit>& node_fits);

// The objective of the global fit: sum over samples of ||lobes(x, d) - t||^2 over bands
// 2..n-1 ([4] Eq. 17 summed over the samples, the lobe parameters bilinear in (x, d)),
// with its gradient (Eq. 19-21 at each sample by fit::zh_objective, then the bilinear
// weights carry it to the nodes). Parameters per node and lobe:
// [s_x, s_y, s_z, g*_2 .. g*_{n-1}]. Per-sample values and gradients are computed in
// parallel into their own slots and summed in sample order, so the value does not depend
// on the thread count.
class GlobalObjective {
 public:
  GlobalObjective(const WrinkleGrid& grid, int order, int lobes, std::span<const double> transfer, int threads);
  ~GlobalObjective();
  std::size_t parameter_count() const;
  double value(std::span<const double> params, std::span<double> grad);
  std::vector<double> pack(const WrinkleModel& model) const;
  void unpack(std::span<const double> params, WrinkleModel& model) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// L-BFGS (NLopt LD_LBFGS, the default) or nonlinear conjugate gradients
// (minimize_conjugate_gradient, [4]'s choice), for the measured comparison.
enum class WrinkleOptimizer { lbfgs, cg };

// Polak-Ribiere+ conjugate gradients with a line search to the strong Wolfe conditions
// (c1 = 1e-4, c2 = 0.1: nearly exact, as CG wants), restarting along -g when the
// direction does not descend. Stops at a relative decrease of the value below ftol_rel
// in one iteration, or after max_evaluations. x: start in, best point out. Returns the
// evaluations used.
int minimize_conjugate_gradient(GlobalObjective& objective, std::vector<double>& x, int max_evaluations,
                                double ftol_rel);

struct WrinkleFitOptions {
  int order = 6;
  int lobes = 3;
  std::uint64_t seed = 1;
  int threads = 0;
  int max_evaluations = 1000;  // of the global objective
  double ftol_rel = 1e-8;      // the optimiser stops at this relative change of the objective
  WrinkleOptimizer optimizer = WrinkleOptimizer::lbfgs;
};

// Normalised RMS, sqrt(sum residual^2 / sum |t|^2), over the samples.
struct FitErrors {
  double global = 0;           // the global fit
  double per_point = 0;        // independent fits at every sample
  double node_fits = 0;        // independent node fits, interpolated as they come
  double start = 0;            // symmetric_start, interpolated (the optimiser's start)
};

struct WrinkleFit {
  WrinkleModel model;
  FitErrors errors;
  std::vector<double> global_residual2;     // per sample
  std::vector<double> per_point_residual2;  // per sample
  std::vector<double> norm2;                // per sample, |t|^2
  int evaluations = 0;
};

// Squared residual of the model at every sample.
std::vector<double> model_residuals(const WrinkleModel& model, std::span<const double> transfer);

WrinkleFit fit_wrinkles(const WrinkleGrid& grid, std::span<const double> transfer, const WrinkleFitOptions& options);

}  // namespace shtool::wrinkles
