// Real SH evaluation (include/shtool/sh.h) against references that do not share code
// with src/runtime/basis/sh.cpp: hand-written Cartesian closed forms of bands 0-3, a long
// double evaluation through libstdc++'s std::assoc_legendrel, std::sph_legendre, the
// addition theorem with P_l from the Bonnet recurrence, quadrature orthonormality and
// finite differences. Conventions are those of docs/conventions.md.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include "shtool/quadrature.h"
#include "shtool/sh.h"
#include "test_util.h"

// Counting replacement of the global allocator, so the allocation-free promise of
// sh.h can be checked. Counting is switched on only around the calls under test.
namespace {
std::atomic<long> g_allocations{0};
std::atomic<bool> g_count_allocations{false};
}  // namespace

void* operator new(std::size_t size) {
  if (g_count_allocations.load(std::memory_order_relaxed)) ++g_allocations;
  if (void* p = std::malloc(size ? size : 1)) return p;
  throw std::bad_alloc();
}
// Not inlined, so GCC does not see free() applied to a new-ed pointer at each call site
// (-Wmismatched-new-delete); the pair is consistent by construction.
[[gnu::noinline]] void operator delete(void* p) noexcept { std::free(p); }
[[gnu::noinline]] void operator delete(void* p, std::size_t) noexcept { std::free(p); }

