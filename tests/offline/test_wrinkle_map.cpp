// The runtime's wrinkle map (shtool/wrinkle_map.h): a fitted map's table loads and
// reproduces its model, bad tables are refused by name, node values come back, the blend
// is the offline model's bit for bit, shading equals the rotated SH transfer dotted with
// the lighting, turning light and frame together changes nothing, and the flat groove
// shades as the unshadowed plane.
#include <array>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <Eigen/Geometry>

#include "shtool/irradiance.h"
#include "shtool/rotation.h"
#include "shtool/sh.h"
#include "shtool/wrinkle_map.h"
#include "wrinkles/wrinkle_fit.h"
#include "wrinkles/wrinkle_job.h"
#include "wrinkles/wrinkle_model.h"
#include "wrinkle_test_model.h"

namespace {

using namespace shtool;
using namespace shtool::wrinkles;

WrinkleModel smooth_random_model(const WrinkleGrid& grid, int order, int lobes, unsigned seed) {
  return test::random_wrinkle_model(grid, order, lobes, seed, test::WrinkleAxes::smooth);
}

// The table fit-wrinkles would write for this model.
Table table_of(const WrinkleModel& m) {
  WrinkleFit fit;
  fit.model = m;
  WrinkleRequest request;
  request.order = m.order;
  request.lobes = m.lobes;
  request.grid = m.grid.grid;
  request.samples = m.grid.samples;
  request.max_depth = m.grid.max_depth;
  return wrinkle_table(fit, request);
}

TableArray* array(Table& t, const std::string& name) {
  for (TableArray& a : t.arrays)
    if (a.name == name) return &a;
  return nullptr;
}

void set_value(Table& t, const std::string& name, std::size_t index, double value) {
  TableArray* a = array(t, name);
  std::vector<double> v = a->values<double>();
  v[index] = value;
  *a = TableArray::from<double>(a->name, a->shape, v);
}

Eigen::Matrix3d random_rotation(std::mt19937_64& rng) {
  std::normal_distribution<double> n;
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized().toRotationMatrix();
}

std::vector<double> random_light(int order, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<double> e(static_cast<std::size_t>(order) * order);
  for (double& v : e) v = u(rng);
  return e;
}

const WrinkleGrid kGrid{5, 2, 0.8};

TEST(WrinkleMap, LoadsTheTableOfAModel) {
  const WrinkleModel m = smooth_random_model(kGrid, 5, 3, 1);
  const Result<WrinkleMap<double>> map = WrinkleMap<double>::from_table(table_of(m));
  ASSERT_TRUE(map.ok()) << map.error().message;
  EXPECT_EQ(map.value().order, 5);
  EXPECT_EQ(map.value().lobes, 3);
  EXPECT_EQ(map.value().grid, 5);
  EXPECT_EQ(map.value().max_depth, 0.8);
  EXPECT_EQ(map.value().axes, m.axes);
  EXPECT_EQ(map.value().coeffs, m.coeffs);
  EXPECT_EQ(map.value().direct, m.direct);
  EXPECT_TRUE(WrinkleMap<float>::from_table(table_of(m)).ok());
}

TEST(WrinkleMap, BadTablesAreRefusedByName) {
  const WrinkleModel m = smooth_random_model(kGrid, 4, 2, 2);
  const Table good = table_of(m);
  ASSERT_TRUE(WrinkleMap<double>::from_table(good).ok());
  struct Bad {
    const char* what;
    std::function<void(Table&)> spoil;
    const char* message;
  };
  const Bad bad[] = {
      {"kind", [](Table& t) { t.kind = "zh-fit"; }, "wrong kind 'zh-fit'"},
      {"order", [](Table& t) { t.order = 9; }, "order 9"},
      {"grid", [](Table& t) { t.meta = R"({"grid": 1, "lobes": 2, "max_depth": 0.8})"; }, "'grid'"},
      {"lobes", [](Table& t) { t.meta = R"({"grid": 5, "lobes": 5, "max_depth": 0.8})"; }, "'lobes'"},
      {"max_depth", [](Table& t) { t.meta = R"({"grid": 5, "lobes": 2, "max_depth": -1})"; }, "'max_depth'"},
      {"axes shape",
       [](Table& t) {
         TableArray* a = array(t, "axes");
         *a = TableArray::from<double>("axes", {5, 5, 2, 2}, std::vector<double>(100, 1.0));
       },
       "array 'axes' has shape [5, 5, 2, 2], expected [5, 5, 2, 3]"},
      {"coeffs missing", [](Table& t) { array(t, "coeffs")->name = "other"; }, "missing array 'coeffs'"},
      {"direct dtype",
       [](Table& t) { *array(t, "direct") = TableArray::from<float>("direct", {5, 5, 4}, std::vector<float>(100)); },
       "array 'direct' is not f64"},
      {"NaN", [](Table& t) { set_value(t, "coeffs", 7, std::nan("")); }, "array 'coeffs' element 7 is not finite"},
      {"infinity", [](Table& t) { set_value(t, "direct", 3, INFINITY); }, "array 'direct' element 3 is not finite"},
      {"node x", [](Table& t) { set_value(t, "x", 2, 0.41); }, "x[2]"},
      {"node depth", [](Table& t) { set_value(t, "depth", 4, 1.0); }, "depth[4]"},
      {"band 1 in a lobe", [](Table& t) { set_value(t, "coeffs", 4 + 1, 0.5); }, "bands 0 and 1"},
      {"zero axis",
       [](Table& t) {
         for (int c = 0; c < 3; ++c) set_value(t, "axes", (7 * 2 + 1) * 3 + c, 0.0);
       },
       "axis of lobe 1 at node 7 is zero"},
      // Node axes are not unit in a valid map (the blend normalises); what a map must not
      // hold is a cell whose axes can cancel.
      {"opposite axes",
       [](Table& t) {
         for (int c = 0; c < 3; ++c) set_value(t, "axes", (6 * 2 + 0) * 3 + c, -array(t, "axes")->values<double>()[(6 * 2) * 3 + c]);
       },
       "can blend to zero"},
  };
  for (const Bad& b : bad) {
    Table t = good;
    b.spoil(t);
    const Result<WrinkleMap<double>> map = WrinkleMap<double>::from_table(t);
    ASSERT_FALSE(map.ok()) << b.what;
    EXPECT_NE(map.error().message.find(b.message), std::string::npos) << b.what << ": " << map.error().message;
    EXPECT_EQ(map.error().message.rfind("wrinkle-zh table: ", 0), 0u) << map.error().message;
    EXPECT_FALSE(WrinkleMap<float>::from_table(t).ok()) << b.what;
  }
  // A float map refuses values its shading sums cannot carry (max / 2^64); a double map
  // takes them, up to its own limit.
  Table big = good;
  set_value(big, "direct", 0, 1e30);
  EXPECT_FALSE(WrinkleMap<float>::from_table(big).ok());
  EXPECT_TRUE(WrinkleMap<double>::from_table(big).ok());
  set_value(big, "direct", 0, 1e300);
  EXPECT_FALSE(WrinkleMap<double>::from_table(big).ok());
  // Axes a float cannot normalise: 1e20 (its square overflows) and 3e-23 (its square is
  // below the smallest normal float, and the normalised axis came out 0.8 long).
  for (const double length : {1e20, 3e-23}) {
    Table t = good;
    const std::vector<double> axes = array(t, "axes")->values<double>();
    const double norm = std::sqrt(axes[27] * axes[27] + axes[28] * axes[28] + axes[29] * axes[29]);
    for (int c = 0; c < 3; ++c) set_value(t, "axes", 9 * 3 + c, axes[9 * 3 + c] / norm * length);
    const Result<WrinkleMap<float>> f = WrinkleMap<float>::from_table(t);
    ASSERT_FALSE(f.ok()) << length;
    // 3e-23 squared may flush to float zero: "is zero" then says the same.
    const std::string& m = f.error().message;
    EXPECT_TRUE(m.find("cannot be normalised in the requested precision") != std::string::npos ||
                (length < 1 && m.find("axis of lobe 1 at node 4 is zero") != std::string::npos))
        << m;
    EXPECT_TRUE(WrinkleMap<double>::from_table(t).ok()) << length;
  }
}

TEST(WrinkleMap, NodesGiveTheStoredValues) {
  const WrinkleModel m = smooth_random_model(kGrid, 5, 3, 3);
  const WrinkleMap<double> map = WrinkleMap<double>::from_table(table_of(m)).value();
  const int g = kGrid.grid;
  WrinkleLobes<double> lobes;
  for (int k = 0; k < g; ++k)
    for (int j = 0; j < g; ++j) {
      map.lobes_at(kGrid.node_x(j), kGrid.node_depth(k), lobes);
      const std::size_t node = static_cast<std::size_t>(k) * g + j;
      // j / G * G and d_k / max_depth * (G - 1) may miss the integer by an ulp, leaving
      // a weight of ~1e-16 on a neighbour: 1e-14 covers that, any real blend is >> 1e-3.
      for (int i = 0; i < 4; ++i) EXPECT_NEAR(lobes.direct[i], m.direct[node * 4 + i], 1e-14) << k << " " << j;
      for (int i = 0; i < 3; ++i) {
        const Eigen::Vector3d stored(&m.axes[(node * 3 + i) * 3]);
        EXPECT_LT((lobes.axes[i] - stored.normalized()).norm(), 1e-14) << k << " " << j << " lobe " << i;
        for (int l = 0; l < 5; ++l)
          EXPECT_NEAR(lobes.coeffs[i * 5 + l], m.coeffs[(node * 3 + i) * 5 + l], 1e-14) << k << " " << j;
      }
    }
  // x is periodic and d clamps: x = 1 is node column 0, d beyond max_depth the last row.
  WrinkleLobes<double> a, b;
  map.lobes_at(1.0 + 2.0, 0.3, a);
  map.lobes_at(0.0, 0.3, b);
  EXPECT_EQ(a.direct, b.direct);
  map.lobes_at(0.37, 5.0, a);
  map.lobes_at(0.37, kGrid.max_depth, b);
  EXPECT_EQ(a.direct, b.direct);
  map.lobes_at(0.37, -1.0, a);
  map.lobes_at(0.37, 0.0, b);
  EXPECT_EQ(a.direct, b.direct);
}

TEST(WrinkleMap, BlendIsTheOfflineModelsBitForBit) {
  const WrinkleModel m = smooth_random_model(kGrid, 6, 3, 4);
  const WrinkleMap<double> map = WrinkleMap<double>::from_table(table_of(m)).value();
  const WrinkleMap<float> mapf = WrinkleMap<float>::from_table(table_of(m)).value();
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> ux(-2.0, 3.0), ud(-0.2, 1.0);
  std::vector<double> offline(36), runtime(36), y(36);
  for (int trial = 0; trial < 500; ++trial) {
    const double x = ux(rng), d = ud(rng);
    const BilinearWeights wo = bilinear_weights(m.grid, x, d);
    const WrinkleWeights<double> wr = map.weights(x, d);
    for (int c = 0; c < 4; ++c) {
      ASSERT_EQ(wo.node[c], wr.node[c]);
      ASSERT_EQ(wo.weight[c], wr.weight[c]);
    }
    evaluate_model(m, wo, offline);
    WrinkleLobes<double> lobes;
    map.lobes_at(x, d, lobes);
    std::fill(runtime.begin(), runtime.end(), 0.0);
    for (int i = 0; i < 4; ++i) runtime[i] = lobes.direct[i];
    for (int i = 0; i < 3; ++i) {
      eval_sh<double>(6, lobes.axes[i], y);
      for (int l = 0; l < 6; ++l)
        for (int mm = -l; mm <= l; ++mm) runtime[sh_index(l, mm)] += lobes.coeffs[i * 6 + l] * y[sh_index(l, mm)];
    }
    for (int i = 0; i < 36; ++i) ASSERT_EQ(offline[i], runtime[i]) << "x " << x << " d " << d << " i " << i;
    // The float map: the same blend in float, so within float rounding of the double one.
    WrinkleLobes<float> lf;
    mapf.lobes_at(static_cast<float>(x), static_cast<float>(d), lf);
    for (int i = 0; i < 4; ++i) EXPECT_NEAR(lf.direct[i], lobes.direct[i], 2e-5) << x << " " << d;
    // Shading in float: within float rounding of double over ~40 terms of size ~1.
    std::vector<double> e(36, 0.25);
    const std::vector<float> ef(e.begin(), e.end());
    EXPECT_NEAR(mapf.shade(ef, Eigen::Matrix3f::Identity(), static_cast<float>(x), static_cast<float>(d)),
                map.shade(e, Eigen::Matrix3d::Identity(), x, d), 1e-4) << x << " " << d;
  }
}

// What the tests of shading in turned frames share: the map of a smooth random model of
// order n, seeded draws of its points, of frames and of lights, and an exact SH rotation
// of order n.
struct TurnedFrameTrials {
  int n;
  WrinkleModel model;
  WrinkleMap<double> map;
  std::mt19937_64 rng;
  std::uniform_real_distribution<double> u{0.0, 1.0};
  ShRotation<double> rotation;

