// SH <-> Fourier tensors and the Fourier-space products ([3] Sec. 3.2, 4):
// tensors against independent constructions (sampling + discrete cosine/sine sums,
// Gauss-Legendre projections) up to l = 40, the orthonormality identity that ties the two
// tensors together, products against the SH projection of the pointwise product by
// quadrature (N up to 20, k up to 8), the recursive approximation's Table 1 magnitude,
// determinism, table round trip.
#include <cmath>
#include <cstdio>
#include <string>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include <gtest/gtest.h>

#include "table_test_util.h"

#include "tensors/fourier_tables.h"
#include "test_util.h"
#include "shtool/fourier_product.h"
#include "shtool/fourier_tensors.h"
#include "shtool/legendre.h"
#include "shtool/product.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"
#include "shtool/tripling_product.h"

namespace shtool {
namespace {

using namespace test;

// The required accuracy for accurate products in double: 1e-10 relative.
constexpr double kProductTolDouble = 1e-10;
// float: 24-bit mantissa, errors grow with the number of inputs and the FFT length.
constexpr double kProductTolFloat = 1e-4;
// Tensor entries: values O(1), built in long double, checked against identities and
// Gauss-Legendre sums of double Legendre values.
constexpr double kTensorTol = 1e-14;
// Against the sampled transform: double-precision samples (|Theta| up to ~4 at l = 40,
// a few ulp each) summed over J + 1 = 43 points.
constexpr double kSampledTol = 2e-14;  // measured 9e-15; the unstable coefficient-space
                                       // recurrence gave 5e-14 at l = 35, 3e-13 at l = 39

// Theta_l^m(t) = sqrt(2 pi) K P_l^m(cos t), from the project's Legendre evaluator.
double theta_fn(int l, int m, double t) {
  return std::sqrt(2.0 * std::numbers::pi) * normalized_legendre(l, m, t);
}

TEST(ShFourierTensors, ToFourierMatchesSampledTransform) {
  // Independent route: sample Theta at J + 1 equispaced t in [0, pi] and take the
  // discrete cosine (even m) or sine (odd m) transform, exact for degree < J.
  const int order = 41;
  const ShFourierTensors t = ShFourierTensors::compute(order, order - 1);
  const int J = order + 1;
  const long double pi = std::numbers::pi_v<long double>;
  double worst = 0;
  for (int l = 0; l < order; ++l)
    for (int m = 0; m <= l; ++m) {
      std::vector<long double> f(J + 1);
      for (int j = 0; j <= J; ++j) f[j] = theta_fn(l, m, static_cast<double>(pi * j / J));
      for (int s = 0; s <= l; ++s) {
        long double c = 0;
        if (m % 2 == 0) {
          for (int j = 0; j <= J; ++j)
            c += ((j == 0 || j == J) ? 0.5L : 1.0L) * f[j] * std::cos(pi * s * j / J);
          c *= (s == 0 ? 1.0L : 2.0L) / J;
        } else {
          for (int j = 1; j < J; ++j) c += f[j] * std::sin(pi * s * j / J);
          c *= 2.0L / J;
        }
        const double err = std::abs(static_cast<double>(c) - t.fourier(l, m, s));
        worst = std::max(worst, err);
        ASSERT_LT(err, kSampledTol) << "l " << l << " m " << m << " s " << s << ": tensor "
                                   << t.fourier(l, m, s) << " sampled " << static_cast<double>(c);
      }
    }
  RecordProperty("max_abs_error", sci(worst));
}

TEST(ShFourierTensors, ToShMatchesGaussLegendre) {
  // integral_0^pi trig(s t) Theta_l^m(t) sin t dt; the integrand is a polynomial of degree
  // <= s + l in x = cos t (times sin^2 for odd m, whose Theta carries one sin t), so a
  // Gauss rule with enough nodes is exact.
  const int order = 31, degree = 90;
  const ShFourierTensors t = ShFourierTensors::compute(order, degree);
  const GaussLegendre gl = gauss_legendre((degree + order) / 2 + 2);
  for (int l = 0; l < order; l += 3)
    for (int m = 0; m <= l; m += 2 + l % 2)
      for (int s = 0; s <= degree; s += 7) {
        long double sum = 0;
        for (std::size_t q = 0; q < gl.nodes.size(); ++q) {
          const double th = std::acos(gl.nodes[q]);
          const double trig = m % 2 == 0 ? std::cos(s * th) : std::sin(s * th);
          sum += gl.weights[q] * trig * theta_fn(l, m, th);
        }
        ASSERT_NEAR(t.projection(l, m, s), static_cast<double>(sum), kTensorTol)
            << "l " << l << " m " << m << " s " << s;
      }
}

TEST(ShFourierTensors, OrthonormalityIdentity) {
  // integral Theta_l Theta_l' sin t = sum_s to_fourier[l'][m][s] to_sh[l][m][s] = delta.
  const int order = 31;
  const ShFourierTensors t = ShFourierTensors::compute(order, order - 1);
  for (int m = 0; m < order; ++m)
    for (int l = m; l < order; ++l)
      for (int lp = m; lp < order; ++lp) {
        long double sum = 0;
        for (int s = 0; s < order; ++s) sum += t.fourier(lp, m, s) * t.projection(l, m, s);
        ASSERT_NEAR(static_cast<double>(sum), l == lp ? 1.0 : 0.0, 1e-14)
            << "m " << m << " l " << l << " l' " << lp;
      }
}

TEST(ShFourierTensors, TableRoundTripAndCorruption) {
  const ShFourierTensors t = ShFourierTensors::compute(6, 35);
  const Table table = to_table(t, {{"tool", "test"}});
  const auto back = ShFourierTensors::from_table(table);
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back.value().degree, 35);
  EXPECT_EQ(back.value().to_fourier, t.to_fourier);
  EXPECT_EQ(back.value().to_sh, t.to_sh);
  Table bad = table;
  std::vector<double> v = t.to_fourier;
  v[(1 * 6 + 0) * 6 + 0] = 0.25;  // l = 1, m = 0, s = 0: parity says zero
  bad.arrays[0] = TableArray::from<double>("to_fourier", {6, 6, 6}, v);
  const auto r = ShFourierTensors::from_table(bad);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("reduced layout"), std::string::npos) << r.error().message;
  bad = table;
  bad.kind = "tripling-tensor";
  EXPECT_FALSE(ShFourierTensors::from_table(bad).ok());
}

