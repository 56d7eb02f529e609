// Light-specialized ZH shading ([4] Eq. 24-25). References: the addition theorem
// (std::legendre), zh_lobe_dot_sh, a quadrature integral of lobe times light, the
// reference SH rotation, and the exact band sums for the tabulated path.
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <new>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "shtool/euler.h"
#include "shtool/quadrature.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "shtool/zh.h"
#include "shtool/zh_shading.h"
#include "test_util.h"

#include "allocation_counter.h"  // counts this program's allocations

namespace {

using namespace shtool;
using shtool::test::sci;
using shtool::test::Lcg;

constexpr double kPi = std::numbers::pi;
constexpr int kOrder = 6;

std::vector<double> random_coeffs(Lcg& rng, int count) {
  std::vector<double> c(count);
  for (double& x : c) x = 2 * rng.uniform() - 1;
  return c;
}

// Largest |e^_l(s)| can be: sqrt(sum_m y_l^m(s)^2) |e_l| = sqrt((2l+1)/(4 pi)) |e_l|
// (Cauchy-Schwarz with the addition theorem); table errors are measured against it.
std::vector<double> band_scales(const std::vector<double>& light, int order) {
  std::vector<double> s(order);
  for (int l = 0; l < order; ++l) {
    double n = 0;
    for (int m = -l; m <= l; ++m) n += light[sh_index(l, m)] * light[sh_index(l, m)];
    s[l] = std::sqrt((2 * l + 1) / (4 * kPi) * n);
  }
  return s;
}

// Test directions: random, plus the special points of the cube map (face centres, edge
// midpoints, corners, and points just either side of an edge).
std::vector<Eigen::Vector3d> test_directions(int random_count) {
  Lcg rng{99};
  std::vector<Eigen::Vector3d> d;
  for (int i = 0; i < random_count; ++i) d.push_back(rng.unit());
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int c = -1; c <= 1; ++c)
        if (a || b || c) d.push_back(Eigen::Vector3d(a, b, c).normalized());
  d.push_back(Eigen::Vector3d(1, 1 + 1e-12, 0.3).normalized());
  d.push_back(Eigen::Vector3d(1 + 1e-12, 1, 0.3).normalized());
  return d;
}

// Worst table error per band over the directions, relative to the band scale.
std::vector<double> table_band_errors(const ZhLightTable<double>& table, const std::vector<double>& light,
                                      const std::vector<Eigen::Vector3d>& dirs) {
  const int order = table.order();
  const std::vector<double> scale = band_scales(light, order);
  std::vector<double> worst(order, 0.0), got(order), want(order);
  for (const Eigen::Vector3d& s : dirs) {
    table.lookup(s, got);
    zh_light_bands<double>(light, s, want);
    for (int l = 0; l < order; ++l) worst[l] = std::max(worst[l], std::abs(got[l] - want[l]) / scale[l]);
  }
  return worst;
}

// --- exact path -----------------------------------------------------------------------

// A light that is itself one ZH lobe along d with coefficients c_l has band sums
// e^_l(s) = c_l (2l+1)/(4 pi) P_l(s . d) by the addition theorem: an independent
// reference through std::legendre.
TEST(ZhShadingExact, BandSumsOfAZonalLightFollowTheAdditionTheorem) {
  // Rounding of an order-6 recurrence plus a 2l+1-term sum: a few ulp of values <= 1.
  constexpr double kTol = 1e-14;
  Lcg rng{3};
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Vector3d d = rng.unit();
    const std::vector<double> c = random_coeffs(rng, kOrder);
    std::vector<double> light(sh_count(kOrder), 0.0);
    add_zh_lobe_to_sh(d, c, light);
    const Eigen::Vector3d s = rng.unit();
    std::vector<double> bands(kOrder);
    zh_light_bands<double>(light, s, bands);
    for (int l = 0; l < kOrder; ++l) {
      const double want = c[l] * (2 * l + 1) / (4 * kPi) * std::legendre(l, s.dot(d));
      EXPECT_NEAR(bands[l], want, kTol) << "trial " << trial << " l " << l;
    }
  }
}

