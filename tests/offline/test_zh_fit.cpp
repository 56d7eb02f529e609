// ZH lobe fitting ([4] Sec. 4.1) and the runtime ZH functions. References: the
// addition theorem, finite differences of the objective, vectors built from known lobes,
// and a brute-force closed-form (Eq. 18) scan over a dense axis set.
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "fit/mesh.h"
#include "fit/transfer.h"
#include "fit/zh_fit.h"
#include "shtool/sh.h"
#include "shtool/zh.h"
#include "test_util.h"

namespace {

using namespace shtool;
using namespace shtool::fit;
using test::Lcg;
using test::random_unit_vector;

ZhLobe random_lobe(Lcg& rng, int order) {
  ZhLobe lobe;
  lobe.axis = rng.unit();
  for (int l = 0; l < order; ++l) lobe.coeffs.push_back(2 * rng.uniform() - 1);
  return lobe;
}

// Best single lobe over a dense spherical-Fibonacci set of axes (both hemispheres,
// though s and -s are equivalent), each with its closed-form coefficients (Eq. 18).
double dense_single_lobe_residual(const std::vector<double>& t, int order, int count) {
  double best = 1e300;
  std::vector<double> c(order);
  for (const Eigen::Vector3d& s : hemisphere_axes(count))
    best = std::min(best, single_lobe_closed_form(order, t, s, c));
  return std::sqrt(best);
}

TEST(ZhRuntime, EvaluationMatchesSHExpansion) {
  // Addition theorem: the Legendre-series evaluation and the SH coefficients
  // g*_l y_l^m(s) reconstructed with the SH basis are two independent paths.
  Lcg rng{3};
  for (int trial = 0; trial < 20; ++trial) {
    const ZhLobe lobe = random_lobe(rng, 7);
    std::vector<double> sh(49, 0.0);
    add_zh_lobe_to_sh(lobe.axis, lobe.coeffs, sh);
    const Eigen::Vector3d w = rng.unit();
    const double direct = eval_zh_lobe(lobe.axis, lobe.coeffs, w);
    const double via_sh = reconstruct<double>(sh, w);
    // Sums of ~50 terms of size <= ~2: 1e-13 is a few hundred ulps.
    EXPECT_NEAR(direct, via_sh, 1e-13) << "trial " << trial;
    // Shading against "lighting" equal to a basis function picks out one coefficient.
    std::vector<double> light(49, 0.0);
    light[sh_index(3, -2)] = 1.0;
    EXPECT_NEAR(zh_lobe_dot_sh(lobe.axis, lobe.coeffs, light), sh[sh_index(3, -2)], 1e-15);
  }
}

TEST(ZhRuntime, RotatingTheAxisRotatesTheFunction) {
  Lcg rng{4};
  const ZhLobe lobe = random_lobe(rng, 5);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, rng.unit()).toRotationMatrix();
  const Eigen::Vector3d axis = rotate_zh_axis(r, lobe.axis);
  for (int k = 0; k < 10; ++k) {
    const Eigen::Vector3d w = rng.unit();
    // g(w) = f(R^-1 w) (the rotation convention of docs/conventions.md).
    EXPECT_NEAR(eval_zh_lobe(axis, lobe.coeffs, w), eval_zh_lobe(lobe.axis, lobe.coeffs, r.transpose() * w), 1e-13);
  }
}

// Every fitting test runs both methods: variable projection (the default) and the joint
// BFGS of [4] as printed (the reference).
class ZhFitMethods : public ::testing::TestWithParam<ZhFitMethod> {
 protected:
  // The options of this method for `lobes` lobes at `order`, the rest at their defaults.
  ZhFitOptions options(int order, int lobes) const {
    ZhFitOptions o;
    o.method = GetParam();
    o.order = order;
    o.lobes = lobes;
    return o;
  }
};
INSTANTIATE_TEST_SUITE_P(Methods, ZhFitMethods, ::testing::Values(ZhFitMethod::varpro, ZhFitMethod::joint),
                         [](const auto& info) { return info.param == ZhFitMethod::varpro ? "varpro" : "joint"; });