struct Case {
  int order, inputs;
};

TEST(FourierProduct, AccurateAgainstQuadratureDouble) {
  // k = inputs + 1 up to 8, N up to 20; a few combinations keep the run short.
  for (const Case c : {Case{1, 2}, Case{2, 7}, Case{3, 2}, Case{4, 3}, Case{6, 5}, Case{10, 2},
                       Case{10, 7}, Case{13, 4}, Case{20, 2}, Case{20, 3}, Case{20, 7}}) {
    const auto f = random_inputs(c.order, c.inputs, 100 + c.order * 10 + c.inputs);
    const std::vector<double> ref = reference_product(c.order, f);
    FourierProduct<double> product(c.order, c.inputs);
    std::vector<std::span<const double>> spans(f.begin(), f.end());
    std::vector<double> g(sh_count(c.order));
    product.multiply(spans, g);
    const double err = relative_l2(g, ref);
    EXPECT_LT(err, kProductTolDouble) << "N " << c.order << " k " << c.inputs + 1;
    RecordProperty("rel_l2_N" + std::to_string(c.order) + "_k" + std::to_string(c.inputs + 1),
                   sci(err));
  }
}

TEST(FourierProduct, AccurateAgainstQuadratureFloat) {
  for (const Case c : {Case{5, 2}, Case{12, 3}, Case{20, 7}}) {
    const auto f = random_inputs(c.order, c.inputs, 7 + c.order);
    const std::vector<double> ref = reference_product(c.order, f);
    std::vector<std::vector<float>> ff(c.inputs);
    for (int i = 0; i < c.inputs; ++i) ff[i].assign(f[i].begin(), f[i].end());
    FourierProduct<float> product(c.order, c.inputs);
    std::vector<std::span<const float>> spans(ff.begin(), ff.end());
    std::vector<float> g(sh_count(c.order));
    product.multiply(spans, g);
    EXPECT_LT(relative_l2(g, ref), kProductTolFloat) << "N " << c.order << " k " << c.inputs + 1;
  }
}

TEST(FourierProduct, MatchesTriplingTensorAndAliasing) {
  const int order = 12;
  const auto f = random_inputs(order, 2, 5);
  const TriplingProduct<double> tripling(TriplingTensor::compute(order));
  std::vector<double> a(sh_count(order)), b = f[0];
  tripling.multiply(f[0], f[1], a);
  FourierProduct<double> fourier(order, 2);
  fourier.multiply(b, f[1], b);  // output aliases the first input
  for (int i = 0; i < sh_count(order); ++i) ASSERT_NEAR(a[i], b[i], 1e-13) << "coefficient " << i;
}

