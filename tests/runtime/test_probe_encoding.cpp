// The compact probe encodings (shtool/probe_encoding.h) against their published formulas,
// their exact cases, the least-squares property of the explicit ZH3 fit and the error
// ordering L1 >= ZH3 hallucinated >= ZH3 >= L2 over random non-negative lights.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "shtool/irradiance.h"
#include "shtool/probe_encoding.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

constexpr double kPi = std::numbers::pi;
using V = Vec3<double>;

// RGB radiance coefficients (order 3) of a light: ambient radiance per channel plus
// directional lights of radiance integral phi[c] along s (a delta projects exactly: phi y_i(s)).
struct Light {
  std::array<double, 3> ambient{};
  std::vector<std::pair<V, std::array<double, 3>>> deltas;

  std::vector<double> coefficients(int order = 3) const {
    std::vector<double> c(static_cast<std::size_t>(3 * order * order), 0.0);
    for (int k = 0; k < 3; ++k) c[k] = ambient[k] * std::sqrt(4 * kPi);
    std::vector<double> y(order * order);
    for (const auto& [s, phi] : deltas) {
      eval_sh<double>(order, s, y);
      for (int i = 0; i < order * order; ++i)
        for (int k = 0; k < 3; ++k) c[3 * i + k] += phi[k] * y[i];
    }
    return c;
  }
  // The exact irradiance, channel k.
  double irradiance(const V& n, int k) const {
    double e = kPi * ambient[k];
    for (const auto& [s, phi] : deltas) e += phi[k] * std::max(0.0, n.dot(s));
    return e;
  }
};

V unit(double x, double y, double z) { return V(x, y, z).normalized(); }

// The order-3 irradiance of RGB radiance coefficients, channel k (the exact band-limited one).
double l2_irradiance(const std::vector<double>& radiance, const V& n, int k) {
  std::vector<double> e(radiance.begin(), radiance.begin() + 27);
  radiance_to_irradiance(3, e);
  double y[9];
  eval_sh<double>(3, n, std::span<double>(y, 9));
  double sum = 0;
  for (int i = 0; i < 9; ++i) sum += e[3 * i + k] * y[i];
  return sum;
}

TEST(ProbeEncoding, NonLinearL1MatchesHazelsFormulaOnAWorkedCase) {
  // c00 = 2, d = (0.3, -0.2, 0.5), n = (0, 0.6, 0.8): Hazel's E/pi = R0 (a + (1 - a)(p + 1) q^p)
  // times pi, evaluated in 30-digit arithmetic (mpmath) from R0 = c00 / sqrt(4 pi), R1 = d / sqrt(12 pi).
  const double e = l1_nonlinear_irradiance<double>(2.0, V(0.3, -0.2, 0.5), V(0, 0.6, 0.8));
  EXPECT_NEAR(e, 2.05592144332811582787857334552, 1e-14);
  const float f = l1_nonlinear_irradiance<float>(2.0f, Vec3<float>(0.3f, -0.2f, 0.5f), Vec3<float>(0, 0.6f, 0.8f));
  EXPECT_NEAR(f, 2.0559214f, 2e-6f);
}

TEST(ProbeEncoding, NonLinearL1ReadsDFromTheShtoolBasis) {
  // d = (-c_11, -c_1-1, c_10): a delta along s gives d parallel to s, so the probe's
  // irradiance peaks at n = s. Checked along each axis, both signs.
  for (const V& s : {V(1, 0, 0), V(-1, 0, 0), V(0, 1, 0), V(0, -1, 0), V(0, 0, 1), V(0, 0, -1)}) {
    Light l;
    l.deltas.push_back({s, {1, 1, 1}});
    const L1Probe<double> p = encode_l1<double>(l.coefficients());
    EXPECT_NEAR((l1_vector(p, 0).normalized() - s).norm(), 0, 1e-15) << s.transpose();
  }
}

TEST(ProbeEncoding, NonLinearL1IsExactForAConstantLight) {
  Light l;
  l.ambient = {0.5, 1.0, 2.0};
  const L1Probe<double> p = encode_l1<double>(l.coefficients());
  for (const V& n : {unit(1, 2, 3), unit(-1, 0, 0), unit(0, 0, -1)})
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(l1_nonlinear_irradiance(p, n)[k], kPi * l.ambient[k], 1e-14);
}