TEST(ZhShadingExact, EqualsZhLobeDotShAndQuadrature) {
  // Same products summed in a different grouping: rounding only.
  constexpr double kDotTol = 1e-14;
  // Quadrature exact for degree 2n - 2 (lobe times light); the residue is the rounding of
  // about 2n^2 weighted terms.
  constexpr double kQuadTol = 1e-13;
  const SphereQuadrature q = sphere_quadrature(2 * kOrder);
  Lcg rng{5};
  for (int trial = 0; trial < 10; ++trial) {
    const std::vector<double> light = test::random_unit_vector(rng, kOrder);
    const int lobes = 1 + trial % 4;
    std::vector<Eigen::Vector3d> axes;
    std::vector<double> coeffs;
    double via_dot = 0.0;
    for (int i = 0; i < lobes; ++i) {
      axes.push_back(rng.unit());
      const std::vector<double> g = random_coeffs(rng, kOrder);
      coeffs.insert(coeffs.end(), g.begin(), g.end());
      via_dot += zh_lobe_dot_sh(axes.back(), g, light);
    }
    double via_quadrature = 0.0;
    for (std::size_t k = 0; k < q.directions.size(); ++k) {
      double transfer = 0.0;
      for (int i = 0; i < lobes; ++i)
        transfer += eval_zh_lobe(axes[i], std::span<const double>(coeffs).subspan(i * kOrder, kOrder), q.directions[k]);
      via_quadrature += q.weights[k] * transfer * reconstruct<double>(light, q.directions[k]);
    }
    const double exact = zh_shade_exact<double>(light, axes, coeffs);
    EXPECT_NEAR(exact, via_dot, kDotTol) << "trial " << trial;
    EXPECT_NEAR(exact, via_quadrature, kQuadTol) << "trial " << trial;

    // float: same values to float rounding of order-1 sums (a few ulp at 2^-24).
    constexpr double kFloatTol = 2e-6;
    std::vector<float> lightf(light.begin(), light.end()), coeffsf(coeffs.begin(), coeffs.end());
    std::vector<Vec3<float>> axesf;
    for (const auto& a : axes) axesf.push_back(a.cast<float>());
    EXPECT_NEAR(zh_shade_exact<float>(lightf, axesf, coeffsf), exact, kFloatTol) << "trial " << trial;
  }
}

// --- tabulated path ---------------------------------------------------------------------

TEST(ZhLightTable, NodesHoldTheExactBandSums) {
  // Nodes are computed in double by the same band sums: equality to rounding.
  constexpr double kTol = 1e-15;
  Lcg rng{7};
  const std::vector<double> light = test::random_unit_vector(rng, kOrder);
  const int r = 5;  // odd, so face centres are not nodes and every cell kind occurs
  const ZhLightTable<double> table(kOrder, light, r);
  ASSERT_EQ(table.nodes().size(), 6u * (r + 1) * (r + 1) * kOrder);
  EXPECT_EQ(table.bytes(), table.nodes().size() * sizeof(double));
  std::vector<double> want(kOrder);
  for (int face = 0; face < 6; ++face)
    for (int j = 0; j <= r; ++j)
      for (int i = 0; i <= r; ++i) {
        Eigen::Vector3d c;
        const int k = face / 2;
        c[k] = face % 2 ? -1.0 : 1.0;
        c[(k + 1) % 3] = -1.0 + 2.0 * i / r;
        c[(k + 2) % 3] = -1.0 + 2.0 * j / r;
        zh_light_bands<double>(light, c.normalized(), want);
        for (int l = 0; l < kOrder; ++l)
          ASSERT_NEAR(table.nodes()[((face * (r + 1) + j) * (r + 1) + i) * kOrder + l], want[l], kTol)
              << "face " << face << " node " << i << "," << j << " l " << l;
        // The look-up at a node returns the node (bilinear weights 1, 0, 0, 0).
        std::vector<double> got(kOrder);
        table.lookup(c.normalized(), got);
        for (int l = 0; l < kOrder; ++l)
          ASSERT_NEAR(got[l], want[l], kTol) << "look-up at face " << face << " node " << i << "," << j;
      }
}