// Spans shorter than N^2 are a checked precondition: std::invalid_argument naming the
// call and the span, never a read or write past the end (a generated kernel included).
TEST(FourierProduct, ShortSpansAreRefused) {
  for (const int order : {3, 12}) {  // order 3 runs a generated tripling kernel
    const int n = sh_count(order);
    const std::vector<double> f(n, 0.5), short_f(n - 1, 0.5);
    std::vector<double> g(n), short_g(n - 1);
    const TriplingProduct<double> tripling(TriplingTensor::compute(order));
    EXPECT_THROW(tripling.multiply(short_f, f, g), std::invalid_argument) << order;
    EXPECT_THROW(tripling.multiply(f, short_f, g), std::invalid_argument) << order;
    EXPECT_THROW(tripling.multiply(f, f, short_g), std::invalid_argument) << order;
    EXPECT_THROW(tripling.integral(f, f, short_f), std::invalid_argument) << order;
    FourierProduct<double> fourier(order, 2);
    EXPECT_THROW(fourier.multiply(f, short_f, g), std::invalid_argument) << order;
    EXPECT_THROW(fourier.multiply(f, f, short_g), std::invalid_argument) << order;
    const std::span<const double> one[1] = {f};
    EXPECT_THROW(fourier.multiply(std::span<const std::span<const double>>(one, 1), g), std::invalid_argument);
    try {
      tripling.multiply(f, f, short_g);
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("TriplingProduct::multiply: g holds " + std::to_string(n - 1) + " values, " +
                                           std::to_string(n) + " needed"),
                std::string::npos)
          << e.what();
    }
    // Longer spans are fine: the first N^2 values are used.
    std::vector<double> long_g(n + 5, 7.0);
    tripling.multiply(f, f, long_g);
    EXPECT_EQ(long_g[n], 7.0);
  }
}

// triple() calls the generated kernel directly at orders 2..6 (tripling method) and must
// still allow g to alias an input: every method, orders with and without a kernel, each
// input aliased in turn, against the product into a separate output.
TEST(ShProduct, TripleOutputMayAliasAnInput) {
  for (const int order : {3, 6, 7}) {
    const auto f = random_inputs(order, 2, 31 + order);
    const std::vector<double> ref = reference_product(order, f);
    for (ProductMethod m : {ProductMethod::tripling, ProductMethod::grid, ProductMethod::automatic}) {
      ShProduct<double> product(order, m);
      std::vector<double> separate(sh_count(order)), a = f[0], b = f[1];
      product.triple(f[0], f[1], separate);
      product.triple(a, f[1], a);
      product.triple(f[0], b, b);
      for (int i = 0; i < sh_count(order); ++i) {
        ASSERT_NEAR(separate[i], ref[i], 1e-14) << "N " << order << " coefficient " << i;
        ASSERT_EQ(a[i], separate[i]) << "N " << order << " first input aliased, coefficient " << i;
        ASSERT_EQ(b[i], separate[i]) << "N " << order << " second input aliased, coefficient " << i;
      }
    }
  }
}

TEST(ShProduct, IntegralAndMethodsAgree) {
  const int order = 9;
  const auto f = random_inputs(order, 3, 21);
  const std::vector<double> ref = reference_product(order, {f[0], f[1]});
  double expected = 0;
  for (int i = 0; i < sh_count(order); ++i) expected += ref[i] * f[2][i];
  for (ProductMethod m : {ProductMethod::tripling, ProductMethod::fourier, ProductMethod::grid,
                          ProductMethod::automatic}) {
    ShProduct<double> product(order, m);
    EXPECT_NEAR(product.triple_integral(f[0], f[1], f[2]), expected, 1e-12 * std::abs(expected) + 1e-14);
    std::vector<double> g(sh_count(order));
    product.triple(f[0], f[1], g);
    EXPECT_LT(relative_l2(g, ref), 1e-13) << "method " << static_cast<int>(m);
  }
  EXPECT_EQ(ShProduct<double>(kGridTripleFromOrder - 1).triple_method(), ProductMethod::tripling);
  EXPECT_EQ(ShProduct<double>(kGridTripleFromOrder).triple_method(), ProductMethod::grid);
  EXPECT_EQ(ShProduct<double>(kMaxTriplingOrder + 1).triple_method(), ProductMethod::grid);
  EXPECT_EQ(ShProduct<double>(5, ProductMethod::fourier).triple_method(), ProductMethod::fourier);
}

TEST(ShProduct, MultipleByGridAndFourierAgainstQuadrature) {
  // Accurate k-multiple products through the public entry point: the grid (default) and
  // the Fourier method (ProductMethod::fourier) both match the quadrature reference.
  for (const Case c : {Case{4, 3}, Case{9, 5}, Case{15, 7}}) {
    const auto f = random_inputs(c.order, c.inputs, 500 + c.order);
    const std::vector<double> ref = reference_product(c.order, f);
    std::vector<std::span<const double>> spans(f.begin(), f.end());
    for (ProductMethod m : {ProductMethod::automatic, ProductMethod::grid, ProductMethod::fourier,
                            ProductMethod::tripling}) {
      ShProduct<double> product(c.order, m);
      std::vector<double> g(sh_count(c.order));
      product.multiple(spans, g);
      EXPECT_LT(relative_l2(g, ref), kProductTolDouble)
          << "N " << c.order << " k " << c.inputs + 1 << " method " << static_cast<int>(m);
    }
  }
}