TEST(ProbeEncoding, NonLinearL1IsExactForOneDirectionalLightAlongIt) {
  // r = 1, a = 0, p = 3: E(n) = phi ((1 + n . s) / 2)^3, phi at n = s, 0 at n = -s.
  const V s = unit(0.3, -0.5, 0.8);
  Light l;
  l.deltas.push_back({s, {3.0, 1.5, 0.25}});
  const L1Probe<double> p = encode_l1<double>(l.coefficients());
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(l1_nonlinear_irradiance(p, s)[k], l.deltas[0].second[k], 1e-13);
    EXPECT_NEAR(l1_nonlinear_irradiance(p, V(-s))[k], 0, 1e-13);
    const V n = unit(1, 1, 0);
    EXPECT_NEAR(l1_nonlinear_irradiance(p, n)[k], l.deltas[0].second[k] * std::pow((1 + n.dot(s)) / 2, 3), 1e-13);
  }
}

TEST(ProbeEncoding, NonLinearL1IsTheLinearIrradianceToFirstOrderInR) {
  // E = pi R0 + 2 pi R1 . n + O(r^2): with r = 1e-4 the difference is about r^2 pi R0.
  const double c00 = 1.0;
  const V d = 1e-4 * std::sqrt(12 * kPi) / std::sqrt(4 * kPi) * unit(1, -2, 0.5);  // |R1| / R0 = 1e-4
  for (const V& n : {unit(1, 2, 3), unit(0, 0, 1), unit(-1, 0.2, 0)}) {
    const double linear = kPi * c00 / std::sqrt(4 * kPi) + (2 * kPi / 3) * std::sqrt(3 / (4 * kPi)) * d.dot(n);
    EXPECT_NEAR(l1_nonlinear_irradiance(c00, d, n), linear, 1e-7) << n.transpose();
  }
}

TEST(ProbeEncoding, Zh3AxesAreLuminanceWeightedOrPerChannel) {
  L1Probe<double> p;
  // d_r = (1, 0, 0), d_g = (0, 1, 0), d_b = (0, 0, 1) through c_11 = -d_x, c_1-1 = -d_y, c_10 = d_z.
  p.coefficients = {1, 1, 1, 0, -1, 0, 0, 0, 1, -1, 0, 0};
  const V lum = V(0.2126, 0.7152, 0.0722).normalized();
  for (int c = 0; c < 3; ++c) {
    EXPECT_NEAR((zh3_axis(p, Zh3Axis::luminance, c) - lum).norm(), 0, 1e-15);
    EXPECT_NEAR((zh3_axis(p, Zh3Axis::per_channel, c) - V::Unit(c)).norm(), 0, 1e-15);
  }
  L1Probe<double> zero;
  EXPECT_EQ(zh3_axis(zero, Zh3Axis::luminance, 0), V(0, 0, 1));
}

TEST(ProbeEncoding, Zh3HallucinatedMatchesThePublishedCurve) {
  // Per-channel axis: r = |d| / c00 with c00 = 2, d = (0.3, -0.2, 0.5): f = c00 r (0.08 + 0.6 r)
  // = 0.163315312023751811602 (30-digit arithmetic).
  L1Probe<double> p;
  for (int c = 0; c < 3; ++c) {
    p.coefficients[c] = 2;
    p.coefficients[3 * 3 + c] = -0.3, p.coefficients[3 * 1 + c] = 0.2, p.coefficients[3 * 2 + c] = 0.5;
  }
  EXPECT_NEAR(zh3_hallucinated_zonal(p, Zh3Axis::per_channel, 1), 0.163315312023751811602, 1e-15);
  // Luminance axis of equal channels is the same axis.
  EXPECT_NEAR(zh3_hallucinated_zonal(p, Zh3Axis::luminance, 1), 0.163315312023751811602, 1e-15);
  // A black channel hallucinates nothing.
  L1Probe<double> black;
  EXPECT_EQ(zh3_hallucinated_zonal(black, Zh3Axis::luminance, 0), 0);
}

