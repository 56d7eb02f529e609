// Gauss-Legendre and sphere quadrature (include/shtool/quadrature.h) against closed-form
// nodes and weights, exact monomial integrals, the known Gauss error term, and SH
// projection of band-limited and closed-form functions.
#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

using LD = long double;
constexpr double kPi = std::numbers::pi;
constexpr double kEps = 2.220446049250313e-16;

std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// ---------------------------------------------------------------------------
// Gauss-Legendre.

// Closed-form nodes and weights are O(1); a correctly rounded result is within 1/2 ulp,
// and Newton-polished values within ~2 ulp.
constexpr double kNodeTol = 4 * kEps;

TEST(GaussLegendre, ClosedFormsUpTo5) {
  struct Rule {
    std::vector<double> x, w;
  };
  const double s30 = std::sqrt(30.0), s70 = std::sqrt(70.0);
  const double x4a = std::sqrt(3.0 / 7 - 2.0 / 7 * std::sqrt(6.0 / 5));
  const double x4b = std::sqrt(3.0 / 7 + 2.0 / 7 * std::sqrt(6.0 / 5));
  const double x5a = std::sqrt(5 - 2 * std::sqrt(10.0 / 7)) / 3;
  const double x5b = std::sqrt(5 + 2 * std::sqrt(10.0 / 7)) / 3;
  const std::vector<Rule> rules = {
      {{0.0}, {2.0}},
      {{-1 / std::sqrt(3.0), 1 / std::sqrt(3.0)}, {1.0, 1.0}},
      {{-std::sqrt(0.6), 0.0, std::sqrt(0.6)}, {5.0 / 9, 8.0 / 9, 5.0 / 9}},
      {{-x4b, -x4a, x4a, x4b}, {(18 - s30) / 36, (18 + s30) / 36, (18 + s30) / 36, (18 - s30) / 36}},
      {{-x5b, -x5a, 0.0, x5a, x5b},
       {(322 - 13 * s70) / 900, (322 + 13 * s70) / 900, 128.0 / 225, (322 + 13 * s70) / 900,
        (322 - 13 * s70) / 900}},
  };
  for (int n = 1; n <= 5; ++n) {
    const GaussLegendre gl = gauss_legendre(n);
    ASSERT_EQ(gl.nodes.size(), std::size_t(n));
    ASSERT_EQ(gl.weights.size(), std::size_t(n));
    for (int i = 0; i < n; ++i) {
      EXPECT_NEAR(gl.nodes[i], rules[n - 1].x[i], kNodeTol) << "n " << n << " i " << i;
      EXPECT_NEAR(gl.weights[i], rules[n - 1].w[i], kNodeTol) << "n " << n << " i " << i;
    }
  }
}

// The reference for large n needs more than long double: at the outermost node of
// n = 200, P_{n-1} is ~6e-3 while the Bonnet recurrence near x = 1 carries ~n^2/6 ulp of
// noise, which in long double alone is ~3e-14 of the weight. Quad precision (113-bit)
// puts that noise far below double rounding.
#if defined(__SIZEOF_FLOAT128__) && LDBL_MANT_DIG < 113
using Quad = __float128;
#else
using Quad = long double;
#endif

void legendre_pair_quad(int n, Quad x, Quad& pn, Quad& pn1) {
  Quad p0 = 1, p1 = x;
  for (int k = 2; k <= n; ++k) {
    const Quad pk = (Quad(2 * k - 1) * x * p1 - Quad(k - 1) * p0) / Quad(k);
    p0 = p1;
    p1 = pk;
  }
  pn = p1;
  pn1 = n == 0 ? Quad(0) : p0;
}