namespace shtool {
namespace {

using LD = long double;
constexpr LD kPiL = 3.141592653589793238462643383279502884L;
constexpr double kPi = std::numbers::pi;

// Bound on |y_l^m| over the sphere: by the addition theorem at a = b,
// sum_m (y_l^m)^2 = (2l+1)/(4 pi), so every |y_l^m| <= sqrt((2l+1)/(4 pi)).
// Errors are measured relative to this band scale.
double band_scale(int l) { return std::sqrt((2.0 * l + 1.0) / (4.0 * kPi)); }

constexpr double kEps = 2.220446049250313e-16;

// Measured figures are recorded as test properties (--gtest_output=xml shows them).
std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}
// Error budget of a three-term recurrence in l, relative to the band scale. Away from
// the poles each step adds ~1 rounding (~l ulp in all). Near z = +-1 the two roots of the
// recurrence merge, an error made at step k is carried forward growing like (l - k), and
// the total reaches ~l^2/6 ulp: measured 62 ulp at l = 18 and 133 ulp at l = 29 for the
// textbook Bonnet recurrence of P_l in double, and the same size for sh.cpp. So allow
// 4 + l^2/3 ulp (6.3e-14 at l = 29).
double recurrence_tol(int l) { return (4.0 + l * l / 3.0) * kEps; }

// Directions used throughout: poles, axes, equator points, near-pole points and
// uniformly random unit vectors (fixed seed).
std::vector<Vec3<double>> test_directions(int random_count, unsigned seed = 12345) {
  std::vector<Vec3<double>> dirs = {
      {0, 0, 1},  {0, 0, -1}, {1, 0, 0},  {-1, 0, 0}, {0, 1, 0}, {0, -1, 0},
      {std::sqrt(0.5), std::sqrt(0.5), 0}, {-0.6, 0.8, 0},  // equator
      {1e-9, 0, 1},  {0, -1e-12, -1},                         // next to the poles
  };
  for (auto& d : dirs) d.normalize();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> uz(-1.0, 1.0), up(0.0, 2.0 * kPi);
  for (int k = 0; k < random_count; ++k) {
    const double z = uz(rng), p = up(rng), s = std::sqrt((1.0 - z) * (1.0 + z));
    dirs.emplace_back(s * std::cos(p), s * std::sin(p), z);
  }
  return dirs;
}

// Bands 0-3 written out by hand from the convention (Condon-Shortley phase), in long
// double. Index i = l(l+1)+m. Derivation (P with CS phase, K_l^m as in the doc):
//   y_2^{+-1}: sqrt2 K_2^1 P_2^1 with P_2^1 = -3 z sin t       -> -sqrt(15/(4pi)) {x,y} z
//   y_2^{+-2}: sqrt2 K_2^2 P_2^2 with P_2^2 = 3 sin^2 t        -> sqrt(15/(16pi)) {x^2-y^2, 2xy}
//   y_3^{+-1}: P_3^1 = -(3/2)(5z^2-1) sin t                    -> -sqrt(21/(32pi)) {x,y} (5z^2-1)
//   y_3^{+-2}: P_3^2 = 15 z sin^2 t                            -> sqrt(105/(16pi)) z {x^2-y^2, 2xy}
//   y_3^{+-3}: P_3^3 = -15 sin^3 t                             -> -sqrt(35/(32pi)) {x^3-3xy^2, 3x^2y-y^3}
std::array<LD, 16> closed_form_bands_0_3(LD x, LD y, LD z) {
  const LD c0 = 0.5L / std::sqrt(kPiL);
  const LD c1 = std::sqrt(3 / (4 * kPiL));
  const LD c2a = std::sqrt(15 / (4 * kPiL)), c2b = std::sqrt(5 / (16 * kPiL)),
           c2c = std::sqrt(15 / (16 * kPiL));
  const LD c3a = std::sqrt(35 / (32 * kPiL)), c3b = std::sqrt(105 / (4 * kPiL)),
           c3c = std::sqrt(21 / (32 * kPiL)), c3d = std::sqrt(7 / (16 * kPiL)),
           c3e = std::sqrt(105 / (16 * kPiL));
  return {
      c0,
      -c1 * y, c1 * z, -c1 * x,
      c2a * x * y, -c2a * y * z, c2b * (3 * z * z - 1), -c2a * x * z, c2c * (x * x - y * y),
      -c3a * y * (3 * x * x - y * y), c3b * x * y * z, -c3c * y * (5 * z * z - 1),
      c3d * z * (5 * z * z - 3), -c3c * x * (5 * z * z - 1), c3e * z * (x * x - y * y),
      -c3a * x * (x * x - 3 * y * y),
  };
}

// Independent high-order reference in long double by another route: the Gegenbauer
// form P_l^m(x) = (-1)^m (2m-1)!! sin^m t C_{l-m}^{(m+1/2)}(x) (the m-th derivative of
// P_l), with C by its own three-term recurrence, K_l^m (2m-1)!! from lgamma, sin t from
// hypot(x, y) and the azimuth from cos/sin of atan2. sh.cpp instead runs the normalised
// recurrence and the polynomial (x+iy)^m and never forms K, P or a factorial.
// (std::assoc_legendrel is not used here: it forms sin t as sqrt(1-x^2), which loses
// all precision next to the poles.)
std::vector<LD> reference_sh(int order, const Vec3<double>& w) {
  // w is unit only to ~1 ulp, and near the poles y_l^0 changes by ~l^2/2 band scales per
  // unit of z; so, like sh.cpp, take cos t = z and sin t = |(x, y)| as given instead of
  // renormalising, or the comparison would measure input conditioning, not evaluation.
  const LD x = w.x(), y = w.y();
  const LD ct = w.z(), st = std::hypot(x, y), phi = std::atan2(y, x);
  std::vector<LD> out(sh_count(order));
  for (int m = 0; m < order; ++m) {
    const LD alpha = m + 0.5L;
    LD c2 = 0, c1 = 1;  // C_{n-2}, C_{n-1}; starts with C_0 = 1
    for (int l = m; l < order; ++l) {
      const int n = l - m;
      LD c = 1;
      if (n == 1) c = 2 * alpha * ct;
      if (n >= 2) c = (2 * ct * (n + alpha - 1) * c1 - (n + 2 * alpha - 2) * c2) / n;
      if (n >= 1) {
        c2 = c1;
        c1 = c;
      }
      // log of K_l^m (2m-1)!! / sqrt((2l+1)/(4 pi)), with (2m-1)!! = (2m)! / (2^m m!)
      const LD log_norm = 0.5L * (std::lgamma(LD(l - m + 1)) - std::lgamma(LD(l + m + 1))) +
                          std::lgamma(LD(2 * m + 1)) - m * std::log(2.0L) - std::lgamma(LD(m + 1));
      const LD p = (m % 2 ? -1 : 1) * std::sqrt((2 * l + 1) / (4 * kPiL)) * std::exp(log_norm) *
                   std::pow(st, m) * c;
      if (m == 0) {
        out[sh_index(l, 0)] = p;
      } else {
        out[sh_index(l, m)] = std::sqrt(2.0L) * p * std::cos(m * phi);
        out[sh_index(l, -m)] = std::sqrt(2.0L) * p * std::sin(m * phi);
      }
    }
  }
  return out;
}

using test::legendre_p;

std::vector<double> eval_d(int order, const Vec3<double>& w) {
  std::vector<double> v(sh_count(order));
  eval_sh<double>(order, w, v);
  return v;
}

// ---------------------------------------------------------------------------
// Closed forms of bands 0-3.

// Double: the closed forms and the recurrence each take a handful of roundings on values
// of size <= band scale, so 4 ulp of the band scale bounds the difference.
constexpr double kClosedFormTolDouble = 4 * 2.220446049250313e-16;
// Float: same argument with float ulp (6e-8); 1e-6 leaves a factor ~4 of headroom over
// 4 float ulp and is the accuracy required of float evaluation.
constexpr double kClosedFormTolFloat = 1e-6;

TEST(ShClosedForm, Bands0To3Double) {
  double worst = 0;
  for (const auto& w : test_directions(2000)) {
    const auto ref = closed_form_bands_0_3(w.x(), w.y(), w.z());
    const auto got = eval_d(4, w);
    for (int i = 0; i < 16; ++i) {
      const double err = std::abs(got[i] - double(ref[i])) / band_scale(sh_band(i));
      worst = std::max(worst, err);
      EXPECT_LE(err, kClosedFormTolDouble)
          << "i " << i << " w " << w.transpose() << " got " << got[i] << " ref " << double(ref[i]);
    }
  }
  RecordProperty("max_rel_err", sci(worst));
}

TEST(ShClosedForm, Bands0To3Float) {
  double worst = 0;
  for (const auto& wd : test_directions(2000)) {
    const Vec3<float> w = wd.cast<float>();
    // Reference at the float direction itself, so input rounding is not counted.
    const auto ref = closed_form_bands_0_3(w.x(), w.y(), w.z());
    std::array<float, 16> got{};
    eval_sh<float>(4, w, got);
    for (int i = 0; i < 16; ++i) {
      const double err = std::abs(double(got[i]) - double(ref[i])) / band_scale(sh_band(i));
      worst = std::max(worst, err);
      EXPECT_LE(err, kClosedFormTolFloat)
          << "i " << i << " w " << w.transpose() << " got " << got[i] << " ref " << double(ref[i]);
    }
  }
  RecordProperty("max_rel_err", sci(worst));
}

// ---------------------------------------------------------------------------
// One test per convention point (docs/conventions.md).

TEST(ShConvention, FlatIndexRule) {
  for (int l = 0; l < kMaxOrder; ++l)
    for (int m = -l; m <= l; ++m) {
      ASSERT_EQ(sh_index(l, m), l * l + l + m);
      ASSERT_EQ(sh_band(sh_index(l, m)), l) << "l " << l << " m " << m;
    }
  EXPECT_EQ(sh_count(3), 9);
  EXPECT_EQ(sh_index(kMaxOrder - 1, kMaxOrder - 1) + 1, sh_count(kMaxOrder));
  // m runs -l..l inside a band: on +y band 1 is (y_1^-1, y_1^0, y_1^1) = (-c, 0, 0),
  // so the only nonzero band-1 entry sits at index 1 = sh_index(1, -1).
  const auto v = eval_d(2, {0, 1, 0});
  EXPECT_NE(v[1], 0.0);
  EXPECT_EQ(v[2], 0.0);
  EXPECT_EQ(v[3], 0.0);
}

TEST(ShConvention, CondonShortleyPhase) {
  // With the CS phase, P_l^l = (-1)^l (2l-1)!! sin^l t, so y_l^l(+x) has sign (-1)^l.
  const auto v = eval_d(31, {1, 0, 0});
  for (int l = 1; l <= 30; ++l) {
    const double s = v[sh_index(l, l)];
    EXPECT_EQ(std::signbit(s), l % 2 == 1) << "l " << l << " y_l^l(+x) " << s;
    EXPECT_GT(std::abs(s), 0.1) << "l " << l;
  }
  EXPECT_NEAR(v[sh_index(1, 1)], -std::sqrt(3 / (4 * kPi)), 1e-16);
}

TEST(ShConvention, BandOneIsMinusCY_CZ_MinusCX) {
  const double c = std::sqrt(3 / (4 * kPi));
  for (const auto& w : test_directions(200)) {
    const auto v = eval_d(2, w);
    // One multiplication on each side: 2 ulp of c.
    EXPECT_NEAR(v[1], -c * w.y(), 2 * kEps * c) << w.transpose();
    EXPECT_NEAR(v[2], c * w.z(), 2 * kEps * c) << w.transpose();
    EXPECT_NEAR(v[3], -c * w.x(), 2 * kEps * c) << w.transpose();
  }
}

TEST(ShConvention, AzimuthRunsFromXTowardY) {
  // p increases from +x toward +y: direction_from_angles(pi/2, pi/2) is +y, and
  // y_l^{-m} ~ sin(m p), y_l^m ~ cos(m p), so y_l^{-m}(t, p) = y_l^m(t, p - pi/(2m)).
  const Vec3<double> ey = direction_from_angles(kPi / 2, kPi / 2);
  EXPECT_NEAR(ey.x(), 0, 1e-16);
  EXPECT_NEAR(ey.y(), 1, 1e-16);
  EXPECT_NEAR(ey.z(), 0, 1e-16);
  const int order = 11;
  for (double t : {0.3, 1.1, 2.0, 2.9})
    for (double p : {0.0, 0.7, 2.5, 4.0}) {
      const auto a = eval_d(order, direction_from_angles(t, p));
      for (int l = 1; l < order; ++l)
        for (int m = 1; m <= l; ++m) {
          const auto b = eval_d(order, direction_from_angles(t, p - kPi / (2 * m)));
          EXPECT_NEAR(a[sh_index(l, -m)], b[sh_index(l, m)], 1e-14 * band_scale(l))
              << "l " << l << " m " << m << " t " << t << " p " << p;
        }
    }
}

TEST(ShConvention, PoleValues) {
  // At the poles only m = 0 survives: y_l^0(+-z) = (+-1)^l sqrt((2l+1)/(4 pi)).
  const int order = 40;
  const auto n = eval_d(order, {0, 0, 1}), s = eval_d(order, {0, 0, -1});
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) {
      const int i = sh_index(l, m);
      const double expect = m == 0 ? band_scale(l) : 0.0;
      const double tol = recurrence_tol(l) * band_scale(l);
      EXPECT_NEAR(n[i], expect, tol) << "l " << l << " m " << m;
      EXPECT_NEAR(s[i], (l % 2 ? -1 : 1) * expect, tol) << "l " << l << " m " << m;
    }
}