// Bilinear interpolation on smooth face maps: the error falls as R^-2, so each doubling
// of R divides it by 4. A wrong face parameterisation (swapped or mirrored coordinates on
// one face) or a seam would leave an O(1) error that does not fall at all.
TEST(ZhLightTable, ErrorFallsAsResolutionSquared) {
  Lcg rng{11};
  const std::vector<double> light = test::random_unit_vector(rng, kOrder);
  const std::vector<Eigen::Vector3d> dirs = test_directions(20000);
  double previous = 0.0;
  for (int r : {8, 16, 32, 64, 128}) {
    const ZhLightTable<double> table(kOrder, light, r);
    const std::vector<double> err = table_band_errors(table, light, dirs);
    EXPECT_LT(err[0], 1e-14) << "band 0 is constant, interpolated exactly; R " << r;
    double worst = 0.0;
    for (int l = 1; l < kOrder; ++l) worst = std::max(worst, err[l]);
    if (previous > 0) {
      // Expected ratio 4; the worst sample moves between cells, so allow 3.3..4.8.
      const double ratio = previous / worst;
      EXPECT_GT(ratio, 3.3) << "R " << r << " error " << sci(worst) << " previous " << sci(previous);
      EXPECT_LT(ratio, 4.8) << "R " << r << " error " << sci(worst) << " previous " << sci(previous);
    }
    RecordProperty("max_band_error_R" + std::to_string(r), sci(worst));
    previous = worst;
  }
}

TEST(ZhLightTable, DefaultResolutionMeetsTheDocumentedBound) {
  const std::vector<Eigen::Vector3d> dirs = test_directions(20000);
  Lcg rng{13};
  for (int trial = 0; trial < 4; ++trial) {
    const int order = trial < 3 ? kOrder : 10;
    const std::vector<double> light = test::random_unit_vector(rng, order);
    const ZhLightTable<double> table(order, light);
    ASSERT_EQ(table.resolution(), kDefaultZhLightResolution);
    const std::vector<double> err = table_band_errors(table, light, dirs);
    double tightest = 0.0;
    for (int l = 0; l < order; ++l) {
      const double bound = std::max(zh_light_table_error_bound(l, table.resolution()), 1e-14);
      EXPECT_LE(err[l], bound) << "trial " << trial << " order " << order << " band " << l << " error "
                               << sci(err[l]) << " bound " << sci(bound);
      if (l > 0) tightest = std::max(tightest, err[l] / bound);
    }
    // The bound must not be vacuous: in some band the error comes within a factor 2 of it.
    EXPECT_GT(tightest, 0.5) << "trial " << trial;
    RecordProperty("bound_use_trial" + std::to_string(trial), sci(tightest));
  }
}

TEST(ZhLightTable, ContinuousAcrossFaceEdgesAndCorners) {
  // Directions 1e-12 apart on either side of an edge land on different faces; the
  // interpolants agree on the shared edge, so the results differ by slope x 1e-12, and the
  // slope per unit face coordinate is at most R/2 times the largest node difference
  // (< 1 here): about 4e-12, plus rounding. A seam would show an O(1e-2) jump at R = 7.
  constexpr double kTol = 1e-11;
  Lcg rng{17};
  const std::vector<double> light = test::random_unit_vector(rng, kOrder);
  const ZhLightTable<double> table(kOrder, light, 7);
  std::vector<double> a(kOrder), b(kOrder);
  for (int k = 0; k < 3; ++k) {
    for (double sign : {-1.0, 1.0}) {
      for (double t : {-1.0, -0.61, 0.0, 0.37, 1.0}) {
        // A point on the edge between the faces of axes k and k+1.
        Eigen::Vector3d e;
        e[k] = sign;
        e[(k + 1) % 3] = 1.0;
        e[(k + 2) % 3] = t;
        Eigen::Vector3d p = e, q = e;
        p[k] *= 1 + 1e-12;
        q[(k + 1) % 3] *= 1 + 1e-12;
        table.lookup(p.normalized(), a);
        table.lookup(q.normalized(), b);
        for (int l = 0; l < kOrder; ++l)
          EXPECT_NEAR(a[l], b[l], kTol) << "axis " << k << " sign " << sign << " t " << t << " l " << l;
      }
    }
  }
}