TEST(ZhFit, ObjectiveGradientMatchesFiniteDifferences) {
  Lcg rng{5};
  const int order = 6;
  const std::vector<double> t = random_unit_vector(rng, order);
  std::vector<ZhLobe> lobes = {random_lobe(rng, order), random_lobe(rng, order)};
  lobes[1].axis *= 1.3;  // Eq. 21: the gradient must account for the normalisation
  std::vector<double> grad(2 * (3 + order));
  zh_objective(order, t, lobes, grad);
  const double h = 1e-6;
  for (int k = 0; k < 2; ++k)
    for (int p = 0; p < 3 + order; ++p) {
      auto shifted = [&](double d) {
        std::vector<ZhLobe> x = lobes;
        if (p < 3) x[k].axis[p] += d;
        else x[k].coeffs[p - 3] += d;
        return zh_objective(order, t, x, {});
      };
      const double fd = (shifted(h) - shifted(-h)) / (2 * h);
      // Central differences: O(h^2) truncation (~1e-12 here) plus ~1e-16/h rounding.
      EXPECT_NEAR(grad[k * (3 + order) + p], fd, 1e-8) << "lobe " << k << " parameter " << p;
    }
}

TEST(ZhFit, ClosedFormRecoversASingleLobe) {
  Lcg rng{6};
  const int order = 6;
  const ZhLobe lobe = random_lobe(rng, order);
  std::vector<double> t(36);
  lobes_to_sh(order, {lobe}, t);
  std::vector<double> c(order);
  double norm2 = 0;
  for (double x : t) norm2 += x * x;
  // psi is ||t||^2 minus the captured energy: cancellation leaves ~eps ||t||^2.
  EXPECT_NEAR(single_lobe_closed_form(order, t, lobe.axis, c), 0.0, 1e-14 * norm2) << "||t||^2 " << norm2;
  for (int l = 0; l < order; ++l) EXPECT_NEAR(c[l], lobe.coeffs[l], 1e-14) << "band " << l;
  // Linear band alone: the optimal linear lobe axis is the lobe's axis (or its opposite).
  const Eigen::Vector3d a = optimal_linear_axis(t);
  EXPECT_NEAR(std::abs(a.dot(lobe.axis)), 1.0, 1e-14);
}

TEST_P(ZhFitMethods, KnownLobesAreRecovered) {
  Lcg rng{7};
  const int order = 6;
  ZhFitOptions o = options(order, 1);
  for (int n : {1, 2}) {
    std::vector<ZhLobe> truth;
    for (int k = 0; k < n; ++k) truth.push_back(random_lobe(rng, order));
    std::vector<double> t(36);
    lobes_to_sh(order, truth, t);
    o.lobes = n;
    const ZhFit fit = fit_zh(t, o);
    // Exact representation exists; BFGS stops at ftol 1e-12 relative in psi, i.e.
    // ~1e-6 relative in the residual, so 1e-5 still separates "found" from "missed"
    // (a wrong axis leaves residuals of order 0.1).
    EXPECT_LT(fit.residual, 1e-5 * fit.norm) << n << " lobes, residual " << fit.residual << " norm " << fit.norm;
    if (n == 1) EXPECT_NEAR(std::abs(fit.lobes[0].axis.dot(truth[0].axis)), 1.0, 1e-6);
  }
}

TEST_P(ZhFitMethods, AsManyLobesAsBandsIsExactAtDefaultEffort) {
  // N = 6 lobes represent any order-6 vector exactly; the default options must find
  // it ([4] Fig. 2 reports 0.00908; that is beatable by orders of magnitude), not stop at the
  // percent-level restart threshold meant for N < order.
  Lcg rng{11};
  ZhFitOptions o = options(6, 6);
  for (int trial = 0; trial < 3; ++trial) {
    const std::vector<double> t = random_unit_vector(rng, o.order);
    const ZhFit fit = fit_zh(t, o, trial);
    EXPECT_LT(fit.residual, kExactFitResidual * fit.norm) << "trial " << trial << " residual " << fit.residual;
  }
}