TEST(ProbeEncoding, Zh3ExplicitFitIsTheLeastSquaresZonalFit) {
  std::mt19937_64 rng(39);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<double> c(27);
    for (double& x : c) x = u(rng);
    c[0] = c[1] = c[2] = 3;
    for (Zh3Axis mode : {Zh3Axis::luminance, Zh3Axis::per_channel}) {
      const Zh3Probe<double> p = encode_zh3<double>(c, mode, Zh3Fit::explicit_fit);
      const std::array<double, 15> fitted = zh3_band2(p, mode);
      for (int k = 0; k < 3; ++k) {
        // The residual c_2 - f u (u = sqrt(4 pi / 5) y_2(a), |u| = 1) is orthogonal to u.
        double y[9];
        eval_sh<double>(3, zh3_axis(p.l1, mode, k), std::span<double>(y, 9));
        double dot = 0, res2 = 0;
        for (int m = 0; m < 5; ++m) {
          const double r = c[12 + 3 * m + k] - fitted[3 * m + k];
          dot += r * std::sqrt(4 * kPi / 5) * y[4 + m];
          res2 += r * r;
        }
        EXPECT_NEAR(dot, 0, 1e-14) << "trial " << trial << " channel " << k;
        // and any other f leaves a larger residual: |c - (f + e) u|^2 = |c - f u|^2 + e^2.
        double res2_shifted = 0;
        for (int m = 0; m < 5; ++m) {
          const double r = c[12 + 3 * m + k] - (p.zonal[k] + 0.01) * std::sqrt(4 * kPi / 5) * y[4 + m];
          res2_shifted += r * r;
        }
        EXPECT_NEAR(res2_shifted - res2, 1e-4, 1e-12);
      }
    }
  }
}

TEST(ProbeEncoding, Zh3IsExactForZonalLightOnItsL1Axis) {
  // A light rotationally symmetric about a (one delta plus ambient): band 2 is zonal along
  // the L1 axis, so the explicit ZH3 equals the order-3 irradiance at every normal.
  const V s = unit(-0.4, 0.2, 0.9);
  Light l;
  l.ambient = {0.1, 0.2, 0.3};
  l.deltas.push_back({s, {2, 1, 0.5}});
  const std::vector<double> c = l.coefficients();
  const Zh3Probe<double> p = encode_zh3<double>(c, Zh3Axis::luminance, Zh3Fit::explicit_fit);
  for (const V& n : {unit(1, 2, 3), s, unit(0, -1, 0), unit(-1, -1, -1)})
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(zh3_irradiance(p, Zh3Axis::luminance, n)[k], l2_irradiance(c, n, k), 1e-13);
  // E(n) = pi c00 y00 + (2 pi/3) k1 d.n + (pi/4) k20 f (3 (a.n)^2 - 1) with the published
  // constants, written out for one normal and channel.
  const V n = unit(1, 2, 3);
  const double y00 = 0.28209479177387814, k1 = 0.48860251190291992, k20 = 0.31539156525252001;
  const double t = s.dot(n);
  const double by_hand = kPi * y00 * c[0] + 2 * kPi / 3 * k1 * l1_vector(p.l1, 0).dot(n) +
                         kPi / 4 * k20 * p.zonal[0] * (3 * t * t - 1);
  EXPECT_NEAR(zh3_irradiance(p, Zh3Axis::luminance, n)[0], by_hand, 1e-14);
}

TEST(ProbeEncoding, Zh3IrradianceIsTheOrder3IrradianceOfItsBand2) {
  std::vector<double> c(27);
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-0.5, 0.5);
  for (double& x : c) x = u(rng);
  c[0] = 2, c[1] = 3, c[2] = 4;
  for (Zh3Fit fit : {Zh3Fit::explicit_fit, Zh3Fit::hallucinated})
    for (Zh3Axis mode : {Zh3Axis::luminance, Zh3Axis::per_channel}) {
      const Zh3Probe<double> p = encode_zh3<double>(c, mode, fit);
      std::vector<double> full(c.begin(), c.begin() + 12);
      const std::array<double, 15> b2 = zh3_band2(p, mode);
      full.insert(full.end(), b2.begin(), b2.end());
      for (const V& n : {unit(1, 2, 3), unit(0, -1, 0.2)})
        for (int k = 0; k < 3; ++k) EXPECT_NEAR(zh3_irradiance(p, mode, n)[k], l2_irradiance(full, n, k), 1e-13);
    }
}

TEST(ProbeEncoding, FloatFollowsDouble) {
  Light l;
  l.ambient = {0.2, 0.1, 0.05};
  l.deltas.push_back({unit(1, 0.5, 0.2), {2, 3, 1}});
  l.deltas.push_back({unit(-0.3, 0.2, -1), {0.5, 0.1, 1.5}});
  const std::vector<double> c = l.coefficients();
  const std::vector<float> cf(c.begin(), c.end());
  for (Zh3Fit fit : {Zh3Fit::explicit_fit, Zh3Fit::hallucinated}) {
    const Zh3Probe<double> p = encode_zh3<double>(c, Zh3Axis::luminance, fit);
    const Zh3Probe<float> pf = encode_zh3<float>(cf, Zh3Axis::luminance, fit);
    const V n = unit(0.2, 0.9, -0.1);
    const Vec3<float> nf = n.cast<float>();
    for (int k = 0; k < 3; ++k) {
      // float: a few ulps of the largest term (about 3)
      EXPECT_NEAR(zh3_irradiance(pf, Zh3Axis::luminance, nf)[k], zh3_irradiance(p, Zh3Axis::luminance, n)[k], 3e-6);
      EXPECT_NEAR(l1_nonlinear_irradiance(pf.l1, nf)[k], l1_nonlinear_irradiance(p.l1, n)[k], 3e-6);
    }
  }
}