TEST(ZhLightTable, ShadeIsEq25OverLookups) {
  // shade() is the sum over lobes of lookup . g, up to the order of the additions; lobe
  // counts below, at and above shade()'s batch of 8 located lobes.
  constexpr double kTol = 1e-14;
  Lcg rng{19};
  const std::vector<double> light = test::random_unit_vector(rng, kOrder);
  const ZhLightTable<double> table(kOrder, light);
  for (int lobes : {1, 4, 8, 11, 17}) {
    std::vector<Eigen::Vector3d> axes;
    std::vector<double> coeffs;
    double want = 0.0, via_shade_lobe = 0.0;
    std::vector<double> e(kOrder);
    for (int i = 0; i < lobes; ++i) {
      axes.push_back(rng.unit());
      const std::vector<double> g = random_coeffs(rng, kOrder);
      coeffs.insert(coeffs.end(), g.begin(), g.end());
      table.lookup(axes.back(), e);
      for (int l = 0; l < kOrder; ++l) want += e[l] * g[l];
      via_shade_lobe += table.shade_lobe(axes.back(), g);
    }
    EXPECT_NEAR(table.shade(axes, coeffs), want, kTol) << lobes << " lobes";
    EXPECT_NEAR(via_shade_lobe, want, kTol) << lobes << " lobes";
  }
}

// Rotating lobes (rotate_zh_axis) and shading must equal rotating the SH transfer vector
// (reference rotation, independent of ZH) and taking the n^2 dot product with the light.
TEST(ZhShading, RotatedLobesShadeLikeTheRotatedShVector) {
  constexpr double kExactTol = 1e-13;  // rounding of the rotation matrices and sums
  Lcg rng{23};
  ShRotation<double> rotation(kOrder, nullptr);
  std::vector<double> t(sh_count(kOrder)), rotated(sh_count(kOrder));
  for (int trial = 0; trial < 10; ++trial) {
    const std::vector<double> light = test::random_unit_vector(rng, kOrder);
    const ZhLightTable<double> table(kOrder, light);
    const std::vector<double> scale = band_scales(light, kOrder);
    double qn = 0;
    double q[4];
    for (double& x : q) {
      x = 2 * rng.uniform() - 1;
      qn += x * x;
    }
    const Mat3<double> r = matrix_from_quaternion(q[0] / std::sqrt(qn), q[1] / std::sqrt(qn), q[2] / std::sqrt(qn),
                                                  q[3] / std::sqrt(qn));
    ASSERT_TRUE(rotation.set(r, RotationMethod::reference));

    std::fill(t.begin(), t.end(), 0.0);
    std::vector<Eigen::Vector3d> axes;
    std::vector<double> coeffs;
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector3d s = rng.unit();
      const std::vector<double> g = random_coeffs(rng, kOrder);
      add_zh_lobe_to_sh(s, g, t);
      axes.push_back(rotate_zh_axis(r, s));
      coeffs.insert(coeffs.end(), g.begin(), g.end());
    }
    rotation.apply(t, rotated);
    double want = 0.0;
    for (int i = 0; i < sh_count(kOrder); ++i) want += rotated[i] * light[i];

    EXPECT_NEAR(zh_shade_exact<double>(light, axes, coeffs), want, kExactTol) << "trial " << trial;
    // Table: each lobe's error is at most sum_l |g_l| bound_l scale_l.
    double table_tol = 0.0;
    for (int i = 0; i < 4; ++i)
      for (int l = 0; l < kOrder; ++l)
        table_tol += std::abs(coeffs[i * kOrder + l]) * zh_light_table_error_bound(l, table.resolution()) * scale[l];
    table_tol += kExactTol;
    EXPECT_NEAR(table.shade(axes, coeffs), want, table_tol) << "trial " << trial;

    // float table and float look-ups: the same bound plus float rounding.
    constexpr double kFloatTol = 1e-5;
    const ZhLightTable<float> tablef(kOrder, light);
    std::vector<Vec3<float>> axesf;
    for (const auto& a : axes) axesf.push_back(a.cast<float>());
    std::vector<float> coeffsf(coeffs.begin(), coeffs.end());
    EXPECT_NEAR(tablef.shade(axesf, coeffsf), want, table_tol + kFloatTol) << "float, trial " << trial;
  }
}