TEST_P(ZhFitMethods, NeverWorseThanBestDenseSingleLobe) {
  Lcg rng{8};
  const int order = 6;
  ZhFitOptions o = options(order, 1);
  o.starts = 2;
  for (int trial = 0; trial < 3; ++trial) {
    const std::vector<double> t = random_unit_vector(rng, order);
    const double dense = dense_single_lobe_residual(t, order, 20000);
    for (int n : {1, 2, 4}) {
      o.lobes = n;
      const ZhFit fit = fit_zh(t, o, trial);
      // A continuous optimum can only be below the best grid point; 1e-12 absorbs rounding.
      EXPECT_LE(fit.residual, dense + 1e-12) << "trial " << trial << " N " << n << " dense " << dense;
      // The reported residual is the true one.
      std::vector<double> approx(36);
      lobes_to_sh(order, fit.lobes, approx);
      double r = 0;
      for (int i = 0; i < 36; ++i) r += (approx[i] - t[i]) * (approx[i] - t[i]);
      EXPECT_NEAR(fit.residual, std::sqrt(r), 1e-14);
      for (const ZhLobe& lobe : fit.lobes) EXPECT_NEAR(lobe.axis.norm(), 1.0, 1e-15);
    }
  }
}

TEST_P(ZhFitMethods, DirectStorageKeepsDcAndLinear) {
  Lcg rng{9};
  const int order = 4;
  const std::vector<double> t = random_unit_vector(rng, order);
  ZhFitOptions o = options(order, 3);
  o.direct = true;
  o.starts = 0;
  const ZhFit fit = fit_zh(t, o);
  ASSERT_EQ(fit.direct.size(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(fit.direct[i], t[i]);
  for (const ZhLobe& lobe : fit.lobes) {
    EXPECT_EQ(lobe.coeffs[0], 0.0);
    EXPECT_EQ(lobe.coeffs[1], 0.0);
  }
  // Residual over the whole vector: direct part exact, lobes account for the rest.
  std::vector<double> approx(16);
  lobes_to_sh(order, fit.lobes, approx);
  double r = 0;
  for (int i = 4; i < 16; ++i) r += (approx[i] - t[i]) * (approx[i] - t[i]);
  EXPECT_NEAR(fit.residual, std::sqrt(r), 1e-14);
}

TEST_P(ZhFitMethods, ScalingTheVectorScalesTheFit) {
  // The fit of c t is c times the fit of t: the search's steps and tolerances do not see
  // the vector's size. Before it, t x 1e3 fitted at N = 4 with twice t's relative
  // residual, and t x 1e-20 stopped before its first step.
  Lcg rng{13};
  const int order = 6;
  const std::vector<double> t = random_unit_vector(rng, order);
  const ZhFitOptions o = options(order, 4);
  const ZhFit unit = fit_zh(t, o);
  std::vector<double> unit_sh(t.size()), sh(t.size());
  lobes_to_sh(order, unit.lobes, unit_sh);
  for (const double c : {1e-160, 1e-20, 1e-3, 3.0, 1e3, 1e90}) {
    std::vector<double> scaled = t;
    for (double& x : scaled) x *= c;
    const ZhFit fit = fit_zh(scaled, o);
    EXPECT_NEAR(fit.norm / c, unit.norm, 1e-14) << c;
    EXPECT_NEAR(fit.residual / (c * unit.residual), 1.0, 1e-9) << c;
    // The fitted function, not each lobe: the joint method's coefficients may differ
    // along directions psi does not see (a band with more lobes than coefficients), and
    // its stop at a relative change of 1e-12 in psi leaves the function within ~1e-7.
    lobes_to_sh(order, fit.lobes, sh);
    for (std::size_t i = 0; i < sh.size(); ++i) EXPECT_NEAR(sh[i] / c, unit_sh[i], 1e-6) << c << " " << i;
  }
}

TEST_P(ZhFitMethods, DirectStorageFitsTheLobesPartAtItsOwnScale) {
  // With --direct the lobes fit bands 2 and up alone; the search sees that part at unit
  // norm however small it is beside bands 0 and 1. Scaled by the whole vector's norm, a
  // part 1e-4 of it stopped at its start, 20 times the error of the part fitted alone.
  Lcg rng{14};
  const int order = 4;
  const std::vector<double> t = random_unit_vector(rng, order);
  ZhFitOptions o = options(order, 3);
  o.direct = true;
  for (const double c : {1e-4, 1e-8}) {
    std::vector<double> with_dc = t, part = t;
    for (std::size_t i = 0; i < t.size(); ++i) {
      with_dc[i] = i < 4 ? t[i] : t[i] * c;
      part[i] = i < 4 ? 0.0 : t[i] * c;
    }
    const ZhFit fit = fit_zh(with_dc, o), alone = fit_zh(part, o);
    // The same search up to rounding, which moves where a polish stops (and the joint
    // method's long descent): within 0.1 %.
    EXPECT_NEAR(fit.residual / alone.residual, 1.0, 1e-3) << c;
  }
}

TEST(ZhFit, VectorsBeyondDoublesRangeAreRefusedAndThoseNearItFitted) {
  ZhFitOptions o;
  // ||t|| = 6 x 1.7e308 is not a double: refused, not returned as inf and NaN.
  try {
    fit_zh(std::vector<double>(36, 1.7e308), o);
    ADD_FAILURE() << "a vector whose norm overflows was fitted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("beyond double's range"), std::string::npos) << e.what();
  }
  // 1e306 times a unit vector: the unit vector's fit, scaled.
  Lcg rng{15};
  const std::vector<double> t = random_unit_vector(rng, 6);
  std::vector<double> big = t;
  for (double& x : big) x *= 1e306;
  const ZhFit unit = fit_zh(t, o), fit = fit_zh(big, o);
  EXPECT_NEAR(fit.residual / (1e306 * unit.residual), 1.0, 1e-9);
  for (const ZhLobe& lobe : fit.lobes)
    for (const double g : lobe.coeffs) EXPECT_TRUE(std::isfinite(g));
}

TEST_P(ZhFitMethods, DeterministicAcrossThreadCounts) {
  Lcg rng{10};
  std::vector<double> vectors;
  for (int v = 0; v < 6; ++v) {
    const std::vector<double> t = random_unit_vector(rng, 4);
    vectors.insert(vectors.end(), t.begin(), t.end());
  }
  ZhFitOptions o = options(4, 2);
  o.starts = 1;
  o.restart_above = 0;
  const ZhFitTable<double> one = fit_zh_all(vectors, o, 1);
  const ZhFitTable<double> two = fit_zh_all(vectors, o, 2);
  ASSERT_EQ(one.vertices, 6u);
  EXPECT_EQ(one.axes, two.axes);
  EXPECT_EQ(one.coeffs, two.coeffs);
  EXPECT_EQ(one.residual, two.residual);
  EXPECT_EQ(one.norm, two.norm);
  // Each row is the fit of its vector alone, drawn from stream v.
  for (std::size_t v = 0; v < one.vertices; ++v) {
    const ZhFit alone = fit_zh(std::span<const double>(vectors).subspan(v * 16, 16), o, v);
    EXPECT_EQ(two.residual[v], alone.residual) << "vector " << v;
    EXPECT_EQ(two.norm[v], alone.norm);
    ASSERT_EQ(alone.lobes.size(), 2u);
    for (int k = 0; k < 2; ++k) {
      EXPECT_EQ(two.axes_of(v)[k], alone.lobes[k].axis);
      const std::span<const double> coeffs = two.coeffs_of(v).subspan(k * 4, 4);
      EXPECT_EQ(std::vector<double>(coeffs.begin(), coeffs.end()), alone.lobes[k].coeffs);
    }
  }
}

TEST(ZhFit, VarProGradientMatchesFiniteDifferences) {
  Lcg rng{12};
  const int order = 6;
  const std::vector<double> t = random_unit_vector(rng, order);
  for (const std::vector<bool>& mask : {std::vector<bool>{}, std::vector<bool>{false, false, true, true, true, true}}) {
    std::vector<Eigen::Vector3d> axes = {rng.unit(), 1.3 * rng.unit(), 0.7 * rng.unit()};
    std::vector<double> grad(9);
    zh_varpro_objective(order, t, mask, axes, grad);
    const double h = 1e-6;
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) {
        auto shifted = [&](double d) {
          std::vector<Eigen::Vector3d> x = axes;
          x[k][c] += d;
          return zh_varpro_objective(order, t, mask, x, {});
        };
        const double fd = (shifted(h) - shifted(-h)) / (2 * h);
        // The coefficients are re-solved at every shifted point: the analytic gradient,
        // which leaves their change out, agrees only because they are optimal.
        EXPECT_NEAR(grad[3 * k + c], fd, 1e-8) << "axis " << k << " component " << c << " masked " << !mask.empty();
      }
  }
}

TEST(ZhFit, VarProCoefficientsAreTheLeastSquaresSolution) {
  // Per band, the coefficients must solve the ridge normal equations
  // (Y^T Y + lambda I) g = Y^T t; their fit Y g must be the least-squares one, which Eigen's
  // complete orthogonal decomposition gives independently (the coefficients themselves
  // differ from its minimum-norm solution where a band's columns are dependent, as in
  // band 0, by about the ridge over the smallest singular value squared); and psi must be
  // the joint objective at them plus the ridge term. Order 6 with 1 and 3 axes runs the
  // instances compiled for fixed sizes, orders 5 and 6 with 5 axes the run-time-size one.
  Lcg rng{13};
  for (const auto& [order, count] : std::vector<std::pair<int, int>>{{6, 1}, {6, 3}, {5, 3}, {6, 5}}) {
    const std::vector<double> t = random_unit_vector(rng, order);
    std::vector<Eigen::Vector3d> axes;
    for (int k = 0; k < count; ++k) axes.push_back(rng.unit());
    std::vector<double> coeffs(count * order);
    double squared_residual = 0;
    const double psi = zh_varpro_objective(order, t, {}, axes, {}, coeffs, &squared_residual);
    std::vector<ZhLobe> lobes(count);
    std::vector<std::vector<double>> y(count, std::vector<double>(sh_count(order)));
    for (int k = 0; k < count; ++k) eval_sh<double>(order, axes[k], y[k]);
    double ridge_term = 0;
    for (int l = 0; l < order; ++l) {
      Eigen::MatrixXd a(2 * l + 1, count);
      Eigen::VectorXd b(2 * l + 1), g(count);
      for (int k = 0; k < count; ++k) {
        for (int m = -l; m <= l; ++m) a(m + l, k) = y[k][sh_index(l, m)];
        g[k] = coeffs[k * order + l];
      }
      for (int m = -l; m <= l; ++m) b[m + l] = t[sh_index(l, m)];
      const double lambda = kVarProRidge * (2 * l + 1) / (4 * std::numbers::pi);
      const Eigen::VectorXd normal = a.transpose() * (a * g - b) + lambda * g;
      EXPECT_LT(normal.norm(), 1e-14 * (1 + g.norm())) << "order " << order << " axes " << count << " band " << l;
      // With A = U S V^T, the ridge fit differs from the least-squares one by
      // U diag(lambda / (s^2 + lambda)) U^T t, whose part along each singular vector is
      // lambda / s times the coefficients' part: at most lambda / s_min ||g|| (s_min the
      // smallest non-zero singular value), plus rounding.
      const Eigen::VectorXd fit = a * a.completeOrthogonalDecomposition().solve(b);
      const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a);
      double s_min = svd.singularValues()[0];
      for (const double s : svd.singularValues())
        if (s > 1e-10 * svd.singularValues()[0]) s_min = s;
      EXPECT_LT((a * g - fit).norm(), 1.01 * lambda / s_min * g.norm() + 1e-14)
          << "order " << order << " axes " << count << " band " << l;
      for (int k = 0; k < count; ++k) {
        lobes[k].axis = axes[k];
        lobes[k].coeffs.push_back(g[k]);
        ridge_term += lambda * g[k] * g[k];
      }
    }
    EXPECT_NEAR(squared_residual, zh_objective(order, t, lobes, {}), 1e-14) << "order " << order << " axes " << count;
    EXPECT_NEAR(psi, squared_residual + ridge_term, 1e-14) << "order " << order << " axes " << count;
    EXPECT_GT(ridge_term, 0.0);
  }
}

