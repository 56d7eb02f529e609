// ZhFitTable::load (include/shtool/zh_fit_table.h) against the fit-zh table writer: exact
// round trip of every value, the span layout zh_shading.h takes, and every structural or
// numeric corruption rejected with a message.
#include <cmath>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "common/generator_record.h"
#include "fit/zh_fit.h"
#include "fit/zh_fit_table.h"
#include "shtool/sh.h"
#include "shtool/zh.h"
#include "shtool/zh_fit_table.h"
#include "shtool/zh_shading.h"
#include "table_test_util.h"

namespace shtool {
namespace {

namespace fs = std::filesystem;

constexpr int kOrder = 4, kLobes = 3;

fit::ZhFitOptions options(bool direct) {
  fit::ZhFitOptions o;
  o.order = kOrder;
  o.lobes = kLobes;
  o.direct = direct;
  o.starts = 1;
  return o;
}

std::vector<double> some_vector(int v) {
  std::vector<double> t(sh_count(kOrder));
  for (std::size_t i = 0; i < t.size(); ++i) t[i] = std::cos(0.7 * i + v) / (1 + i);
  return t;
}

// The reference: each vector fitted on its own (stream v, as fit_zh_all draws it).
std::vector<fit::ZhFit> some_fits(int count, bool direct) {
  std::vector<fit::ZhFit> fits;
  for (int v = 0; v < count; ++v) fits.push_back(fit::fit_zh(some_vector(v), options(direct), v));
  return fits;
}

// The same vectors through the flat set the jobs write (two workers).
Table fit_table(int count, bool direct, std::vector<std::uint32_t> index = {}) {
  std::vector<double> vectors;
  for (int v = 0; v < count; ++v) {
    const std::vector<double> t = some_vector(v);
    vectors.insert(vectors.end(), t.begin(), t.end());
  }
  ZhFitTable<double> fits = fit::fit_zh_all(vectors, options(direct), 2);
  fits.vertex_index = std::move(index);
  return fit::zh_fit_table(fits, nlohmann::json::object(), generator_record("test", nlohmann::json::object()));
}

class ZhFitTableTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("shtool-test-zhfit-" + std::to_string(::getpid()) + "-" +
                                        ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ec;
    fs::remove_all(dir_, ec);
  }
  fs::path dir_;
};

TEST_F(ZhFitTableTest, RoundTripIsExactAndSpansShade) {
  const std::vector<fit::ZhFit> fits = some_fits(5, false);
  const fs::path p = dir_ / "f.shtb";
  ASSERT_TRUE(test::try_write(fit_table(5, false, {10, 11, 12, 20, 21}), p).ok());
  const auto loaded = ZhFitTable<double>::load(p);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const ZhFitTable<double>& z = loaded.value();
  EXPECT_EQ(z.order, kOrder);
  EXPECT_EQ(z.lobes, kLobes);
  ASSERT_EQ(z.vertices, fits.size());
  EXPECT_EQ(z.direct_count, 0);
  EXPECT_EQ(z.vertex_index, (std::vector<std::uint32_t>{10, 11, 12, 20, 21}));
  std::vector<double> light(sh_count(kOrder));
  for (std::size_t i = 0; i < light.size(); ++i) light[i] = 1.0 / (1.0 + i);
  for (std::size_t v = 0; v < fits.size(); ++v) {
    EXPECT_EQ(z.residual[v], fits[v].residual);
    EXPECT_EQ(z.norm[v], fits[v].norm);
    ASSERT_EQ(z.axes_of(v).size(), static_cast<std::size_t>(kLobes));
    double want = 0;
    for (int k = 0; k < kLobes; ++k) {
      EXPECT_EQ(z.axes_of(v)[k], fits[v].lobes[k].axis) << v << " " << k;
      for (int l = 0; l < kOrder; ++l) EXPECT_EQ(z.coeffs_of(v)[k * kOrder + l], fits[v].lobes[k].coeffs[l]);
      want += zh_lobe_dot_sh(fits[v].lobes[k].axis, fits[v].lobes[k].coeffs, light);
    }
    EXPECT_NEAR(zh_shade_exact<double>(light, z.axes_of(v), z.coeffs_of(v)), want, 1e-13);
  }
  const auto as_float = ZhFitTable<float>::load(p);
  ASSERT_TRUE(as_float.ok()) << as_float.error().message;
  EXPECT_EQ(as_float.value().coeffs[7], static_cast<float>(z.coeffs[7]));
}

TEST_F(ZhFitTableTest, DirectCoefficientsLoad) {
  const std::vector<fit::ZhFit> fits = some_fits(3, true);
  const auto z = ZhFitTable<double>::from_table(fit_table(3, true));
  ASSERT_TRUE(z.ok()) << z.error().message;
  ASSERT_EQ(z.value().direct_count, static_cast<int>(fits[0].direct.size()));
  EXPECT_EQ(z.value().direct_count, fit::direct_count(options(true)));
  for (std::size_t v = 0; v < fits.size(); ++v)
    for (std::size_t i = 0; i < fits[v].direct.size(); ++i) EXPECT_EQ(z.value().direct_of(v)[i], fits[v].direct[i]);
}

TEST_F(ZhFitTableTest, CorruptionsAreRejected) {
  const Table good = fit_table(2, false);
  ASSERT_TRUE(ZhFitTable<double>::from_table(good).ok());
  auto expect_rejected = [](const Table& t, const std::string& fragment) {
    const auto z = ZhFitTable<double>::from_table(t);
    ASSERT_FALSE(z.ok()) << "accepted a table with " << fragment;
    EXPECT_NE(z.error().message.find(fragment), std::string::npos) << z.error().message;
  };
  auto set_f64 = [](Table& t, const char* name, std::size_t i, double v) {
    for (TableArray& a : t.arrays)
      if (a.name == name) {
        std::vector<double> x = a.values<double>();
        x[i] = v;
        a = TableArray::from<double>(a.name, a.shape, x);
      }
  };
  Table t = good;
  t.kind = "zhf-lobes";
  expect_rejected(t, "wrong kind");
  t = good;
  t.order = 5;
  expect_rejected(t, "'coeffs' has shape [2, 3, 4], expected [2, 3, 5]");
  t = good;
  set_f64(t, "axes", 0, 2.0);
  expect_rejected(t, "not a unit vector");
  t = good;
  set_f64(t, "coeffs", 4, std::numeric_limits<double>::quiet_NaN());
  expect_rejected(t, "'coeffs' element 4 is not finite");
  t = good;
  set_f64(t, "residual", 1, -1.0);
  expect_rejected(t, "negative residual");
  t = good;
  t.arrays.erase(t.arrays.begin() + 3);  // norm
  expect_rejected(t, "missing array 'norm'");
  t = good;
  t.arrays.push_back(TableArray::from<std::uint32_t>("vertex_index", {3}, std::vector<std::uint32_t>{1, 2, 3}));
  expect_rejected(t, "vertex_index");
  // Direct coefficients beyond the table's order (DC and band 1 need order 2).
  t = good;
  t.order = 1;
  for (TableArray& a : t.arrays)
    if (a.name == "coeffs") a = TableArray::from<double>("coeffs", {2, 3, 1}, std::vector<double>(6, 0.1));
  ASSERT_TRUE(ZhFitTable<double>::from_table(t).ok());
  t.arrays.push_back(TableArray::from<double>("direct", {2, 4}, std::vector<double>(8, 0.0)));
  expect_rejected(t, "more than order 1");
  // Coefficients beyond what a float's shading sums can carry (max / 2^64), and a double's.
  t = good;
  set_f64(t, "coeffs", 0, 1e30);
  EXPECT_FALSE(ZhFitTable<float>::from_table(t).ok());
  EXPECT_TRUE(ZhFitTable<double>::from_table(t).ok());
  set_f64(t, "coeffs", 0, 1e300);
  expect_rejected(t, "too large for the requested precision");
}

TEST_F(ZhFitTableTest, LoadNamesTheFile) {
  const auto z = ZhFitTable<double>::load(dir_ / "none.shtb");
  ASSERT_FALSE(z.ok());
  EXPECT_NE(z.error().message.find("none.shtb"), std::string::npos) << z.error().message;
}

}  // namespace
}  // namespace shtool