// --- bad input ----------------------------------------------------------------------------

void expect_invalid(int order, const std::vector<double>& light, int resolution, const std::string& words) {
  try {
    ZhLightTable<double> table(order, light, resolution);
    ADD_FAILURE() << "accepted order " << order << ", " << light.size() << " coefficients, resolution "
                  << resolution;
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << "message: " << e.what();
  }
}

TEST(ZhLightTable, RejectsBadInput) {
  Lcg rng{29};
  std::vector<double> light = test::random_unit_vector(rng, kOrder);
  expect_invalid(kOrder, std::vector<double>(25, 0.1), 16, "order mismatch");
  expect_invalid(5, light, 16, "order mismatch");
  expect_invalid(0, {}, 16, "order 0");
  expect_invalid(kMaxOrder + 1, light, 16, "outside");
  expect_invalid(kOrder, light, 0, "resolution 0");
  expect_invalid(kOrder, light, -3, "resolution -3");
  expect_invalid(kOrder, light, kMaxZhLightResolution + 1, "resolution");
  const std::vector<double> order64(sh_count(64), 0.0);
  expect_invalid(64, order64, kMaxZhLightResolution, "more than the limit");
  light[7] = std::numeric_limits<double>::quiet_NaN();
  expect_invalid(kOrder, light, 16, "coefficient 7 is not finite");
  light[7] = std::numeric_limits<double>::infinity();
  expect_invalid(kOrder, light, 16, "coefficient 7 is not finite");
  EXPECT_THROW(ZhLightTable<float>(kOrder, light, 16), std::invalid_argument);
}

TEST(ZhShading, PerPointCallsAreNoexceptAndFlagMismatchesWithNaN) {
  // declval arguments: constructing an Eigen temporary is itself not noexcept.
  static_assert(noexcept(std::declval<const ZhLightTable<double>&>().shade(
      std::declval<std::span<const Vec3<double>>>(), std::declval<std::span<const double>>())));
  static_assert(noexcept(std::declval<const ZhLightTable<float>&>().shade_lobe(
      std::declval<const Vec3<float>&>(), std::declval<std::span<const float>>())));
  static_assert(noexcept(std::declval<const ZhLightTable<float>&>().lookup(std::declval<const Vec3<float>&>(),
                                                                           std::declval<std::span<float>>())));
  static_assert(noexcept(zh_shade_exact<double>(std::declval<std::span<const double>>(),
                                                std::declval<std::span<const Vec3<double>>>(),
                                                std::declval<std::span<const double>>())));
  static_assert(noexcept(zh_light_bands<float>(std::declval<std::span<const float>>(),
                                               std::declval<const Vec3<float>&>(), std::declval<std::span<float>>())));

  Lcg rng{31};
  const std::vector<double> light = test::random_unit_vector(rng, kOrder);
  const ZhLightTable<double> table(kOrder, light, 8);
  const std::vector<Eigen::Vector3d> axes = {rng.unit(), rng.unit()};
  const std::vector<double> good = random_coeffs(rng, 2 * kOrder);
  const std::vector<double> short_coeffs = random_coeffs(rng, 2 * kOrder - 1);
  const std::vector<double> order5 = random_coeffs(rng, 5);
  EXPECT_TRUE(std::isfinite(table.shade(axes, good)));
  EXPECT_TRUE(std::isnan(table.shade(axes, short_coeffs)));
  EXPECT_TRUE(std::isnan(table.shade_lobe(axes[0], order5)));
  EXPECT_TRUE(std::isfinite(zh_shade_exact<double>(light, axes, good)));
  EXPECT_TRUE(std::isnan(zh_shade_exact<double>(light, axes, short_coeffs)));
  const std::vector<double> not_square(30, 0.1);
  EXPECT_TRUE(std::isnan(zh_shade_exact<double>(not_square, axes, good)));
  std::vector<double> bands(kOrder, 0.0);
  zh_light_bands<double>(not_square, axes[0], bands);
  EXPECT_TRUE(std::isnan(bands[0]));

  // NaN, zero or direction-less infinite axes: NaN out, never a read outside the table.
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& bad : {Eigen::Vector3d(nan, 0, 1), Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(inf, inf, 0),
                                     Eigen::Vector3d(1, -inf, inf), Eigen::Vector3d(nan, nan, nan)}) {
    EXPECT_TRUE(std::isnan(table.shade_lobe(bad, std::span<const double>(good).first(kOrder))))
        << bad.transpose();
  }
}