TEST(ZhFit, VarProFixedSizesMatchTheAnySizeReference) {
  // The instances compiled for order 6 and 1-4 axes repeat the run-time-size objective's
  // operations in the same order: value, coefficients, residual and gradient agree bit for
  // bit, also with a pair of nearly coincident axes (the ill-conditioned case), non-unit
  // axes and bands stored directly.
  Lcg rng{17};
  const int order = 6;
  for (int count = 1; count <= 4; ++count)
    for (const std::vector<bool>& mask :
         {std::vector<bool>{}, std::vector<bool>{false, false, true, true, true, true}})
      for (int trial = 0; trial < 3; ++trial) {
        const std::vector<double> t = random_unit_vector(rng, order);
        std::vector<Eigen::Vector3d> axes;
        for (int k = 0; k < count; ++k) axes.push_back((0.5 + rng.uniform()) * rng.unit());
        if (count >= 2 && trial == 2) axes[1] = axes[0] + 1e-4 * rng.unit();
        std::vector<double> grad[2], coeffs[2];
        double value[2], squared_residual[2];
        for (int reference = 0; reference < 2; ++reference) {
          grad[reference].assign(3 * count, 0.0);
          coeffs[reference].assign(count * order, 0.0);
          value[reference] = (reference ? zh_varpro_objective_any_size : zh_varpro_objective)(
              order, t, mask, axes, grad[reference], coeffs[reference], &squared_residual[reference]);
        }
        const std::string what = "axes " + std::to_string(count) + " trial " + std::to_string(trial) +
                                 " masked " + std::to_string(!mask.empty());
        EXPECT_EQ(value[0], value[1]) << what;
        EXPECT_EQ(squared_residual[0], squared_residual[1]) << what;
        EXPECT_EQ(coeffs[0], coeffs[1]) << what;
        EXPECT_EQ(grad[0], grad[1]) << what;
        EXPECT_GT(value[0], 0.0) << what;
      }
}