// ---------------------------------------------------------------------------
// Orthonormality by quadrature.

// Gram matrix sum_k w_k y_i(w_k) y_j(w_k) with a rule exact for degree 2N-2.
double orthonormality_deviation(int order) {
  const SphereQuadrature q = sphere_quadrature(2 * order - 2);
  const int n = sh_count(order);
  Eigen::MatrixXd b(q.directions.size(), n);
  std::vector<double> v(n);
  for (std::size_t k = 0; k < q.directions.size(); ++k) {
    eval_sh<double>(order, q.directions[k], v);
    for (int i = 0; i < n; ++i) b(k, i) = v[i] * std::sqrt(q.weights[k]);
  }
  const Eigen::MatrixXd g = b.transpose() * b;
  return (g - Eigen::MatrixXd::Identity(n, n)).cwiseAbs().maxCoeff();
}

// Each Gram entry is a sum of ~N * 2N terms of size <= (2l+1)/(4pi) * weight;
// 1e-12 is the required bound and still ~100x above the rounding accumulated here.
constexpr double kOrthonormalityTol = 1e-12;

TEST(ShOrthonormality, UpTo20) {
  for (int order = 1; order <= 20; ++order) {
    const double dev = orthonormality_deviation(order);
    EXPECT_LE(dev, kOrthonormalityTol) << "order " << order << " max |G - I| " << dev;
  }
}