// A float engine builds its table from float lighting: the same nodes as from the
// lighting widened by hand. A subnormal axis is a direction like any other.
TEST(ZhLightTable, FloatLightingAndTinyAxes) {
  Lcg rng{41};
  const std::vector<double> light = test::random_unit_vector(rng, kOrder);
  const std::vector<float> light_f(light.begin(), light.end());
  const ZhLightTable<float> from_float(kOrder, std::span<const float>(light_f), 8);
  const ZhLightTable<float> from_double(kOrder, std::vector<double>(light_f.begin(), light_f.end()), 8);
  EXPECT_TRUE(std::equal(from_float.nodes().begin(), from_float.nodes().end(), from_double.nodes().begin(),
                         from_double.nodes().end()));
  std::vector<float> tiny(kOrder), unit(kOrder);
  from_float.lookup(Vec3<float>(1e-40f, 0, 0), tiny);
  from_float.lookup(Vec3<float>(1, 0, 0), unit);
  EXPECT_EQ(tiny, unit);
}

TEST(ZhShading, PerPointCallsAllocateNothing) {
  Lcg rng{37};
  const std::vector<double> light = test::random_unit_vector(rng, kOrder);
  const std::vector<float> lightf(light.begin(), light.end());
  const ZhLightTable<double> table(kOrder, light);
  const ZhLightTable<float> tablef(kOrder, light);
  const std::vector<Eigen::Vector3d> axes = {rng.unit(), rng.unit(), rng.unit()};
  const std::vector<Vec3<float>> axesf = {axes[0].cast<float>(), axes[1].cast<float>(), axes[2].cast<float>()};
  const std::vector<double> coeffs = random_coeffs(rng, 3 * kOrder);
  const std::vector<float> coeffsf(coeffs.begin(), coeffs.end());
  std::vector<double> bands(kOrder);
  std::vector<float> bandsf(kOrder);
  zh_shade_exact<double>(light, axes, coeffs);  // first calls build eval_sh's static tables
  zh_shade_exact<float>(lightf, axesf, coeffsf);

  const long before = test::allocation_count();
  double sum = 0;
  for (int k = 0; k < 100; ++k) {
    sum += table.shade(axes, coeffs) + tablef.shade(axesf, coeffsf);
    sum += zh_shade_exact<double>(light, axes, coeffs) + zh_shade_exact<float>(lightf, axesf, coeffsf);
    table.lookup(axes[0], bands);
    tablef.lookup(axesf[0], bandsf);
    zh_light_bands<double>(light, axes[1], bands);
    zh_light_bands<float>(lightf, axesf[1], bandsf);
    sum += bands[0] + bandsf[0];
  }
  const long after = test::allocation_count();
  EXPECT_EQ(after - before, 0) << "allocations during shading";
  EXPECT_TRUE(std::isfinite(sum));
  // The counter works: building a table allocates.
  { const ZhLightTable<double> t(kOrder, light, 2); }
  EXPECT_GT(test::allocation_count(), after);
}

}  // namespace