TEST(ZhFit, VarProFitsMeshTransferAtLeastAsWellAsTheReference) {
  // Shadowed transfer of spot (every 10th vertex): the default method against [4]'s
  // joint BFGS at the same effort, N = 1..4, by the normalized RMS of [4] Fig. 3.
  const Mesh mesh = load_obj(SHTOOL_SOURCE_DIR "/data/spot.obj");
  TransferOptions to;
  to.rays = 64;
  to.threads = 1;
  const std::vector<double> transfer = compute_transfer(mesh, to);
  const std::size_t n2 = sh_count(to.order);
  for (int n = 1; n <= 4; ++n) {
    double nrms[2];
    for (const ZhFitMethod method : {ZhFitMethod::varpro, ZhFitMethod::joint}) {
      ZhFitOptions o;
      o.order = to.order;
      o.lobes = n;
      o.method = method;
      double r2 = 0, t2 = 0;
      for (std::size_t v = 0; v < mesh.positions.size(); v += 10) {
        const ZhFit fit = fit_zh(std::span<const double>(transfer).subspan(v * n2, n2), o, v);
        r2 += fit.residual * fit.residual;
        t2 += fit.norm * fit.norm;
      }
      nrms[method == ZhFitMethod::joint] = std::sqrt(r2 / t2);
    }
    // N = 1 has one global optimum both find; from N = 2 the search matters.
    EXPECT_LE(nrms[0], nrms[1] * (1 + 1e-3)) << "N " << n << " varpro " << nrms[0] << " joint " << nrms[1];
  }
}

