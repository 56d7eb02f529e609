// ZHF rotation ([1] Eq. 10-11) against the dense reference rotation.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "lobes/lobes.h"
#include "common/generator_record.h"
#include "shtool/euler.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "shtool/table.h"
#include "table_test_util.h"
#include "shtool/zhf_rotation.h"

namespace {

using namespace shtool;

// Rotating through A^_l amplifies rounding by about cond(Y_l) * (2l+1) * eps; the shipped
// tables keep cond <= 1e4 (1e4 * 19 * 1.1e-16 = 2e-11 for N <= 10), under the required 1e-10.
// Unit-norm inputs, so this is an absolute tolerance.
constexpr double kZhfTolerance = 1e-10;
// float: the same amplification with float eps (6e-8): cond ~ 30..1e3 for N <= 8 shipped.
constexpr double kZhfFloatTolerancePerCond = 3e-7;

std::vector<Mat3<double>> test_rotations() {
  std::mt19937_64 rng(2024);
  std::normal_distribution<double> g(0, 1);
  std::vector<Mat3<double>> r = {Mat3<double>::Identity()};
  for (int k = 0; k < 12; ++k) {
    double w = g(rng), x = g(rng), y = g(rng), z = g(rng);
    const double n = std::sqrt(w * w + x * x + y * y + z * z);
    r.push_back(matrix_from_quaternion<double>(w / n, x / n, y / n, z / n));
  }
  // Near-singular zyz cases: tilt 0 and pi.
  r.push_back(matrix_from_quaternion<double>(std::cos(0.35), 0, 0, std::sin(0.35)));
  r.push_back(matrix_from_quaternion<double>(0, 1, 0, 0));
  return r;
}

std::vector<double> random_unit_vector(int order, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  std::vector<double> f(sh_count(order));
  double n = 0;
  for (double& v : f) n += (v = g(rng)) * v;
  for (double& v : f) v /= std::sqrt(n);
  return f;
}

// Max |ZHF - reference| over rotations and inputs, standard and signal-tailored.
void check_against_reference(const std::shared_ptr<const ZhfLobes>& lobes, int order, const std::string& what) {
  ShRotation<double> ref(order, nullptr);
  ZhfRotation<double> zhf(order, lobes);
  std::vector<double> expect(sh_count(order)), got(sh_count(order)), tailored(sh_count(order));
  double worst = 0, worst_t = 0;
  int k = 0;
  for (const Mat3<double>& r : test_rotations()) {
    ASSERT_TRUE(ref.set(r, RotationMethod::reference));
    zhf.set(r);
    for (int v = 0; v < 3; ++v, ++k) {
      const std::vector<double> f = random_unit_vector(order, 100 + k);
      ref.apply(f, expect);
      zhf.apply(f, got);
      ZhfTailoredSignal<double> sig(lobes, f);
      ASSERT_TRUE(sig.set(r));
      sig.apply(tailored);
      for (int i = 0; i < sh_count(order); ++i) {
        worst = std::max(worst, std::abs(got[i] - expect[i]));
        worst_t = std::max(worst_t, std::abs(tailored[i] - expect[i]));
      }
    }
  }
  EXPECT_LT(worst, kZhfTolerance) << what << " N " << order << " standard (Eq. 10)";
  EXPECT_LT(worst_t, kZhfTolerance) << what << " N " << order << " signal-tailored (Eq. 11)";
}

std::filesystem::path tables_dir() { return std::filesystem::path(SHTOOL_SOURCE_DIR) / "tables"; }

TEST(ZhfRotation, ShippedSharedTablesMatchReference) {
  int checked = 0;
  // The shipped shared tables are N = 4..10 (tables/regenerate.txt); each must exist.
  for (int n = 4; n <= 10; ++n) {
    const auto path = tables_dir() / ("zhf-shared-N" + std::to_string(n) + ".shtb");
    ASSERT_TRUE(std::filesystem::exists(path)) << "shipped table missing: " << path;
    auto loaded = ZhfLobes::load(path);
    ASSERT_TRUE(loaded.ok()) << loaded.error().message;
    auto lobes = std::make_shared<const ZhfLobes>(std::move(loaded).value());
    ASSERT_EQ(lobes->order, n);
    EXPECT_EQ(lobes->directions.size(), static_cast<std::size_t>(2 * n - 1)) << "shared lobes: 2N-1 directions";
    for (int order = 1; order <= n; ++order) check_against_reference(lobes, order, path.filename().string());
    ++checked;
  }
  EXPECT_EQ(checked, 7);
}

TEST(ZhfRotation, DefaultPathFindsShippedTable) {
  const auto p = default_zhf_lobes_path(4);
  ASSERT_TRUE(std::filesystem::exists(tables_dir() / "zhf-shared-N4.shtb")) << "shipped N=4 table missing";
  EXPECT_EQ(p.filename().string(), "zhf-shared-N4.shtb");
  // A larger shipped table serves a smaller order (nested directions).
  auto small = ZhfLobes::load(p);
  ASSERT_TRUE(small.ok()) << small.error().message;
  small = small.value().bands_below(3);
  ASSERT_TRUE(small.ok()) << small.error().message;
  EXPECT_EQ(small.value().order, 3);
  EXPECT_EQ(small.value().directions.size(), 5u);
}

// Independent of the shipped tables and of the search: lobes at generic (random) directions
// give a dense A^ that must rotate just as exactly (Lessig et al.: any invertible Y_l works).
TEST(ZhfRotation, GenericDirectionsTableRoundTrip) {
  const int order = 6;
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> u(0, 1);
  lobes::SearchResult res;
  res.shared = true;
  res.order = order;
  std::vector<Vec3<double>> dirs;
  for (int d = 0; d < 2 * order - 1; ++d) {
    res.theta.push_back(std::acos(1 - 2 * u(rng)));
    res.phi.push_back(2 * M_PI * u(rng));
    dirs.push_back(lobes::lobe_direction(res.theta.back(), res.phi.back()));
  }
  for (int k = 0; k < order; ++k)
    res.bands.push_back(lobes::analyze_band(k, std::span<const Vec3<double>>(dirs).first(2 * k + 1)));
  for (const auto& b : res.bands) ASSERT_TRUE(b.invertible) << "band " << b.l;
  for (const auto& b : res.bands) ASSERT_LT(b.cond, 1e4) << "band " << b.l << ": pick another seed";
  const auto path = std::filesystem::temp_directory_path() / "shtool_test_zhf_generic.shtb";
  const Table t = lobes::make_lobes_table({res}, generator_record("test", {{"seed", 99}}), {});
  ASSERT_TRUE(shtool::test::try_write(t, path).ok());
  auto loaded = ZhfLobes::load(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  auto lobes = std::make_shared<const ZhfLobes>(std::move(loaded).value());
  EXPECT_EQ(lobes->nonzeros(), static_cast<std::size_t>(order * (4 * order * order - 1) / 3))
      << "generic directions: dense A^";
  for (int n = 1; n <= order; ++n) check_against_reference(lobes, n, "generic");
}

// Per-band lobes (each band its own 2l+1 directions, N^2 in all, not nested): the
// evaluators run the SH recurrence for all directions at once and must serve every band
// from its own direction range, including directions that only higher bands use.
TEST(ZhfRotation, PerBandDirectionsTableRoundTrip) {
  const int order = 5;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  std::vector<lobes::SearchResult> searches;
  for (int l = 0; l < order; ++l) {
    lobes::SearchResult res;
    res.order = l + 1;
    std::vector<Vec3<double>> dirs;
    for (int d = 0; d < 2 * l + 1; ++d) {
      res.theta.push_back(std::acos(1 - 2 * u(rng)));
      res.phi.push_back(2 * M_PI * u(rng));
      dirs.push_back(lobes::lobe_direction(res.theta.back(), res.phi.back()));
    }
    res.bands.push_back(lobes::analyze_band(l, dirs));
    ASSERT_TRUE(res.bands.back().invertible) << "band " << l;
    ASSERT_LT(res.bands.back().cond, 1e4) << "band " << l << ": pick another seed";
    searches.push_back(std::move(res));
  }
  const auto path = std::filesystem::temp_directory_path() / "shtool_test_zhf_perband.shtb";
  const Table t = lobes::make_lobes_table(searches, generator_record("test", {{"seed", 7}}), {});
  ASSERT_TRUE(shtool::test::try_write(t, path).ok());
  auto loaded = ZhfLobes::load(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  auto lobes = std::make_shared<const ZhfLobes>(std::move(loaded).value());
  ASSERT_EQ(lobes->directions.size(), static_cast<std::size_t>(order * order)) << "one direction set per band";
  for (int n = 1; n <= order; ++n) check_against_reference(lobes, n, "per-band");
}

TEST(ZhfRotation, FloatAgreesWithinConditioning) {
  const auto path = default_zhf_lobes_path(6);
  ASSERT_FALSE(path.empty()) << "no shipped shared table found (SHTOOL_TABLES)";
  auto loaded = ZhfLobes::load(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  auto lobes = std::make_shared<const ZhfLobes>(std::move(loaded).value());
  double cond = 1;
  for (double c : lobes->cond) cond = std::max(cond, c);
  ShRotation<double> ref(6, nullptr);
  ZhfRotation<float> zhf(6, lobes);
  const std::vector<double> f = random_unit_vector(6, 5);
  std::vector<float> ff(f.begin(), f.end()), got(36), tailored(36);
  std::vector<double> expect(36);
  for (const Mat3<double>& r : test_rotations()) {
    ASSERT_TRUE(ref.set(r, RotationMethod::reference));
    ref.apply(f, expect);
    zhf.set(r.cast<float>());
    zhf.apply(ff, got);
    ZhfTailoredSignal<float> sig(lobes, ff);
    ASSERT_TRUE(sig.set(r.cast<float>()));
    sig.apply(tailored);
    for (int i = 0; i < 36; ++i) {
      EXPECT_NEAR(got[i], expect[i], kZhfFloatTolerancePerCond * cond) << "i " << i;
      EXPECT_NEAR(tailored[i], expect[i], kZhfFloatTolerancePerCond * cond) << "i " << i;
    }
  }
}

TEST(ZhfRotation, ApplySamplesIsTheSparseProduct) {
  // With samples f~_l(w_d) of the unrotated signal, A^ samples gives f back (A^ Y = I).
  const auto path = default_zhf_lobes_path(5);
  ASSERT_FALSE(path.empty()) << "no shipped shared table found (SHTOOL_TABLES)";
  auto loaded = ZhfLobes::load(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const ZhfLobes& z = loaded.value();
  const std::vector<double> f = random_unit_vector(5, 11);
  std::vector<double> samples(25), out(25), y(25);
  for (int l = 0; l < 5; ++l)
    for (int d = 0; d <= 2 * l; ++d) {
      eval_sh<double>(5, z.directions[z.band_offset[l] + d], y);
      double s = 0;
      for (int m = -l; m <= l; ++m) s += f[sh_index(l, m)] * y[sh_index(l, m)];
      samples[l * l + d] = s;
    }
  ZhfTailoredSignal<double>::apply_samples(z, 5, samples, out);
  for (int i = 0; i < 25; ++i) EXPECT_NEAR(out[i], f[i], kZhfTolerance) << "i " << i;
}

TEST(ZhfRotation, LoaderRejectsBadTables) {
  auto missing = ZhfLobes::load("/nonexistent/zhf.shtb");
  EXPECT_FALSE(missing.ok());
  // A table of another kind.
  Table other;
  other.kind = "tripling-tensor";
  other.order = 2;
  other.generator = generator_record("test", nlohmann::json::object()).dump();
  other.arrays.push_back(TableArray::from<double>("value", {1}, std::vector<double>{1.0}));
  const auto path = std::filesystem::temp_directory_path() / "shtool_test_zhf_wrongkind.shtb";
  ASSERT_TRUE(shtool::test::try_write(other, path).ok());
  auto wrong = ZhfLobes::load(path);
  EXPECT_FALSE(wrong.ok());
  if (!wrong.ok()) EXPECT_NE(wrong.error().message.find("zhf-lobes"), std::string::npos) << wrong.error().message;
  std::filesystem::remove(path);
  // A per-band table (bands 2..) cannot rotate on its own.
  const auto bands = tables_dir() / "zhf-bands-l2-10.shtb";
  if (std::filesystem::exists(bands)) {
    auto b = ZhfLobes::load(bands);
    ASSERT_FALSE(b.ok());
    EXPECT_NE(b.error().message.find("band 0"), std::string::npos) << b.error().message;
  }
  // Asking for more bands than the table holds.
  const auto p4 = tables_dir() / "zhf-shared-N4.shtb";
  if (std::filesystem::exists(p4)) EXPECT_FALSE(ZhfLobes::load(p4).value().bands_below(5).ok());
}

}  // namespace