TEST(ShOrthonormality, Order30) {
  const double dev = orthonormality_deviation(30);
  RecordProperty("max_dev", sci(dev));
  EXPECT_LE(dev, kOrthonormalityTol) << "max |G - I| " << dev;
}

TEST(ShOrthonormality, DetectsAnUnderResolvedRule) {
  // The check above must be able to fail: a rule one degree short of 2N-2 leaves the
  // Gram matrix visibly off the identity.
  const int order = 8;
  const SphereQuadrature q = sphere_quadrature(2 * order - 3);
  const int n = sh_count(order);
  std::vector<double> v(n);
  double g = 0;  // <y_{7,7}, y_{7,7}> under the short rule
  for (std::size_t k = 0; k < q.directions.size(); ++k) {
    eval_sh<double>(order, q.directions[k], v);
    g += q.weights[k] * v[sh_index(7, 7)] * v[sh_index(7, 7)];
  }
  EXPECT_GT(std::abs(g - 1.0), 1e-3) << "g " << g;
}

// ---------------------------------------------------------------------------
// Addition theorem: sum_m y_l^m(a) y_l^m(b) = (2l+1)/(4 pi) P_l(a . b).

// By Cauchy-Schwarz sum_m |y_l^m(a) y_l^m(b)| <= band scale^2, and each factor carries
// recurrence_tol(l) of the band scale, so the sum is good to 2 recurrence_tol(l) of scale^2.
double addition_tol(int l) { return 2 * recurrence_tol(l); }