TEST(GaussLegendre, NodesAreZerosAndWeightsMatchUpTo200) {
  // Independent check for larger n: Newton on P_n in quad precision from each node must
  // not move it by more than kNodeTol, and the weight must equal the other textbook form
  // w = 2 (1 - x^2) / (n P_{n-1}(x))^2 at that zero (the implementation uses
  // 2 / ((1-x^2) P_n'^2)); the header promises ~1 ulp, 8 ulp is asserted.
  constexpr double kWeightRelTol = 8 * kEps;
  double worst_x = 0, worst_w = 0;
  for (int n : {6, 7, 10, 17, 32, 50, 64, 99, 128, 200}) {
    const GaussLegendre gl = gauss_legendre(n);
    ASSERT_EQ(gl.nodes.size(), std::size_t(n));
    LD sum = 0;
    for (int i = 0; i < n; ++i) {
      Quad x = gl.nodes[i], pn, pn1;
      for (int it = 0; it < 4; ++it) {
        legendre_pair_quad(n, x, pn, pn1);
        const Quad dp = Quad(n) * (pn1 - x * pn) / (1 - x * x);
        x -= pn / dp;
      }
      legendre_pair_quad(n, x, pn, pn1);
      const Quad w = 2 * (1 - x * x) / ((Quad(n) * pn1) * (Quad(n) * pn1));
      const double ex = std::abs(double(x - Quad(gl.nodes[i])));
      const double ew = std::abs(double((w - Quad(gl.weights[i])) / w));
      worst_x = std::max(worst_x, ex);
      worst_w = std::max(worst_w, ew);
      EXPECT_LE(ex, kNodeTol) << "n " << n << " i " << i << " node " << gl.nodes[i];
      EXPECT_LE(ew, kWeightRelTol) << "n " << n << " i " << i << " w " << gl.weights[i]
                                   << " ref " << double(w);
      if (i > 0) {
        EXPECT_LT(gl.nodes[i - 1], gl.nodes[i]) << "n " << n << " i " << i;
      }
      EXPECT_EQ(gl.nodes[i], -gl.nodes[n - 1 - i]) << "n " << n << " i " << i;
      EXPECT_EQ(gl.weights[i], gl.weights[n - 1 - i]) << "n " << n << " i " << i;
      sum += gl.weights[i];
    }
    EXPECT_NEAR(double(sum), 2.0, n * kEps) << "n " << n;
  }
  RecordProperty("max_node_err", sci(worst_x));
  RecordProperty("max_weight_rel_err", sci(worst_w));
}

// Integral of x^k over [-1, 1] is 2/(k+1) for even k, 0 for odd k. Sums of n terms of
// size <= 2: n ulp of 2 bounds the rounding.
TEST(GaussLegendre, ExactUpToDegree2nMinus1AndNotAt2n) {
  for (int n = 1; n <= 40; ++n) {
    const GaussLegendre gl = gauss_legendre(n);
    for (int k = 0; k <= 2 * n; ++k) {
      double q = 0;
      for (int i = 0; i < n; ++i) q += gl.weights[i] * std::pow(gl.nodes[i], k);
      const double exact = k % 2 ? 0.0 : 2.0 / (k + 1);
      if (k <= 2 * n - 1) {
        EXPECT_NEAR(q, exact, 2 * n * kEps) << "n " << n << " x^" << k;
      } else {
        // Gauss error term for x^{2n}: E_n = 2^{2n+1} (n!)^4 / ((2n+1) ((2n)!)^2),
        // so the rule is short by exactly E_n (checked where E_n is above rounding).
        const LD log_e = (2 * n + 1) * std::log(2.0L) + 4 * std::lgamma(LD(n + 1)) -
                         std::log(LD(2 * n + 1)) - 2 * std::lgamma(LD(2 * n + 1));
        const double e = double(std::exp(log_e));
        if (e > 1e-10) {
          EXPECT_NEAR(exact - q, e, 2 * n * kEps + 1e-12 * e) << "n " << n << " x^" << k;
          EXPECT_GT(exact - q, 1e-11) << "n " << n << ": the rule must not be exact at 2n";
        }
      }
    }
  }
}

// ---------------------------------------------------------------------------
// Sphere quadrature.

// Integral over the unit sphere of x^a y^b z^c:
// 2 G((a+1)/2) G((b+1)/2) G((c+1)/2) / G((a+b+c+3)/2) when a, b, c are all even, else 0.
double sphere_monomial_integral(int a, int b, int c) {
  if (a % 2 || b % 2 || c % 2) return 0.0;
  const LD lg = std::lgamma((a + 1) / 2.0L) + std::lgamma((b + 1) / 2.0L) +
                std::lgamma((c + 1) / 2.0L) - std::lgamma((a + b + c + 3) / 2.0L);
  return double(2 * std::exp(lg));
}

// Integrates x^a y^b z^c for a + b + c <= max_degree with the rule, accumulated in long
// double so that what is measured is the rule (nodes and weights as stored), not the
// rounding of a sum over hundreds of points. Powers are tabulated once per point.
struct MonomialIntegrator {
  int max_degree;
  std::vector<LD> px, py, pz, wt;  // [k * (max_degree + 1) + e]
  MonomialIntegrator(const SphereQuadrature& q, int max_deg) : max_degree(max_deg) {
    const int e = max_degree + 1;
    px.resize(q.directions.size() * e);
    py.resize(px.size());
    pz.resize(px.size());
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
      px[k * e] = py[k * e] = pz[k * e] = 1;
      for (int j = 1; j < e; ++j) {
        px[k * e + j] = px[k * e + j - 1] * q.directions[k].x();
        py[k * e + j] = py[k * e + j - 1] * q.directions[k].y();
        pz[k * e + j] = pz[k * e + j - 1] * q.directions[k].z();
      }
      wt.push_back(q.weights[k]);
    }
  }
  double operator()(int a, int b, int c) const {
    const int e = max_degree + 1;
    LD s = 0;
    for (std::size_t k = 0; k < wt.size(); ++k) s += wt[k] * px[k * e + a] * py[k * e + b] * pz[k * e + c];
    return double(s);
  }
};