  TurnedFrameTrials(int order, int lobes, unsigned model_seed, unsigned draw_seed)
      : n(order),
        model(smooth_random_model(kGrid, order, lobes, model_seed)),
        map(WrinkleMap<double>::from_table(table_of(model)).value()),
        rng(draw_seed),
        rotation(order, nullptr) {}

  // (x, d) with d below the deepest node.
  std::array<double, 2> point() {
    const double x = u(rng);
    return {x, 0.8 * u(rng)};
  }
  Eigen::Matrix3d frame() { return random_rotation(rng); }
  std::vector<double> light() { return random_light(n, rng); }
};

// The SH transfer of the groove frame, rotated into the surface frame by an exact SH
// rotation and dotted with the lighting, is what shading gives: this pins the turned axes
// and the turned linear band (a transposed frame or a band-1 sign slip is off by O(1)).
TEST(WrinkleMap, ShadingIsTheRotatedTransferDottedWithTheLight) {
  TurnedFrameTrials s(5, 2, 6, 7);
  const int n = s.n;
  std::vector<double> t(n * n), turned(n * n);
  for (int trial = 0; trial < 50; ++trial) {
    const auto [x, d] = s.point();
    const Eigen::Matrix3d frame = s.frame();
    const std::vector<double> e = s.light();
    evaluate_model(s.model, bilinear_weights(s.model.grid, x, d), t);
    ASSERT_TRUE(s.rotation.set(frame, RotationMethod::reference));
    s.rotation.apply(std::span<const double>(t), turned);
    double expected = 0;
    for (int i = 0; i < n * n; ++i) expected += turned[i] * e[i];
    // Two evaluations of the same sum in different orders, |terms| ~ 1: 1e-12.
    EXPECT_NEAR(s.map.shade(e, frame, x, d), expected, 1e-12) << "x " << x << " d " << d;
  }
  const std::vector<double> short_light(9, 1.0);
  EXPECT_TRUE(std::isnan(s.map.shade(short_light, Eigen::Matrix3d::Identity(), 0.5, 0.5)));
  EXPECT_TRUE(std::isnan(s.map.shade(std::vector<double>(25, 1.0), Eigen::Matrix3d::Identity(), NAN, 0.5)));
}

TEST(WrinkleMap, TurningLightAndFrameTogetherChangesNothing) {
  TurnedFrameTrials s(6, 3, 8, 9);
  std::vector<double> turned(s.n * s.n);
  for (int trial = 0; trial < 50; ++trial) {
    const auto [x, d] = s.point();
    const Eigen::Matrix3d frame = s.frame(), q = s.frame();
    const std::vector<double> e = s.light();
    ASSERT_TRUE(s.rotation.set(q, RotationMethod::reference));
    s.rotation.apply(std::span<const double>(e), turned);
    const double before = s.map.shade(e, frame, x, d), after = s.map.shade(turned, q * frame, x, d);
    // The reference rotation's rounding at order 6 over |terms| ~ 1: 1e-11. A light turned
    // by Q^T instead of Q, or the frame left alone, changes the value by O(1).
    EXPECT_NEAR(after, before, 1e-11) << "x " << x << " d " << d;
    EXPECT_GT(std::abs(s.map.shade(turned, frame, x, d) - before), 1e-6) << "the light's turn must matter";
  }
}

// A real fit of the flat groove (d = 0 is an open plane) shades as the unshadowed plane:
// t_lm = A_l / pi y_lm(n), so r = sum_l A_l / pi sum_m y_lm(R z) e_lm, in any frame R.
TEST(WrinkleMap, FlatGrooveShadesAsTheUnshadowedPlane) {
  const int n = 3;
  const WrinkleGrid grid{4, 1, 1.0};
  SimulationOptions sim;
  sim.order = n;
  sim.rays = 4096;
  sim.threads = 2;
  const std::vector<double> transfer = simulate_transfer(grid, sim);
  WrinkleFitOptions options;
  options.order = n;
  options.lobes = 1;
  options.threads = 2;
  options.max_evaluations = 200;
  WrinkleFit fit = fit_wrinkles(grid, transfer, options);
  WrinkleRequest request;
  request.order = n;
  request.lobes = 1;
  request.grid = grid.grid;
  request.samples = grid.samples;
  const Result<WrinkleMap<double>> loaded = WrinkleMap<double>::from_table(wrinkle_table(fit, request));
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const WrinkleMap<double>& map = loaded.value();
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<double> y(n * n);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix3d frame = random_rotation(rng);
    const std::vector<double> e = random_light(n, rng);
    eval_sh<double>(n, Vec3<double>(frame.col(2)), y);
    double expected = 0, scale = 0;
    for (int l = 0; l < n; ++l)
      for (int mm = -l; mm <= l; ++mm) {
        expected += clamped_cosine_band(l) / std::numbers::pi * y[sh_index(l, mm)] * e[sh_index(l, mm)];
        scale += e[sh_index(l, mm)] * e[sh_index(l, mm)];
      }
    const double x = u(rng);
    // The simulated plane is within 2e-3 per coefficient at 4096 rays (the wrinkle tests'
    // bound) and the fit adds its residual there (0.0035 normalized RMS at the defaults):
    // 6e-3 |e|. A frame used as its transpose or a lost band misses by ~0.1 |e|.
    EXPECT_NEAR(map.shade(e, frame, x, 0.0), expected, 6e-3 * std::sqrt(scale)) << "x " << x;
  }
}

}  // namespace