TEST(ShAddition, TheoremUpTo30) {
  const int order = 31;
  const auto dirs = test_directions(300, 777);
  double worst = 0;
  for (std::size_t k = 0; k + 1 < dirs.size(); ++k) {
    const Vec3<double>& a = dirs[k];
    const Vec3<double>& b = dirs[k + 1];
    const auto ya = eval_d(order, a), yb = eval_d(order, b);
    const LD dot = LD(a.x()) * b.x() + LD(a.y()) * b.y() + LD(a.z()) * b.z();
    for (int l = 0; l < order; ++l) {
      double sum = 0;
      for (int m = -l; m <= l; ++m) sum += ya[sh_index(l, m)] * yb[sh_index(l, m)];
      const double ref = double((2 * l + 1) / (4 * kPiL) * legendre_p(l, dot));
      const double err = std::abs(sum - ref) / (band_scale(l) * band_scale(l));
      worst = std::max(worst, err);
      EXPECT_LE(err, addition_tol(l)) << "l " << l << " a " << a.transpose() << " b "
                                   << b.transpose() << " sum " << sum << " ref " << ref;
    }
  }
  RecordProperty("max_rel_err", sci(worst));
}

// ---------------------------------------------------------------------------
// High order against the long double reference.


TEST(ShHighOrder, Order30DoubleAgainstLongDoubleReference) {
  const int order = 30;
  double worst = 0;
  for (const auto& w : test_directions(500, 99)) {
    const auto ref = reference_sh(order, w);
    const auto got = eval_d(order, w);
    for (int l = 0; l < order; ++l)
      for (int m = -l; m <= l; ++m) {
        const int i = sh_index(l, m);
        const double err = std::abs(got[i] - double(ref[i])) / band_scale(l);
        worst = std::max(worst, err);
        EXPECT_LE(err, recurrence_tol(l)) << "l " << l << " m " << m << " w " << w.transpose()
                                            << " got " << got[i] << " ref " << double(ref[i]);
      }
  }
  RecordProperty("max_rel_err", sci(worst));
}

// Float: the budget of recurrence_tol with the float epsilon (1.7e-5 at l = 29); the
// reference is double at the same float direction, so input rounding is not counted.
double recurrence_tol_float(int l) { return (4.0 + l * l / 3.0) * 1.1920928955078125e-7; }

TEST(ShHighOrder, Order30FloatAgainstDouble) {
  const int order = 30;
  double worst = 0;
  std::vector<float> got(sh_count(order));
  for (const auto& wd : test_directions(500, 98)) {
    const Vec3<float> w = wd.cast<float>();
    eval_sh<float>(order, w, got);
    const auto ref = eval_d(order, w.cast<double>());
    for (int l = 0; l < order; ++l)
      for (int m = -l; m <= l; ++m) {
        const int i = sh_index(l, m);
        const double err = std::abs(double(got[i]) - ref[i]) / band_scale(l);
        worst = std::max(worst, err);
        EXPECT_LE(err, recurrence_tol_float(l))
            << "l " << l << " m " << m << " w " << w.transpose() << " got " << got[i] << " ref "
            << ref[i];
      }
  }
  RecordProperty("max_rel_err", sci(worst));
}