// The fit fixture `bench_fit --write-best-known` computed: random unit order-6 vectors
// and shadowed transfer vectors of data/spot.obj, each with the best residual known for
// N = 1, 2, 4 (N = 1 from every grid maximum of 65,536 axes refined; N = 2, 4 the lowest
// of thousands of starts of both methods).
struct BestKnown {
  std::vector<std::vector<double>> vectors;
  std::map<int, std::vector<double>> residual;  // by lobe count
};

std::map<std::string, BestKnown> load_best_known(int& order) {
  std::ifstream in(SHTOOL_SOURCE_DIR "/tests/offline/data/zh_fit_best_known.json");
  std::stringstream text;
  text << in.rdbuf();
  const nlohmann::json doc = nlohmann::json::parse(text.str());
  order = doc.at("order").get<int>();
  std::map<std::string, BestKnown> sets;
  for (const auto& [name, set] : doc.at("sets").items()) {
    BestKnown& b = sets[name];
    b.vectors = set.at("vectors").get<std::vector<std::vector<double>>>();
    for (const auto& [lobes, r] : set.at("best_residual").items())
      b.residual[std::stoi(lobes)] = r.get<std::vector<double>>();
  }
  return sets;
}

// Mean over the vectors of residual / best-known residual.
double mean_ratio_to_best(const BestKnown& b, const ZhFitOptions& o, const std::string& name) {
  double sum = 0;
  const std::vector<double>& best = b.residual.at(o.lobes);
  for (std::size_t v = 0; v < b.vectors.size(); ++v) {
    const ZhFit fit = fit_zh(b.vectors[v], o, v);
    // Never below the best known by more than rounding: that would make the reference stale.
    EXPECT_GE(fit.residual, best[v] * (1 - 1e-6)) << name << " vector " << v << " lobes " << o.lobes;
    sum += fit.residual / best[v];
  }
  return sum / static_cast<double>(b.vectors.size());
}

