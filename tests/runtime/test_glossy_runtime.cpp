// The glossy-zh runtime: the concentric view map (inverse, equal area, the horizon at the
// border), the view-factor look-up (exact at texel centres, bilinear between), Eq. 16 as
// the sum of the rows' ZH shadings, and a loader that refuses malformed tables.
#include <cmath>
#include <array>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "shtool/glossy.h"
#include "shtool/zh_shading.h"

namespace {

using namespace shtool;

TEST(GlossyViewMap, InverseAndUnitLength) {
  for (int i = 0; i <= 40; ++i)
    for (int j = 0; j <= 40; ++j) {
      const double a = i / 40.0, b = j / 40.0;
      const Vec3<double> v = glossy_view_direction(a, b);
      EXPECT_NEAR(v.norm(), 1.0, 1e-14);
      EXPECT_GE(v.z(), 0.0);
      const auto back = glossy_view_square(v);
      EXPECT_NEAR(back[0], a, 1e-12) << a << " " << b;
      EXPECT_NEAR(back[1], b, 1e-12) << a << " " << b;
      if (i == 0 || i == 40 || j == 0 || j == 40) EXPECT_NEAR(v.z(), 0.0, 1e-15);  // the border is the horizon
    }
  EXPECT_EQ(glossy_view_direction(0.5, 0.5), Vec3<double>(0, 0, 1));
  for (const Vec3<double>& odd : {Vec3<double>(0, 0, 0), Vec3<double>(0.1, 0, INFINITY), Vec3<double>(NAN, 0, 1)})
    EXPECT_EQ(glossy_view_square(odd), (std::array<double, 2>{0.5, 0.5}));
  // Views whose squared length leaves the type's range land where their directions do.
  for (double s : {1e300, 1e-200})
    EXPECT_EQ(glossy_view_square(Vec3<double>(s, 0, 0)), (std::array<double, 2>{1, 0.5}));
  EXPECT_EQ(glossy_view_square(Vec3<double>(1e300, 1e300, 0)), glossy_view_square(Vec3<double>(1, 1, 0)));
  for (float s : {1e20f, 1e-23f}) EXPECT_EQ(glossy_view_square(Vec3<float>(s, 0, 0)), (std::array<float, 2>{1, 0.5f}));
  const auto below = glossy_view_square(Vec3<double>(1, 0, -0.5));
  EXPECT_NEAR(below[0], 1.0, 1e-15);  // below the horizon: at the horizon, same azimuth
  EXPECT_NEAR(below[1], 0.5, 1e-15);
}

TEST(GlossyViewMap, EveryTexelCoversTheSameSolidAngle) {
  // 2^20 hemisphere points uniform in solid angle (spherical Fibonacci) fall evenly into
  // the 8 x 8 texels; a map that is not equal area would put 2x more in some.
  const int g = 8, points = 1 << 20;
  std::vector<int> count(g * g, 0);
  for (int k = 0; k < points; ++k) {
    const double z = 1.0 - (k + 0.5) / points, r = std::sqrt(1 - z * z);
    const double phi = 2 * std::numbers::pi * std::fmod(k * 0.61803398874989484820, 1.0);
    const auto ab = glossy_view_square(Vec3<double>(r * std::cos(phi), r * std::sin(phi), z));
    const int a = std::min(g - 1, static_cast<int>(ab[0] * g)), b = std::min(g - 1, static_cast<int>(ab[1] * g));
    ++count[b * g + a];
  }
  for (int c : count) EXPECT_NEAR(c, points / double(g * g), 0.01 * points / (g * g));
}

// A glossy-zh table built by hand: order 2, 2 vertices, 2 terms, 1 lobe per row, a 3 x 3
// view map.
Table small_table() {
  Table t;
  t.kind = "glossy-zh";
  t.order = 2;
  const std::vector<double> axes = {0, 0, 1, 1, 0, 0, 0, 1, 0, 0.6, 0.8, 0};
  std::vector<double> coeffs = {0.5, 0.2, 0.1, -0.3, 0.4, 0.4, -0.2, 0.7};
  std::vector<double> u(3 * 3 * 2);
  for (std::size_t i = 0; i < u.size(); ++i) u[i] = 0.1 * i - 0.4;
  t.arrays.push_back(TableArray::from<double>("axes", {4, 1, 3}, axes));
  t.arrays.push_back(TableArray::from<double>("coeffs", {4, 1, 2}, coeffs));
  t.arrays.push_back(TableArray::from<double>("residual", {4}, std::vector<double>{0, 0, 0, 0}));
  t.arrays.push_back(TableArray::from<double>("norm", {4}, std::vector<double>{1, 1, 1, 1}));
  t.arrays.push_back(TableArray::from<double>("direct", {4, 1}, std::vector<double>{0.3, -0.1, 0.2, 0.05}));
  t.arrays.push_back(TableArray::from<double>("view_factors", {3, 3, 2}, u));
  t.arrays.push_back(TableArray::from<std::uint32_t>("vertex_index", {2}, std::vector<std::uint32_t>{7, 3}));
  return t;
}

TEST(GlossyFitTable, LooksUpAndShadesAsEq16) {
  const Result<GlossyFit<double>> loaded = GlossyFit<double>::from_table(small_table());
  ASSERT_TRUE(loaded) << loaded.error().message;
  const GlossyFit<double>& fit = loaded.value();
  EXPECT_EQ(fit.vertices, 2u);
  EXPECT_EQ(fit.terms, 2);
  EXPECT_EQ(fit.vertex_index, (std::vector<std::uint32_t>{7, 3}));
  // At every texel centre the stored values come back.
  double u[2];
  for (int b = 0; b < 3; ++b)
    for (int a = 0; a < 3; ++a) {
      fit.view_factors_at(glossy_view_direction((a + 0.5) / 3, (b + 0.5) / 3), u);
      for (int j = 0; j < 2; ++j) EXPECT_NEAR(u[j], fit.view_factors[(b * 3 + a) * 2 + j], 1e-12);
    }
  // Halfway between two centres of a row: their mean.
  fit.view_factors_at(glossy_view_direction(1.0 / 3, 0.5), u);
  for (int j = 0; j < 2; ++j)
    EXPECT_NEAR(u[j], 0.5 * (fit.view_factors[(3 + 0) * 2 + j] + fit.view_factors[(3 + 1) * 2 + j]), 1e-12);
  // Eq. 16: u(v) dotted with each row's ZH shading plus its direct DC.
  const std::vector<double> light = {0.9, -0.2, 0.4, 0.3};
  const Vec3<double> view = Vec3<double>(0.2, -0.3, 0.8).normalized();
  fit.view_factors_at(view, u);
  for (std::size_t v = 0; v < 2; ++v) {
    double expected = 0;
    for (int j = 0; j < 2; ++j) {
      const std::size_t row = v * 2 + j;
      const double r = zh_shade_exact<double>(light, fit.rows.axes_of(row), fit.rows.coeffs_of(row)) +
                       fit.rows.direct[row] * light[0];
      expected += u[j] * r;
    }
    EXPECT_NEAR(fit.shade(light, v, view), expected, 1e-14);
  }
  EXPECT_TRUE(std::isnan(fit.shade(std::vector<double>(9, 1.0), 0, view)));  // another order
  // The float instantiation agrees to float rounding.
  const Result<GlossyFit<float>> f = GlossyFit<float>::from_table(small_table());
  ASSERT_TRUE(f);
  const std::vector<float> lf(light.begin(), light.end());
  EXPECT_NEAR(f.value().shade(lf, 1, view.cast<float>()), fit.shade(light, 1, view), 1e-5);
}

TEST(GlossyFitTable, RefusesMalformedTables) {
  auto refused = [](Table t, const std::string& words) {
    const Result<GlossyFit<double>> r = GlossyFit<double>::from_table(t);
    ASSERT_FALSE(r);
    EXPECT_NE(r.error().message.find(words), std::string::npos) << r.error().message;
  };
  Table t = small_table();
  t.kind = "zh-fit";
  refused(t, "wrong kind");
  t = small_table();
  t.arrays[5] = TableArray::from<double>("view_factors", {3, 2, 2}, std::vector<double>(12, 0.0));
  refused(t, "view_factors");
  t = small_table();
  t.arrays[5] = TableArray::from<double>("view_factors", {3, 3, 3}, std::vector<double>(27, 0.0));
  refused(t, "whole number of vertices");
  t = small_table();
  std::vector<double> u(18, 0.0);
  u[7] = std::numeric_limits<double>::quiet_NaN();
  t.arrays[5] = TableArray::from<double>("view_factors", {3, 3, 2}, u);
  refused(t, "not finite");
  t = small_table();
  t.arrays[0] = TableArray::from<double>("axes", {4, 1, 3}, std::vector<double>{0, 0, 2, 1, 0, 0, 0, 1, 0, 0.6, 0.8, 0});
  refused(t, "unit");
  t = small_table();
  t.arrays[6] = TableArray::from<std::uint32_t>("vertex_index", {4}, std::vector<std::uint32_t>{1, 2, 3, 4});
  refused(t, "vertex_index");
  t = small_table();
  t.arrays.erase(t.arrays.begin() + 5);
  refused(t, "view_factors");
  t = small_table();
  t.arrays[4] = TableArray::from<double>("direct", {4, 1}, std::vector<double>{0.3, 1e30, 0.2, 0.05});
  ASSERT_TRUE(GlossyFit<double>::from_table(t));  // fits a double
  const Result<GlossyFit<float>> narrow = GlossyFit<float>::from_table(t);
  ASSERT_FALSE(narrow);
  EXPECT_NE(narrow.error().message.find("precision"), std::string::npos) << narrow.error().message;
  t = small_table();
  t.order = 1;  // two terms are more than order 1 has coefficients
  t.arrays[1] = TableArray::from<double>("coeffs", {4, 1, 1}, std::vector<double>{1, 1, 1, 1});
  refused(t, "terms");
}

}  // namespace