// Relative RMS irradiance error of each encoding over the sphere of normals, against a
// reference irradiance of the light (exact, not its band-limited projection).
struct Errors {
  double l1 = 0, zh3_hallucinated = 0, zh3 = 0, l2 = 0;
  double l1_linear = 0;                     // bands 0 and 1 as plain SH
  double zh3_hallucinated_per_channel = 0;  // the other axis choice
};

template <class Reference>
Errors errors_of(const std::vector<double>& c, Reference reference, const SphereQuadrature& q) {
  const L1Probe<double> l1 = encode_l1<double>(c);
  const Zh3Probe<double> zh = encode_zh3<double>(c, Zh3Axis::luminance, Zh3Fit::explicit_fit);
  const Zh3Probe<double> zhh = encode_zh3<double>(c, Zh3Axis::luminance, Zh3Fit::hallucinated);
  const Zh3Probe<double> zhc = encode_zh3<double>(c, Zh3Axis::per_channel, Zh3Fit::hallucinated);
  std::vector<double> linear(c.begin(), c.begin() + 12);
  linear.resize(27, 0.0);
  Errors e;
  double norm = 0;
  for (std::size_t j = 0; j < q.directions.size(); ++j) {
    const V& n = q.directions[j];
    const double w = q.weights[j];
    const V a = l1_nonlinear_irradiance(l1, n), b = zh3_irradiance(zhh, Zh3Axis::luminance, n),
            z = zh3_irradiance(zh, Zh3Axis::luminance, n), hc = zh3_irradiance(zhc, Zh3Axis::per_channel, n);
    for (int k = 0; k < 3; ++k) {
      const double t = reference(n, k), l2 = l2_irradiance(c, n, k), lin = l2_irradiance(linear, n, k);
      e.l1_linear += w * (lin - t) * (lin - t);
      e.zh3_hallucinated_per_channel += w * (hc[k] - t) * (hc[k] - t);
      norm += w * t * t;
      e.l1 += w * (a[k] - t) * (a[k] - t);
      e.zh3_hallucinated += w * (b[k] - t) * (b[k] - t);
      e.zh3 += w * (z[k] - t) * (z[k] - t);
      e.l2 += w * (l2 - t) * (l2 - t);
    }
  }
  for (double* x : {&e.l1, &e.zh3_hallucinated, &e.zh3, &e.l2, &e.l1_linear, &e.zh3_hallucinated_per_channel})
    *x = std::sqrt(*x / norm);
  return e;
}

void accumulate(Errors& mean, const Errors& e, int count) {
  mean.l1 += e.l1 / count, mean.zh3_hallucinated += e.zh3_hallucinated / count;
  mean.zh3 += e.zh3 / count, mean.l2 += e.l2 / count;
  mean.l1_linear += e.l1_linear / count, mean.zh3_hallucinated_per_channel += e.zh3_hallucinated_per_channel / count;
}

void print(const char* what, int lights, const Errors& m) {
  std::printf("%s, mean relative RMS irradiance error over %d lights: L1 non-linear %.4f, L1 linear %.4f, ZH3 "
              "hallucinated %.4f (per-channel axes %.4f), ZH3 %.4f, L2 %.4f\n",
              what, lights, m.l1, m.l1_linear, m.zh3_hallucinated, m.zh3_hallucinated_per_channel, m.zh3, m.l2);
}