TEST(ZhFit, FixtureHasBothSets) {
  int order = 0;
  const std::map<std::string, BestKnown> sets = load_best_known(order);
  EXPECT_EQ(order, 6);
  ASSERT_EQ(sets.size(), 2u);
  EXPECT_EQ(sets.at("random").vectors.size(), 20u);
  EXPECT_EQ(sets.at("spot").vectors.size(), 40u);
  for (const auto& [name, b] : sets)
    for (int n : {1, 2, 4}) EXPECT_EQ(b.residual.at(n).size(), b.vectors.size()) << name << " N " << n;
}

TEST(ZhFit, SingleLobeIsTheBestKnownAtEveryEffortAndMethod) {
  int order = 0;
  for (const auto& [name, b] : load_best_known(order)) {
    for (const ZhFitMethod method : {ZhFitMethod::varpro, ZhFitMethod::joint})
      for (int effort = kMinEffort; effort <= kMaxEffort; ++effort) {
        ZhFitOptions o;
        o.order = order;
        o.lobes = 1;
        o.method = method;
        apply_effort(o, effort);
        for (std::size_t v = 0; v < b.vectors.size(); ++v) {
          const ZhFit fit = fit_zh(b.vectors[v], o, v);
          // Both stop at a relative change of 1e-10 in psi at the same maximum.
          EXPECT_NEAR(fit.residual, b.residual.at(1)[v], 1e-9 * b.residual.at(1)[v])
              << name << " vector " << v << " effort " << effort << " joint " << (method == ZhFitMethod::joint);
        }
      }
  }
}

