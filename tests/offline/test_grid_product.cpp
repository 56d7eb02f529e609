// The quadrature ("grid") products (shtool/grid_product.h): triple products against the
// exact tripling tensor (Wigner 3j, offline construction) and the runtime one, accurate
// k-multiple products against the SH projection of the pointwise product by an
// independent sphere quadrature of eval_sh (N up to 20, k up to 8), triple product
// integrals, closed forms, aliasing, determinism, grid sizes and bad arguments.
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <initializer_list>
#include <new>
#include <numbers>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "shtool/grid_product.h"
#include "shtool/product.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"
#include "shtool/tripling_product.h"
#include "tensors/tripling.h"
#include "test_util.h"

#include "allocation_counter.h"  // counts this program's allocations

namespace shtool {
namespace {

using namespace test;

// The required accuracy for accurate products in double: 1e-10 relative.
constexpr double kTolDouble = 1e-10;
// float: 24-bit mantissa; each output sums O(N) Legendre terms per ring over O(N) rings
// and an FFT of O(N) points per input; measured 9e-8 to 3.0e-7 (N = 3..20, k = 3..8),
// so 2e-6 leaves a margin of about 7 without hiding an O(1) error.
constexpr double kTolFloat = 2e-6;

template <class T>
std::vector<T> grid_multiply(int order, const std::vector<std::vector<double>>& f,
                             GridAzimuth azimuth = GridAzimuth::automatic) {
  std::vector<std::vector<T>> ft;
  for (const auto& v : f) ft.emplace_back(v.begin(), v.end());
  std::vector<std::span<const T>> spans(ft.begin(), ft.end());
  std::vector<T> g(sh_count(order));
  GridProduct<T>(order, static_cast<int>(f.size()), azimuth).multiply(spans, g);
  return g;
}

// Both azimuthal methods are exact; each is checked on its own.
constexpr GridAzimuth kMethods[] = {GridAzimuth::direct, GridAzimuth::fft};
std::string name(GridAzimuth a) { return a == GridAzimuth::direct ? "direct" : "fft"; }

TEST(GridProduct, TripleAgainstExactTriplingTensor) {
  // Wigner 3j construction (src/offline/tensors/tripling.cpp) for N <= 12; the runtime
  // Gauss-Legendre construction (itself tested against 3j) at N = 16 and 20.
  for (int order : {1, 2, 3, 4, 5, 7, 8, 12, 16, 20}) {
    const TriplingTensor tensor =
        order <= 12 ? compute_tripling_tensor_exact(order) : TriplingTensor::compute(order);
    const auto f = random_inputs(order, 2, 300 + order);
    std::vector<double> ref(sh_count(order));
    TriplingProduct<double>(tensor).multiply(f[0], f[1], ref);
    for (const GridAzimuth a : kMethods) {
      const double err = relative_l2(grid_multiply<double>(order, f, a), ref);
      EXPECT_LT(err, kTolDouble) << name(a) << " N " << order << ": relative L2 " << sci(err);
      RecordProperty(name(a) + "_triple_rel_l2_N" + std::to_string(order), sci(err));
    }
  }
}

struct Case {
  int order, inputs;
};

// Product of `inputs` + 1 random vectors in T against the quadrature projection, by
// each azimuthal method; errors recorded as test properties (prefix + "_rel_l2_N.._k..").
template <class T>
void check_multiple(std::initializer_list<Case> cases, int seed_base, int seed_order, double tol,
                    const std::string& prefix) {
  for (const Case c : cases) {
    const auto f = random_inputs(c.order, c.inputs, seed_base + c.order * seed_order + c.inputs);
    const std::vector<double> ref = reference_product(c.order, f);
    for (const GridAzimuth a : kMethods) {
      const double err = relative_l2(grid_multiply<T>(c.order, f, a), ref);
      EXPECT_LT(err, tol) << name(a) << " N " << c.order << " k " << c.inputs + 1 << ": " << sci(err);
      ::testing::Test::RecordProperty(name(a) + prefix + "_rel_l2_N" + std::to_string(c.order) + "_k" +
                                          std::to_string(c.inputs + 1),
                                      sci(err));
    }
  }
}

TEST(GridProduct, MultipleAgainstQuadratureDouble) {
  // k = inputs + 1 up to 8, N up to 20.
  check_multiple<double>({Case{1, 2}, Case{2, 7}, Case{3, 2}, Case{4, 3}, Case{5, 1}, Case{6, 5}, Case{10, 2},
                          Case{10, 7}, Case{13, 4}, Case{20, 2}, Case{20, 3}, Case{20, 5}, Case{20, 7}},
                         100, 10, kTolDouble, "");
}

TEST(GridProduct, MultipleAgainstQuadratureFloat) {
  check_multiple<float>({Case{3, 2}, Case{5, 2}, Case{8, 2}, Case{12, 3}, Case{20, 2}, Case{20, 3}, Case{20, 7}}, 7,
                        1, kTolFloat, "_float");
}

TEST(GridProduct, ClosedFormSquareOfY10) {
  // (c z)^2 with c^2 = 3/(4 pi): z^2 = 1/3 + (2/3) P_2, so y_1^0 y_1^0 projects to
  // 1/sqrt(4 pi) y_0^0 + 1/sqrt(5 pi) y_2^0 (order 2 keeps band 0 only).
  for (int order : {2, 3, 6}) {
    std::vector<double> y10(sh_count(order), 0.0);
    y10[2] = 1.0;
    for (const GridAzimuth a : kMethods) {
      const std::vector<double> g = grid_multiply<double>(order, {y10, y10}, a);
      for (int i = 0; i < sh_count(order); ++i) {
        const double expected = i == 0   ? 0.5 / std::sqrt(std::numbers::pi)
                                : i == 6 ? 1.0 / std::sqrt(5.0 * std::numbers::pi)
                                         : 0.0;
        EXPECT_NEAR(g[i], expected, 1e-15) << name(a) << " N " << order << " coefficient " << i;
      }
    }
  }
}

TEST(GridProduct, IntegralsAgainstQuadrature) {
  // Triple product integral (Eq. 4) and a 5-function integral, against <P_N(f_1..f_q), f_last>.
  for (const Case c : {Case{4, 2}, Case{9, 2}, Case{20, 2}, Case{7, 4}}) {
    const auto f = random_inputs(c.order, c.inputs + 1, 40 + c.order);
    const std::vector<double> ref =
        reference_product(c.order, std::vector<std::vector<double>>(f.begin(), f.end() - 1));
    double expected = 0;
    for (int i = 0; i < sh_count(c.order); ++i) expected += ref[i] * f.back()[i];
    std::vector<std::span<const double>> spans(f.begin(), f.end());
    for (const GridAzimuth a : kMethods) {
      const double got = GridProduct<double>(c.order, c.inputs, a).integral(spans);
      EXPECT_NEAR(got, expected, 1e-12 * (std::abs(expected) + 1)) << name(a) << " N " << c.order;
    }
  }
}

class GridAliasing : public ::testing::TestWithParam<GridAzimuth> {};

TEST_P(GridAliasing, AliasingReuseAndDeterminism) {
  const int order = 11;
  const auto f = random_inputs(order, 2, 5);
  GridProduct<double> product(order, 2, GetParam());
  std::vector<double> a(sh_count(order)), b = f[0];
  product.multiply(f[0], f[1], a);
  product.multiply(b, f[1], b);  // output aliases the first input
  EXPECT_EQ(a, b);
  // Reuse: a different product in between must not leave state behind.
  const auto h = random_inputs(order, 2, 6);
  std::vector<double> scratch(sh_count(order)), c(sh_count(order));
  product.multiply(h[0], h[1], scratch);
  product.multiply(f[0], f[1], c);
  EXPECT_EQ(a, c);
  std::vector<double> d(sh_count(order));
  GridProduct<double>(order, 2, GetParam()).multiply(f[0], f[1], d);  // fresh object: same bits
  EXPECT_EQ(a, d);
  // Moved: the new owner has the sizes and gives the same bits.
  GridProduct<double> moved = std::move(product);
  EXPECT_EQ(moved.order(), order);
  EXPECT_EQ(moved.inputs(), 2);
  std::vector<double> m(sh_count(order));
  moved.multiply(f[0], f[1], m);
  EXPECT_EQ(a, m);
  GridProduct<double> assigned(3, 3, GetParam());
  assigned = GridProduct<double>(order, 2, GetParam());
  std::vector<double> e(sh_count(order));
  assigned.multiply(f[0], f[1], e);
  EXPECT_EQ(a, e);
}
static_assert(!std::is_copy_constructible_v<GridProduct<double>> && !std::is_copy_assignable_v<GridProduct<double>>);
static_assert(std::is_nothrow_move_constructible_v<GridProduct<double>> &&
              std::is_nothrow_move_assignable_v<GridProduct<double>>);
static_assert(!std::is_copy_constructible_v<FourierProduct<float>> &&
              std::is_nothrow_move_constructible_v<FourierProduct<float>>);
INSTANTIATE_TEST_SUITE_P(Methods, GridAliasing, ::testing::ValuesIn(kMethods),
                         [](const auto& info) { return name(info.param); });

TEST(GridProduct, GridSizesAreTheExactnessBounds) {
  for (const Case c : {Case{1, 2}, Case{3, 2}, Case{10, 2}, Case{20, 2}, Case{20, 7}}) {
    const int degree = (c.inputs + 1) * (c.order - 1);
    const GridProduct<float> fft(c.order, c.inputs, GridAzimuth::fft);
    EXPECT_EQ(fft.grid_theta(), degree / 2 + 1) << "N " << c.order;
    EXPECT_GE(fft.grid_phi(), degree + 1) << "N " << c.order;
    EXPECT_EQ(fft.grid_phi() % 2, 0);
    const GridProduct<float> direct(c.order, c.inputs, GridAzimuth::direct);
    EXPECT_EQ(direct.grid_theta(), degree / 2 + 1) << "N " << c.order;
    EXPECT_EQ(direct.grid_phi(), degree + 1) << "N " << c.order;
  }
  // 58 -> 72, not 60: FFTW_ESTIMATE transforms of 60 points measured 1.5-1.9x slower.
  EXPECT_EQ(GridProduct<double>(20, 2, GridAzimuth::fft).grid_phi(), 72);
  EXPECT_EQ(GridProduct<double>(3, 2, GridAzimuth::fft).grid_phi(), 8);
  // automatic: direct sums for the small grids, FFTW for the large ones
  EXPECT_EQ(GridProduct<double>(8, 2).azimuth(), GridAzimuth::direct);
  EXPECT_EQ(GridProduct<double>(20, 7).azimuth(), GridAzimuth::fft);
  EXPECT_EQ(GridProduct<float>(20, 7).azimuth(), GridAzimuth::direct);
}

// Products are built once and applied many times per frame: after construction (and
// ShProduct::prepare) no call may allocate.
TEST(Products, HotPathsAllocateNothing) {
  for (const int order : {4, 8, 20}) {
    const auto f = random_inputs(order, 4, 9);
    std::vector<std::vector<float>> ff;
    for (const auto& v : f) ff.emplace_back(v.begin(), v.end());
    const std::vector<std::span<const double>> two(f.begin(), f.begin() + 2), four(f.begin(), f.end());
    const std::vector<std::span<const float>> twof(ff.begin(), ff.begin() + 2);
    std::vector<double> g(sh_count(order));
    std::vector<float> gf(sh_count(order));
    GridProduct<double> direct(order, 2, GridAzimuth::direct), fft(order, 2, GridAzimuth::fft);
    GridProduct<float> directf(order, 2, GridAzimuth::direct);
    const TriplingProduct<double> tripling(TriplingTensor::compute(order));
    ShProduct<double> automatic(order);
    automatic.prepare(2);
    automatic.prepare(4);
    const std::span<const double> spans3[3] = {f[0], f[1], f[2]};

    const long before = test::allocation_count();
    direct.multiply(two, g);
    fft.multiply(two, g);
    directf.multiply(twof, gf);
    double sum = direct.integral(std::span<const std::span<const double>>(spans3, 3)) +
                 fft.integral(std::span<const std::span<const double>>(spans3, 3));
    tripling.multiply(f[0], f[1], g);
    sum += tripling.integral(f[0], f[1], f[2]);
    automatic.triple(f[0], f[1], g);
    automatic.multiple(four, g);
    automatic.recursive(four, g);
    EXPECT_EQ(test::allocation_count() - before, 0) << "N " << order << ": allocations in a product";
    EXPECT_TRUE(std::isfinite(sum + g[0] + gf[0]));
  }
  // The counter works: building a product allocates.
  const long before = test::allocation_count();
  { const GridProduct<double> p(5, 2); }
  EXPECT_GT(test::allocation_count(), before);
}

TEST(GridProduct, BadArgumentsThrow) {
  EXPECT_THROW(GridProduct<double>(0, 2), std::invalid_argument);
  EXPECT_THROW(GridProduct<double>(kMaxFourierProductOrder + 1, 2), std::invalid_argument);
  EXPECT_THROW(GridProduct<double>(5, 0), std::invalid_argument);
  EXPECT_THROW(GridProduct<double>(5, kMaxProductInputs + 1), std::invalid_argument);
  GridProduct<double> p(3, 2);
  const std::vector<double> f(9, 1.0);
  std::vector<double> g(9);
  const std::span<const double> one[1] = {f};
  EXPECT_THROW(p.multiply(std::span<const std::span<const double>>(one, 1), g), std::invalid_argument);
  EXPECT_THROW(p.integral(std::span<const std::span<const double>>(one, 1)), std::invalid_argument);
  // Spans shorter than N^2 are refused, not read or written past their end.
  const std::vector<double> short_f(8, 1.0);
  std::vector<double> short_g(8);
  EXPECT_THROW(p.multiply(f, short_f, g), std::invalid_argument);
  EXPECT_THROW(p.multiply(f, f, short_g), std::invalid_argument);
  const std::span<const double> three[3] = {f, f, short_f};
  EXPECT_THROW(p.integral(std::span<const std::span<const double>>(three, 3)), std::invalid_argument);
  try {
    p.multiply(short_f, f, g);
    FAIL() << "no exception for a short input";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("GridProduct::multiply: an input holds 8 values, 9 needed"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace shtool