TEST(SphereQuadrature, ExactForMonomialsUpToDegreeAndNotBeyond) {
  // Values are <= 4 pi and the rule has ~degree^2/2 points; 1e-14 is ~10 ulp of 4 pi,
  // above the rounding of these sums (measured below 3e-15).
  constexpr double kMonomialTol = 1e-14;
  double worst = 0;
  for (int degree = 0; degree <= 24; ++degree) {
    const SphereQuadrature q = sphere_quadrature(degree);
    ASSERT_EQ(q.directions.size(), q.weights.size());
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
      EXPECT_NEAR(q.directions[k].norm(), 1.0, 2 * kEps) << "degree " << degree << " k " << k;
      EXPECT_GT(q.weights[k], 0.0);
    }
    const MonomialIntegrator integrate(q, degree + 1);
    for (int a = 0; a <= degree; ++a)
      for (int b = 0; a + b <= degree; ++b)
        for (int c = 0; a + b + c <= degree; ++c) {
          const double got = integrate(a, b, c);
          const double ref = sphere_monomial_integral(a, b, c);
          worst = std::max(worst, std::abs(got - ref));
          EXPECT_NEAR(got, ref, kMonomialTol) << "degree " << degree << " x^" << a << " y^" << b
                                              << " z^" << c;
        }
    // One degree more is not integrated: x^{degree+1} puts a cos((degree+1) p) term on
    // the degree+1 equally spaced azimuths, where it aliases to a constant.
    const double got = integrate(degree + 1, 0, 0);
    const double ref = sphere_monomial_integral(degree + 1, 0, 0);
    // (The aliased term shrinks like 2^-degree: 6e-5 at degree 16, still 1e5 x rounding.)
    EXPECT_GT(std::abs(got - ref), 1e-9) << "degree " << degree << " got " << got << " ref " << ref;
  }
  RecordProperty("max_abs_err", sci(worst));
}

// Random band-limited f (order Na) and g (order Nb): the integral of f g is the dot
// product of the coefficients when Na - 1 + Nb - 1 <= degree.
TEST(SphereQuadrature, IntegratesBandLimitedProducts) {
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> gauss;
  for (auto [na, nb] : {std::pair{1, 1}, {3, 5}, {8, 8}, {12, 7}, {20, 20}}) {
    const int degree = na + nb - 2;
    const SphereQuadrature q = sphere_quadrature(degree);
    const int n = sh_count(std::max(na, nb));
    std::vector<double> a(sh_count(na)), b(sh_count(nb));
    for (auto& v : a) v = gauss(rng);
    for (auto& v : b) v = gauss(rng);
    double exact = 0, mag = 0;
    for (int i = 0; i < std::min(sh_count(na), sh_count(nb)); ++i) {
      exact += a[i] * b[i];
      mag += std::abs(a[i] * b[i]);
    }
    double got = 0;
    std::vector<double> y(n);
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
      eval_sh<double>(std::max(na, nb), q.directions[k], y);
      double f = 0, g = 0;
      for (int i = 0; i < sh_count(na); ++i) f += a[i] * y[i];
      for (int i = 0; i < sh_count(nb); ++i) g += b[i] * y[i];
      got += q.weights[k] * f * g;
    }
    // |f|, |g| <= sqrt(sum coeff^2) * sqrt(N^2/(4 pi)); rounding scales with N^2 |a||b|.
    const double tol = 1e-14 * n * (1 + mag);
    EXPECT_NEAR(got, exact, tol) << "Na " << na << " Nb " << nb;
  }
}

// ---------------------------------------------------------------------------
// Projection.