TEST(ShHighOrder, FiniteAndBoundedAtOrder128) {
  // Stability: no overflow/underflow to NaN or inf at the largest order, and each band
  // still satisfies sum_m (y_l^m)^2 = (2l+1)/(4 pi) (addition theorem at a = b).
  const int order = kMaxOrder;
  std::vector<double> vd(sh_count(order));
  std::vector<float> vf(sh_count(order));
  double worst_d = 0, worst_f = 0;
  for (const auto& w : test_directions(200, 5)) {
    eval_sh<double>(order, w, vd);
    eval_sh<float>(order, w.cast<float>(), vf);
    for (int l = 0; l < order; ++l) {
      double sd = 0, sf = 0;
      for (int m = -l; m <= l; ++m) {
        const int i = sh_index(l, m);
        ASSERT_TRUE(std::isfinite(vd[i])) << "double l " << l << " m " << m << " w " << w.transpose();
        ASSERT_TRUE(std::isfinite(vf[i])) << "float l " << l << " m " << m << " w " << w.transpose();
        sd += vd[i] * vd[i];
        sf += double(vf[i]) * vf[i];
      }
      const double s2 = band_scale(l) * band_scale(l);
      // Squares: twice the per-value budget (same argument as addition_tol).
      EXPECT_NEAR(sd / s2, 1.0, 2 * recurrence_tol(l)) << "double l " << l << " w " << w.transpose();
      EXPECT_NEAR(sf / s2, 1.0, 2 * recurrence_tol_float(l)) << "float l " << l << " w " << w.transpose();
      worst_d = std::max(worst_d, std::abs(sd / s2 - 1.0));
      worst_f = std::max(worst_f, std::abs(sf / s2 - 1.0));
    }
  }
  RecordProperty("max_dev_double", sci(worst_d));
  RecordProperty("max_dev_float", sci(worst_f));
}

// ---------------------------------------------------------------------------
// Gradients.

// Central differences along a great circle: truncation h^2/6 |f'''| <= h^2/6 l^3 scale
// ~ 3e-8 scale for l <= 11 at h = 1e-5, rounding eps scale / h ~ 2e-11 scale.
constexpr double kFdStep = 1e-5;
constexpr double kFdTol = 1e-7;

TEST(ShGradient, MatchesFiniteDifferencesAndIsTangent) {
  const int order = 12, n = sh_count(order);
  std::vector<double> val(n), grad(3 * n), vp(n), vm(n);
  double worst = 0;
  for (const auto& w : test_directions(100, 31)) {
    eval_sh_with_gradient<double>(order, w, val, grad);
    // Two orthonormal tangents (any pair works; at the poles they are x and y).
    Vec3<double> u = std::abs(w.z()) < 0.9 ? Vec3<double>(0, 0, 1).cross(w) : Vec3<double>(1, 0, 0).cross(w);
    u.normalize();
    const Vec3<double> v = w.cross(u);
    for (const Vec3<double>& t : {u, v}) {
      const Vec3<double> wp = std::cos(kFdStep) * w + std::sin(kFdStep) * t;
      const Vec3<double> wm = std::cos(kFdStep) * w - std::sin(kFdStep) * t;
      eval_sh<double>(order, wp, vp);
      eval_sh<double>(order, wm, vm);
      for (int i = 0; i < n; ++i) {
        const Vec3<double> g(grad[3 * i], grad[3 * i + 1], grad[3 * i + 2]);
        const double fd = (vp[i] - vm[i]) / (2 * kFdStep);
        const double err = std::abs(g.dot(t) - fd) / band_scale(sh_band(i));
        worst = std::max(worst, err);
        EXPECT_LE(err, kFdTol) << "i " << i << " w " << w.transpose() << " grad.t " << g.dot(t)
                               << " fd " << fd;
      }
    }
    for (int i = 0; i < n; ++i) {
      const Vec3<double> g(grad[3 * i], grad[3 * i + 1], grad[3 * i + 2]);
      // Tangency: projected gradient, so only rounding of |g| ~ l scale remains.
      EXPECT_LE(std::abs(g.dot(w)), 1e-14 * band_scale(sh_band(i)) * (sh_band(i) + 1))
          << "i " << i << " w " << w.transpose() << " grad.w " << g.dot(w);
      EXPECT_DOUBLE_EQ(val[i], eval_d(order, w)[i]) << "i " << i;
    }
  }
  RecordProperty("max_rel_err", sci(worst));
}