TEST(ZhFit, SingleLobeSearchFindsTheOptimumOfADenserGrid) {
  // The exhaustive check of the default density: on 400 more vectors (random unit ones,
  // and sums of two or three random lobes with a little noise, whose energy has several
  // comparable maxima), the default search equals the reference that refines every grid
  // maximum of 16 times as many axes.
  Lcg rng{15};
  const int order = 6;
  std::vector<double> c(order);
  int checked = 0;
  for (int trial = 0; trial < 400; ++trial) {
    std::vector<double> t;
    if (trial % 2 == 0) {
      t = random_unit_vector(rng, order);
    } else {
      std::vector<ZhLobe> lobes;
      for (int k = 0; k < 2 + trial % 3; ++k) lobes.push_back(random_lobe(rng, order));
      t.assign(36, 0.0);
      lobes_to_sh(order, lobes, t);
      for (double& x : t) x += 0.05 * (2 * rng.uniform() - 1);
    }
    for (const std::vector<bool>& mask : {std::vector<bool>{}, std::vector<bool>{false, true, true, true, true, true}}) {
      Eigen::Vector3d fast_axis, ref_axis;
      std::vector<double> fast_c(order), ref_c(order);
      const double fast = best_single_lobe(order, t, mask, kSingleLobeAxes, kSingleLobeMaxima, fast_axis, fast_c);
      const double ref = best_single_lobe(order, t, mask, 16 * kSingleLobeAxes, 0, ref_axis, ref_c);
      EXPECT_NEAR(fast, ref, 1e-9 * ref) << "trial " << trial << " masked " << !mask.empty();
      // The returned pair is Eq. 18 at the returned axis.
      EXPECT_NEAR(single_lobe_closed_form(order, t, fast_axis, c, mask), fast, 1e-15);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 800);
}

TEST(ZhFit, SingleLobeSearchScalesWithTheOrder) {
  // Above order 6 the energy's degree grows, and the scan with it (single_lobe_axes_for):
  // on random unit vectors of orders 8, 12 and 16 the default search equals one over 4
  // times as many axes refining 32 grid maxima. With 1024 axes and the grid maxima alone,
  // 1 to 10 in 800 such vectors missed the optimum at these orders (two maxima 0.16 rad
  // apart sharing one grid maximum), so this check would catch a scan left at order 6's.
  Lcg rng{16};
  EXPECT_EQ(single_lobe_axes_for(2), kSingleLobeAxes);
  EXPECT_EQ(single_lobe_axes_for(6), kSingleLobeAxes);
  EXPECT_EQ(single_lobe_axes_for(8), 2007);
  EXPECT_EQ(single_lobe_axes_for(16), 9216);
  for (const int order : {8, 12, 16}) {
    std::vector<double> c(order), ref_c(order);
    for (int trial = 0; trial < 120; ++trial) {
      const std::vector<double> t = random_unit_vector(rng, order);
      Eigen::Vector3d axis, ref_axis;
      const double fast = best_single_lobe(order, t, {}, single_lobe_axes_for(order), kSingleLobeMaxima, axis, c);
      const double ref = best_single_lobe(order, t, {}, 4 * single_lobe_axes_for(order), 32, ref_axis, ref_c);
      EXPECT_NEAR(fast, ref, 1e-9 * ref) << "order " << order << " trial " << trial;
    }
    // fit_zh's single lobe is that search.
    const std::vector<double> t = random_unit_vector(rng, order);
    ZhFitOptions o;
    o.order = order;
    o.lobes = 1;
    Eigen::Vector3d axis;
    const double psi = best_single_lobe(order, t, {}, single_lobe_axes_for(order), kSingleLobeMaxima, axis, c);
    EXPECT_NEAR(fit_zh(t, o).residual, std::sqrt(psi), 1e-12) << "order " << order;
    // An axis count of 0 is the count for the order, not an empty scan.
    EXPECT_EQ(best_single_lobe(order, t, {}, 0, kSingleLobeMaxima, axis, c), psi) << "order " << order;
  }
}

TEST(ZhFit, DefaultEffortIsNearTheBestKnown) {
  int order = 0;
  for (const auto& [name, b] : load_best_known(order)) {
    ZhFitOptions o;
    o.order = order;
    // Default effort: N = 2 within 2 % of the best known fit on both sets.
    o.lobes = 2;
    EXPECT_LE(mean_ratio_to_best(b, o, name), 1.02) << name;
    o.lobes = 4;
    const double varpro = mean_ratio_to_best(b, o, name);
    // The reference method at the same effort stays behind (the reason for the default).
    ZhFitOptions joint = o;
    joint.method = ZhFitMethod::joint;
    EXPECT_LT(varpro, mean_ratio_to_best(b, joint, name)) << name;
    if (name == "random") {
      // N = 4 within 10 % on random vectors, which all get the default's random starts.
      EXPECT_LE(varpro, 1.10) << name;
    } else {
      // Transfer vectors are fitted within the 5 % restart threshold by the deterministic
      // starts (greedy and split, the better one's last lobe re-seated at up to three
      // residual peaks, the low-order start, the winner polished to 1e-4 within 50
      // evaluations), so the default runs no random start for them and stays above the
      // best known at N = 4: 1.351 on average, short of the 1.10 target (docs/fit-zh.md,
      // "Benchmarks"; 1.331 before the search saw every vector at unit norm, which
      // also lowered 20 of the best knowns by up to 12 %; without the low-order start
      // 1.346 with the polish within 40, 1.352 within 30, 1.427 with one re-seat, 1.77
      // with the greedy start alone, on the earlier best knowns).
      // The fit is deterministic; 1.355 leaves room for the last bits of another libm,
      // not for a lost start, re-seat or polish. --effort 3, which restarts every
      // vector, comes within 6 %.
      EXPECT_LE(varpro, 1.355) << name;
      ZhFitOptions high = o;
      apply_effort(high, 3);
      EXPECT_LE(mean_ratio_to_best(b, high, name), 1.06) << name;
    }
  }
}

TEST(ZhFit, EffortLevelsAndTheDefault) {
  ZhFitOptions o;
  EXPECT_THROW(apply_effort(o, kMinEffort - 1), std::exception);
  EXPECT_THROW(apply_effort(o, kMaxEffort + 1), std::exception);
  o.lobes = 3;
  apply_effort(o, 3);
  EXPECT_EQ(o.starts, 12 * 9);
  EXPECT_EQ(o.restart_above, 0.0);
  apply_effort(o, kDefaultEffort);
  EXPECT_EQ(o.starts, 5 * 9);
  // Options left at kStartsByEffort fit as the default level does, bit for bit.
  Lcg rng{14};
  const std::vector<double> t = random_unit_vector(rng, 6);
  ZhFitOptions by_default;
  by_default.lobes = 3;
  const ZhFit a = fit_zh(t, by_default, 7), b = fit_zh(t, o, 7);
  EXPECT_EQ(a.residual, b.residual);
  ZhFitOptions fewer = o;
  fewer.starts = 0;
  EXPECT_NE(fit_zh(t, fewer, 7).residual, a.residual) << "the starts must have changed the fit";
}

}  // namespace