TEST(ProjectSh, RecoversRandomBandLimitedCoefficients) {
  // 1e-13 absolute on O(1) coefficients: the Gram matrix is the identity to ~1e-14 at
  // N = 20 (test_sh ShOrthonormality), times sum |c| / |c| ~ N.
  constexpr double kProjectTol = 1e-13;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> gauss;
  double worst = 0;
  for (int order = 1; order <= 20; ++order) {
    std::vector<double> c(sh_count(order));
    for (auto& v : c) v = gauss(rng);
    const auto f = [&c](const Vec3<double>& w) { return reconstruct<double>(c, w); };
    const std::vector<double> got = project_sh(order, f);
    ASSERT_EQ(got.size(), c.size());
    for (std::size_t i = 0; i < c.size(); ++i) {
      worst = std::max(worst, std::abs(got[i] - c[i]));
      EXPECT_NEAR(got[i], c[i], kProjectTol) << "order " << order << " i " << i;
    }
    // Projecting onto more bands than f has gives zeros there (the rule grows to match).
    const std::vector<double> wider = project_sh(order + 3, f);
    ASSERT_EQ(wider.size(), std::size_t(sh_count(order + 3)));
    for (std::size_t i = 0; i < wider.size(); ++i)
      EXPECT_NEAR(wider[i], i < c.size() ? c[i] : 0.0, kProjectTol) << "order " << order << " i " << i;
  }
  RecordProperty("max_abs_err", sci(worst));
}

TEST(ProjectSh, PolynomialClosedForm) {
  // f = xyz + z^2: xyz = y_3^{-2} / sqrt(105/(4 pi)), z^2 = 1/3 + (2/3) P_2(z), so
  // f_0 = 2 sqrt(pi)/3, f_{2,0} = (2/3) sqrt(4 pi/5), f_{3,-2} = sqrt(4 pi/105), rest 0.
  const auto f = [](const Vec3<double>& w) { return w.x() * w.y() * w.z() + w.z() * w.z(); };
  const std::vector<double> got = project_sh(5, f);
  std::vector<double> ref(25, 0.0);
  ref[0] = 2 * std::sqrt(kPi) / 3;
  ref[sh_index(2, 0)] = 2.0 / 3 * std::sqrt(4 * kPi / 5);
  ref[sh_index(3, -2)] = std::sqrt(4 * kPi / 105);
  for (int i = 0; i < 25; ++i) EXPECT_NEAR(got[i], ref[i], 1e-15) << "i " << i;
}

// Clamped cosine max(z, 0): zonal, with f_l = 2 pi sqrt((2l+1)/(4 pi)) int_0^1 z P_l(z) dz:
// sqrt(pi)/2, sqrt(pi/3), then for even l >= 2
// int_0^1 z P_l = (-1)^{l/2+1} (l-2)! / (2^l (l/2-1)! (l/2+1)!)  (l = 2: 1/8, so sqrt(5 pi)/8),
// and 0 for odd l >= 3.
double clamped_cosine_coefficient(int l) {
  if (l == 0) return std::sqrt(kPi) / 2;
  if (l == 1) return std::sqrt(kPi / 3);
  if (l % 2) return 0.0;
  const int h = l / 2;
  const LD moment = (h % 2 ? 1 : -1) *
                    std::exp(std::lgamma(LD(l - 1)) - l * std::log(2.0L) - std::lgamma(LD(h)) -
                             std::lgamma(LD(h + 2)));
  return double(2 * kPi * std::sqrt((2 * l + 1) / (4 * kPi)) * moment);
}

TEST(ProjectSh, ClampedCosineClosedForm) {
  EXPECT_NEAR(clamped_cosine_coefficient(2), std::sqrt(5 * kPi) / 8, 1e-16);
  // The kink at z = 0 makes the Gauss error fall only like 1/n^2 in the number n of
  // z nodes: measured 2.0e-5 at n = 204 and 1.04e-6 at n = 1253 (odd n, a node on the
  // kink, has the larger constant). exact_order 2502 gives n = 1254 and ~5e-7, under
  // the 1e-6 asked for.
  constexpr double kClampedTol = 1e-6;
  const int order = 6;
  const auto f = [](const Vec3<double>& w) { return std::max(w.z(), 0.0); };
  const std::vector<double> got = project_sh(order, f, 2502);
  double worst = 0;
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) {
      const double ref = m == 0 ? clamped_cosine_coefficient(l) : 0.0;
      worst = std::max(worst, std::abs(got[sh_index(l, m)] - ref));
      EXPECT_NEAR(got[sh_index(l, m)], ref, kClampedTol) << "l " << l << " m " << m;
    }
  RecordProperty("max_abs_err", sci(worst));
  // A small rule is visibly worse, so the test above measures the projection.
  const std::vector<double> coarse = project_sh(order, f, order);
  EXPECT_GT(std::abs(coarse[sh_index(2, 0)] - clamped_cosine_coefficient(2)), 1e-5);
}

}  // namespace
}  // namespace shtool