TEST(ShGradient, BandOneAtThePole) {
  // y_1^1 = -c x: its surface gradient at +z is -c (1, 0, 0); y_1^{-1} gives -c (0, 1, 0).
  const double c = std::sqrt(3 / (4 * kPi));
  std::array<double, 4> val{};
  std::array<double, 12> grad{};
  eval_sh_with_gradient<double>(2, Vec3<double>(0, 0, 1), val, grad);
  EXPECT_NEAR(grad[3 * 3 + 0], -c, 1e-16);
  EXPECT_NEAR(grad[3 * 1 + 1], -c, 1e-16);
  for (int k : {1, 2, 3 * 1 + 0, 3 * 1 + 2, 3 * 2 + 0, 3 * 2 + 1, 3 * 2 + 2, 3 * 3 + 1, 3 * 3 + 2})
    EXPECT_NEAR(grad[k], 0.0, 1e-16) << "grad component " << k;
}

TEST(ShGradient, FloatAgreesWithDouble) {
  const int order = 12, n = sh_count(order);
  std::vector<double> vd(n), gd(3 * n);
  std::vector<float> vf(n), gf(3 * n);
  for (const auto& wd : test_directions(100, 32)) {
    const Vec3<float> w = wd.cast<float>();
    eval_sh_with_gradient<float>(order, w, vf, gf);
    eval_sh_with_gradient<double>(order, w.cast<double>(), vd, gd);
    for (int i = 0; i < 3 * n; ++i) {
      const int l = sh_band(i / 3);
      // Gradient magnitude is up to ~l band scale, each with the float recurrence budget.
      EXPECT_NEAR(gf[i], gd[i], recurrence_tol_float(l) * band_scale(l) * (l + 1))
          << "component " << i << " float " << gf[i] << " double " << gd[i];
    }
  }
}

// ---------------------------------------------------------------------------
// Batch, reconstruction, angles, allocation.

TEST(ShBatch, EqualsSingleAndStaysInBounds) {
  const int order = 9, n = sh_count(order);
  const auto dirs = test_directions(50, 3);
  std::vector<double> flat;
  for (const auto& w : dirs) flat.insert(flat.end(), {w.x(), w.y(), w.z()});
  const double sentinel = -12345.0;
  std::vector<double> out(dirs.size() * n + 7, sentinel);
  eval_sh_batch<double>(order, flat, out);
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    const auto single = eval_d(order, dirs[k]);
    for (int i = 0; i < n; ++i) ASSERT_EQ(out[k * n + i], single[i]) << "dir " << k << " i " << i;
  }
  for (std::size_t j = dirs.size() * n; j < out.size(); ++j) EXPECT_EQ(out[j], sentinel);

  std::vector<float> flatf(flat.begin(), flat.end()), outf(dirs.size() * n);
  eval_sh_batch<float>(order, flatf, outf);
  std::vector<float> single(n);
  for (std::size_t k = 0; k < dirs.size(); ++k) {
    eval_sh<float>(order, Vec3<float>(flatf[3 * k], flatf[3 * k + 1], flatf[3 * k + 2]), single);
    for (int i = 0; i < n; ++i) ASSERT_EQ(outf[k * n + i], single[i]) << "dir " << k << " i " << i;
  }
}

TEST(ShReconstruct, EqualsDotProduct) {
  std::mt19937_64 rng(8);
  std::normal_distribution<double> gauss;
  for (int order : {1, 2, 3, 7, 16, 30}) {
    const int n = sh_count(order);
    std::vector<double> c(n);
    for (auto& ci : c) ci = gauss(rng);
    std::vector<float> cf(c.begin(), c.end());
    for (const auto& w : test_directions(30, order)) {
      const auto y = eval_d(order, w);
      double dot = 0, mag = 0;
      for (int i = 0; i < n; ++i) {
        dot += c[i] * y[i];
        mag += std::abs(c[i] * y[i]);
      }
      // Same terms, possibly different summation: a few ulp of sum |c_i y_i| per term.
      EXPECT_NEAR(reconstruct<double>(c, w), dot, 4e-16 * mag * std::sqrt(double(n)))
          << "order " << order << " w " << w.transpose();
      EXPECT_NEAR(double(reconstruct<float>(cf, w.cast<float>())), dot,
                  (1e-5 + 4e-7 * std::sqrt(double(n))) * mag)
          << "float order " << order << " w " << w.transpose();
    }
  }
}