TEST(ShProduct, Deterministic) {
  // Same inputs, fresh objects: bit-identical results (FFTW_ESTIMATE plans).
  const auto f = random_inputs(11, 5, 9);
  std::vector<std::span<const double>> spans(f.begin(), f.end());
  std::vector<double> g1(sh_count(11)), g2(sh_count(11));
  ShProduct<double>(11).multiple(spans, g1);
  ShProduct<double>(11).multiple(spans, g2);
  EXPECT_EQ(g1, g2);
}

TEST(ShProduct, RecursiveMatchesTwoStepQuadrature) {
  // Eq. 11 for three inputs is P_N(P_N(F1 F2) F3), with P_N the projection onto order N:
  // computed here by quadrature, independently of both product methods.
  const int order = 5;
  const auto f = random_inputs(order, 3, 77);
  const std::vector<double> step1 = reference_product(order, {f[0], f[1]});
  const std::vector<double> step2 = reference_product(order, {step1, f[2]});
  for (ProductMethod m : {ProductMethod::tripling, ProductMethod::fourier, ProductMethod::grid}) {
    ShProduct<double> product(order, m);
    std::vector<std::span<const double>> spans(f.begin(), f.end());
    std::vector<double> g(sh_count(order));
    product.recursive(spans, g);
    EXPECT_LT(relative_l2(g, step2), 1e-13);
  }
}

TEST(ShProduct, RecursiveApproximationTable1Magnitude) {
  // [3] Table 1: error of the recursive triple-product approximation (Eq. 11)
  // against the accurate product, coefficients uniform in [-1, 1]: 0.21-0.25 for k = 4
  // and 0.87-0.89 for k = 8, flat in N. Measured here (docs/products.md, "Recursive
  // approximation") with e = sqrt(sum ||g_rec - g||^2 / sum ||g||^2) over 200 groups:
  // 0.44-0.45 for k = 4, 0.88-0.89 for k = 8, also flat in N. k = 8 reproduces the table;
  // k = 4 is the same magnitude but twice the paper's value (its square, 0.20, would
  // match; the paper does not define the measure). The bounds bracket our values with a
  // margin above the spread between seeds (+-0.03 at 200 groups) and keep the paper's
  // order of magnitude; they are a documented check, not fitted constants.
  struct Row {
    int inputs;
    double lo, hi;
  };
  for (const Row row : {Row{3, 0.35, 0.55}, Row{7, 0.78, 0.98}})
    for (int order : {5, 10}) {
      ShProduct<double> tripling(order, ProductMethod::tripling);
      ShProduct<double> fourier(order, ProductMethod::fourier);
      double err2 = 0, ref2 = 0;
      const int groups = 200;
      for (int trial = 0; trial < groups; ++trial) {
        const auto f = random_inputs(order, row.inputs, 1000 + trial);
        std::vector<std::span<const double>> spans(f.begin(), f.end());
        std::vector<double> exact(sh_count(order)), rec_t(sh_count(order)), rec_f(sh_count(order));
        fourier.multiple(spans, exact);
        tripling.recursive(spans, rec_t);
        fourier.recursive(spans, rec_f);
        // Both methods give the same approximation (paper Sec. 4.5).
        for (int i = 0; i < sh_count(order); ++i)
          ASSERT_NEAR(rec_t[i], rec_f[i], 1e-11 * (1 + std::abs(rec_t[i])));
        for (int i = 0; i < sh_count(order); ++i) {
          err2 += (rec_t[i] - exact[i]) * (rec_t[i] - exact[i]);
          ref2 += exact[i] * exact[i];
        }
      }
      const double plain = std::sqrt(err2 / ref2), squared = err2 / ref2;
      const std::string what = "N " + std::to_string(order) + " k " + std::to_string(row.inputs + 1) +
                               ": plain " + sci(plain) + " squared " + std::to_string(squared);
      EXPECT_GT(plain, row.lo) << what;
      EXPECT_LT(plain, row.hi) << what;
      RecordProperty("recursive_N" + std::to_string(order) + "_k" + std::to_string(row.inputs + 1),
                     sci(plain));
      std::printf("recursive approximation %s\n", what.c_str());
    }
}

}  // namespace
}  // namespace shtool