TEST(ProbeEncoding, ErrorOrderingOverRandomSmoothLights) {
  // 200 lights: a grey-ish ambient plus 1 to 4 clamped cosine-power lobes
  // P max(0, s . w)^p (p in 1..8, random colours and directions), the kind of light a probe
  // sees from skies, windows and lit walls. The probe gets the order-3 projection; the
  // reference is the order-16 irradiance (A_l |L_l| beyond band 15 is below 1e-5 of E). The
  // ordering is a property of averages (the paper compares over production probes), not of
  // every light. Measured (seed 2024): L1 non-linear 0.0726, L1 linear 0.1145, ZH3
  // hallucinated 0.0730, ZH3 0.0534, L2 0.0069. The hallucinated ZH3 beats linear L1 by a
  // third but only ties Geomerics' non-linear L1 (0.4% worse): that comparison is not
  // asserted; the others are.
  const SphereQuadrature q = sphere_quadrature(24);
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 1);
  const int lights = 200, order = 16;
  std::vector<double> a(order);
  for (int l = 0; l < order; ++l) a[l] = clamped_cosine_band(l);
  Errors mean;
  for (int t = 0; t < lights; ++t) {
    const double amb = 0.3 * u(rng);
    std::array<double, 3> ambient;
    for (int k = 0; k < 3; ++k) ambient[k] = amb * (0.5 + u(rng));
    struct Lobe {
      V s;
      int p;
      std::array<double, 3> power;
    };
    std::vector<Lobe> lobes(1 + static_cast<int>(u(rng) * 4));
    for (Lobe& l : lobes) {
      l.s = V(g(rng), g(rng), g(rng)).normalized();
      l.p = 1 + static_cast<int>(u(rng) * 8);
      const double power = 2 * u(rng);
      l.power = {power * (0.5 + u(rng)), power * (0.5 + u(rng)), power * (0.5 + u(rng))};
    }
    std::vector<std::vector<double>> high(3);
    for (int k = 0; k < 3; ++k) {
      high[k] = project_sh(
          order,
          [&](const V& w) {
            double v = ambient[k];
            for (const Lobe& l : lobes) v += l.power[k] * std::pow(std::max(0.0, l.s.dot(w)), l.p);
            return v;
          },
          48);
      for (int i = 0; i < order * order; ++i) high[k][i] *= a[sh_band(i)];
    }
    std::vector<double> c(27);
    for (int i = 0; i < 9; ++i)
      for (int k = 0; k < 3; ++k) c[3 * i + k] = high[k][i] / a[sh_band(i)];
    std::vector<double> y(order * order);
    const Errors e = errors_of(
        c,
        [&](const V& n, int k) {
          eval_sh<double>(order, n, y);
          double sum = 0;
          for (int i = 0; i < order * order; ++i) sum += high[k][i] * y[i];
          return sum;
        },
        q);
    accumulate(mean, e, lights);
  }
  print("smooth lights", lights, mean);
  EXPECT_GE(mean.l1_linear, mean.zh3_hallucinated);
  EXPECT_GE(mean.l1_linear, mean.l1);
  EXPECT_GE(mean.l1, mean.zh3);
  EXPECT_GE(mean.zh3_hallucinated, mean.zh3);
  EXPECT_GE(mean.zh3, mean.l2);
}

TEST(ProbeEncoding, ErrorsUnderDirectionalLights) {
  // 500 lights of ambient plus 1 to 4 directional lights (deltas, the extreme non-negative
  // light), with their exact irradiance. Here the hallucinated coefficient, fitted to
  // smooth production probes, does not beat the non-linear L1 (measured: 0.1215 against
  // 0.1175, linear L1 0.1540); what holds is that the explicit ZH3 beats every 4-number
  // encoding and L2 beats ZH3.
  const SphereQuadrature q = sphere_quadrature(24);
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> g(0, 1);
  Errors mean;
  const int lights = 500;
  for (int t = 0; t < lights; ++t) {
    Light l;
    const double amb = 0.3 * u(rng);
    for (int k = 0; k < 3; ++k) l.ambient[k] = amb * (0.5 + u(rng));
    const int count = 1 + static_cast<int>(u(rng) * 4);
    for (int i = 0; i < count; ++i) {
      const V s = V(g(rng), g(rng), g(rng)).normalized();
      const double power = u(rng);
      l.deltas.push_back({s, {power * (0.5 + u(rng)), power * (0.5 + u(rng)), power * (0.5 + u(rng))}});
    }
    accumulate(mean, errors_of(l.coefficients(), [&](const V& n, int k) { return l.irradiance(n, k); }, q), lights);
  }
  print("directional lights", lights, mean);
  EXPECT_GE(mean.l1_linear, mean.zh3_hallucinated);
  EXPECT_GE(mean.l1, mean.zh3);
  EXPECT_GE(mean.zh3_hallucinated, mean.zh3);
  EXPECT_GE(mean.zh3, mean.l2);
}

}  // namespace
}  // namespace shtool