TEST(ShAngles, DirectionFromAnglesAndStdSphLegendre) {
  // direction_from_angles(t, p) = (sin t cos p, sin t sin p, cos t), and at that direction
  // y_l^m = sqrt2 Y_lm(t) cos(m p) with libstdc++'s std::sph_legendre, which includes
  // the Condon-Shortley phase.
  const int order = 21;
  // No angles just off the poles here: std::sph_legendre forms sin t as sqrt(1 - cos^2 t),
  // which loses precision there (ShHighOrder covers near-pole directions).
  for (double t : {0.0, 0.4, kPi / 2, 2.2, kPi})
    for (double p : {0.0, 0.9, -1.3, 3.5}) {
      const Vec3<double> w = direction_from_angles(t, p);
      EXPECT_NEAR(w.x(), std::sin(t) * std::cos(p), 1e-16);
      EXPECT_NEAR(w.y(), std::sin(t) * std::sin(p), 1e-16);
      EXPECT_NEAR(w.z(), std::cos(t), 1e-16);
      EXPECT_NEAR(w.norm(), 1.0, 2.3e-16);
      const auto y = eval_d(order, w);
      for (int l = 0; l < order; ++l)
        for (int m = 0; m <= l; ++m) {
          const double s = std::sph_legendre(l, m, t);
          const double tol = 2e-14 * band_scale(l);  // ~l ulp for each implementation
          if (m == 0) {
            EXPECT_NEAR(y[sh_index(l, 0)], s, tol) << "l " << l << " t " << t;
          } else {
            EXPECT_NEAR(y[sh_index(l, m)], std::sqrt(2.0) * s * std::cos(m * p), tol)
                << "l " << l << " m " << m << " t " << t << " p " << p;
            EXPECT_NEAR(y[sh_index(l, -m)], std::sqrt(2.0) * s * std::sin(m * p), tol)
                << "l " << l << " m " << -m << " t " << t << " p " << p;
          }
        }
    }
  const Vec3<float> wf = direction_from_angles(0.5f, 1.5f);
  EXPECT_NEAR(wf.z(), std::cos(0.5f), 1e-7f);
}

TEST(ShAllocation, EvaluatorsDoNotAllocate) {
  const int order = kMaxOrder, n = sh_count(order);
  std::vector<double> v(n), g(3 * n), coeffs(n, 0.5), dirs = {0.6, 0.0, 0.8, 0.0, 1.0, 0.0};
  std::vector<double> batch(2 * n);
  std::vector<float> vf(n), gf(3 * n), cf(n, 0.5f);
  const Vec3<double> w(0.6, 0.0, 0.8);
  auto run_all = [&] {
    eval_sh<double>(order, w, v);
    eval_sh<float>(order, w.cast<float>(), vf);
    eval_sh_with_gradient<double>(order, w, v, g);
    eval_sh_with_gradient<float>(order, w.cast<float>(), vf, gf);
    eval_sh_batch<double>(order, dirs, batch);
    volatile double r = reconstruct<double>(coeffs, w);
    volatile float rf = reconstruct<float>(cf, w.cast<float>());
    (void)r;
    (void)rf;
  };
  run_all();  // first call builds the static recurrence tables (allowed to allocate once)
  g_allocations = 0;
  g_count_allocations = true;
  run_all();
  g_count_allocations = false;
  EXPECT_EQ(g_allocations.load(), 0);
  // The counter itself works (otherwise the check above could not fail).
  g_count_allocations = true;
  void* probe = ::operator new(64);  // a direct call, which the compiler may not elide
  g_count_allocations = false;
  EXPECT_GE(g_allocations.load(), 1);
  ::operator delete(probe);
}

}  // namespace
}  // namespace shtool
