// Tripling tensor C_ijk = integral y_i y_j y_k ([3] Eq. 5): the exact Wigner-3j
// construction (src/offline/tensors/tripling.h) against identities of the 3j symbols, against a
// sphere quadrature of eval_sh (an independent route through the SH evaluator, so it
// also checks the real-basis signs), and against the runtime's Gauss-Legendre
// construction; selection rules, symmetry, table round trip; the sparse product.
#include <cmath>
#include <string>
#include <cstdio>
#include <filesystem>
#include <unistd.h>
#include <map>
#include <numbers>
#include <random>
#include <set>
#include <algorithm>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "table_test_util.h"

#include "test_util.h"
#include "shtool/quadrature.h"
#include "shtool/sh.h"
#include "shtool/tripling_product.h"
#include "generated_source.h"
#include "run_command.h"
#include "kernels/tripling_kernels.h"
#include "tensors/fourier_tables.h"
#include "tensors/tripling.h"
#include "tensors/tripling_kernels_gen.h"

namespace shtool {
namespace {

using test::sci;

// Dense C by a sphere rule exact for degree 3(N-1) (the integrand's degree), from the
// double-precision SH evaluator: rounding ~1e-16 per term, a few hundred terms.
constexpr double kQuadratureTol = 1e-14;
// The project's accuracy claim for the stored coefficients: 1e-13.
constexpr double kTensorTol = 1e-13;

std::vector<double> dense_by_quadrature(int order) {
  const int n = sh_count(order);
  const SphereQuadrature q = sphere_quadrature(3 * (order - 1));
  std::vector<double> c(static_cast<std::size_t>(n) * n * n, 0.0), y(n);
  for (std::size_t p = 0; p < q.weights.size(); ++p) {
    eval_sh<double>(order, q.directions[p], y);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j) {
        const double wij = q.weights[p] * y[i] * y[j];
        for (int k = 0; k < n; ++k) c[(static_cast<std::size_t>(i) * n + j) * n + k] += wij * y[k];
      }
  }
  return c;
}

// The order-20 exact tensor takes ~2 s to build; two tests share one copy.
const TriplingTensor& exact_order20() {
  static const TriplingTensor t = compute_tripling_tensor_exact(20);
  return t;
}

TEST(Wigner3j, ClosedFormsAndOrthogonality) {
  // (j j 0; m -m 0) = (-1)^(j-m) / sqrt(2j+1).
  for (int j = 0; j <= 40; j += 7)
    for (int m = -j; m <= j; ++m) {
      const double expected = ((j - m) % 2 == 0 ? 1.0 : -1.0) / std::sqrt(2.0 * j + 1.0);
      EXPECT_NEAR(static_cast<double>(wigner_3j(j, j, 0, m, -m, 0)), expected, 1e-16)
          << "j " << j << " m " << m;
    }
  // (1 1 2; 1 -1 0) = 1/sqrt(30) (tabulated value).
  EXPECT_NEAR(static_cast<double>(wigner_3j(1, 1, 2, 1, -1, 0)), 1.0 / std::sqrt(30.0), 1e-16);
  // sum_{m1,m2} (2 j3 + 1) (j1 j2 j3; m1 m2 m3)(j1 j2 j3'; m1 m2 m3) = delta_{j3 j3'}:
  // large j, where Racah's alternating sum cancels most.
  const int j1 = 30, j2 = 27;
  for (int j3 : {3, 30, 57})
    for (int j3p : {j3, j3 + 2}) {
      if (j3p > j1 + j2) continue;
      const int m3 = 2;
      long double sum = 0;
      for (int m1 = -j1; m1 <= j1; ++m1) {
        const int m2 = m3 - m1;
        if (std::abs(m2) > j2) continue;
        sum += wigner_3j(j1, j2, j3, m1, m2, -m3) * wigner_3j(j1, j2, j3p, m1, m2, -m3);
      }
      // Summing over m1 only (m3 fixed) gives delta / (2 j3 + 1).
      const double expected = j3 == j3p ? 1.0 / (2.0 * j3 + 1.0) : 0.0;
      EXPECT_NEAR(static_cast<double>(sum), expected, 1e-17) << "j3 " << j3 << " j3' " << j3p;
    }
}

TEST(TriplingTensor, LowBandClosedForms) {
  // C_000 = 1 / sqrt(4 pi); C_{0,i,i} = 1 / sqrt(4 pi); C_{0,i,j} = 0 for i != j.
  const double c0 = 0.5 / std::sqrt(std::numbers::pi);
  EXPECT_NEAR(tripling_coefficient_exact(0, 0, 0), c0, 1e-17);
  for (int i = 0; i < 16; ++i) EXPECT_NEAR(tripling_coefficient_exact(0, i, i), c0, 1e-17) << i;
  // y_1^-1 y_1^1 = c^2 x y with c^2 = 3/(4 pi), and x y = sqrt(4 pi / 15) y_2^-2, so
  // C(1,-1; 1,1; 2,-2) = (3 / (4 pi)) sqrt(4 pi / 15) * ... computed by hand:
  // integral (c y)(c x) y_2^-2 with y_2^-2 = sqrt(15/(4 pi)) x y:
  // = c^2 sqrt(15/(4 pi)) integral x^2 y^2 = c^2 sqrt(15/(4 pi)) 4 pi / 15.
  const double c2 = 3.0 / (4.0 * std::numbers::pi);
  const double expected = c2 * std::sqrt(15.0 / (4.0 * std::numbers::pi)) * 4.0 * std::numbers::pi / 15.0;
  // Signs: y_1^-1 = -c y, y_1^1 = -c x, so their product is +c^2 x y.
  EXPECT_NEAR(tripling_coefficient_exact(sh_index(1, -1), sh_index(1, 1), sh_index(2, -2)),
              expected, 1e-16);
}

TEST(TriplingTensor, ExactMatchesDenseQuadratureAndSelectionRules) {
  const int order = 6;
  const int n = sh_count(order);
  const std::vector<double> dense = dense_by_quadrature(order);
  const TriplingTensor t = compute_tripling_tensor_exact(order);
  std::map<std::tuple<int, int, int>, double> stored;
  for (std::size_t e = 0; e < t.size(); ++e)
    stored[{static_cast<int>(t.index[3 * e]), static_cast<int>(t.index[3 * e + 1]),
            static_cast<int>(t.index[3 * e + 2])}] = t.value[e];
  int nonzero = 0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        int s[3] = {i, j, k};
        std::sort(s, s + 3);
        const auto it = stored.find({s[0], s[1], s[2]});
        const double sparse = it == stored.end() ? 0.0 : it->second;
        const double q = dense[(static_cast<std::size_t>(i) * n + j) * n + k];
        if (sparse != 0.0) ++nonzero;
        ASSERT_NEAR(sparse, q, kQuadratureTol) << "C(" << i << "," << j << "," << k << ")";
      }
  // Every permutation of every stored entry was visited: 6, 3 or 1 per entry.
  std::size_t expected = 0;
  for (std::size_t e = 0; e < t.size(); ++e) {
    const auto a = t.index[3 * e], b = t.index[3 * e + 1], c = t.index[3 * e + 2];
    expected += (a == b && b == c) ? 1 : (a == b || b == c) ? 3 : 6;
  }
  EXPECT_EQ(static_cast<std::size_t>(nonzero), expected);
}

TEST(TriplingTensor, ExactMatchesQuadratureAtOrder20) {
  // Sampled entries at the highest product order required (20); the dense check
  // above covers every index at a lower order.
  const int order = 20;
  const TriplingTensor& t = exact_order20();
  ASSERT_GT(t.size(), 0u);
  const SphereQuadrature q = sphere_quadrature(3 * (order - 1));
  std::vector<std::vector<double>> y(q.weights.size(), std::vector<double>(sh_count(order)));
  for (std::size_t p = 0; p < q.weights.size(); ++p) eval_sh<double>(order, q.directions[p], y[p]);
  std::mt19937 rng(7);
  std::uniform_int_distribution<std::size_t> pick(0, t.size() - 1);
  double worst = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t e = trial < 3 ? (trial == 0 ? 0 : trial == 1 ? t.size() - 1 : t.size() / 2)
                                    : pick(rng);
    const int i = t.index[3 * e], j = t.index[3 * e + 1], k = t.index[3 * e + 2];
    long double sum = 0;
    for (std::size_t p = 0; p < q.weights.size(); ++p)
      sum += static_cast<long double>(q.weights[p]) * y[p][i] * y[p][j] * y[p][k];
    worst = std::max(worst, std::abs(static_cast<double>(sum) - t.value[e]));
    ASSERT_NEAR(t.value[e], static_cast<double>(sum), kTensorTol)
        << "C(" << i << "," << j << "," << k << ")";
  }
  RecordProperty("max_abs_error_vs_quadrature", sci(worst));
}

TEST(TriplingTensor, RuntimeConstructionMatchesExact) {
  // Second construction: Gauss-Legendre in cos t with long-double accumulation, no 3j.
  for (int order : {1, 2, 9, 20}) {
    const TriplingTensor exact = order == 20 ? exact_order20() : compute_tripling_tensor_exact(order);
    const TriplingTensor quad = TriplingTensor::compute(order);
    ASSERT_EQ(exact.index, quad.index) << "order " << order << ": different non-zero sets";
    for (std::size_t e = 0; e < exact.size(); ++e)
      ASSERT_NEAR(exact.value[e], quad.value[e], 1e-14)
          << "order " << order << " entry " << e << " (" << exact.index[3 * e] << ","
          << exact.index[3 * e + 1] << "," << exact.index[3 * e + 2] << ")";
  }
}

TEST(TriplingTensor, SymmetryAndRules) {
  // C is symmetric in its three indices (the formula sorts by |m|; check it does not
  // depend on argument order) and vanishes where the rules say so.
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> idx(0, sh_count(8) - 1);
  for (int trial = 0; trial < 500; ++trial) {
    const int i = idx(rng), j = idx(rng), k = idx(rng);
    const double c = tripling_coefficient_exact(i, j, k);
    EXPECT_EQ(c, tripling_coefficient_exact(j, i, k));
    EXPECT_EQ(c, tripling_coefficient_exact(k, j, i));
    EXPECT_EQ(c, tripling_coefficient_exact(i, k, j));
    const int l1 = sh_band(i), l2 = sh_band(j), l3 = sh_band(k);
    if ((l1 + l2 + l3) % 2 != 0 || l3 > l1 + l2 || l3 < std::abs(l1 - l2))
      EXPECT_EQ(c, 0.0) << i << " " << j << " " << k;
  }
  // Canonical layout: sorted, i <= j <= k, rules hold (from_table validates all three).
  const TriplingTensor t = compute_tripling_tensor_exact(10);
  const Result<TriplingTensor> back =
      TriplingTensor::from_table(to_table(t, {{"tool", "test"}}));
  ASSERT_TRUE(back.ok()) << back.error().message;
  EXPECT_EQ(back.value().index, t.index);
  EXPECT_EQ(back.value().value, t.value);
}

TEST(TriplingTensor, FromTableRejectsCorruption) {
  const TriplingTensor t = compute_tripling_tensor_exact(4);
  {
    Table table = to_table(t, {{"tool", "test"}});
    table.kind = "rotation-helpers";
    EXPECT_FALSE(TriplingTensor::from_table(table).ok());
  }
  {
    TriplingTensor bad = t;
    bad.index[3 * 5 + 2] = 16;  // k outside order 4
    const auto r = TriplingTensor::from_table(to_table(bad, {{"tool", "test"}}));
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("i <= j <= k < N^2"), std::string::npos) << r.error().message;
  }
  {
    TriplingTensor bad = t;
    std::swap(bad.index[0], bad.index[3]);  // breaks the sort order (or i <= j)
    std::swap(bad.index[1], bad.index[4]);
    std::swap(bad.index[2], bad.index[5]);
    EXPECT_FALSE(TriplingTensor::from_table(to_table(bad, {{"tool", "test"}})).ok());
  }
  {
    TriplingTensor bad = t;
    // (0, 0, 1): C_{0,0,(1,-1)} is a structural zero.
    bad.index = {0, 0, 1};
    bad.value = {0.5};
    const auto r = TriplingTensor::from_table(to_table(bad, {{"tool", "test"}}));
    ASSERT_FALSE(r.ok());
    EXPECT_NE(r.error().message.find("selection rules"), std::string::npos) << r.error().message;
  }
}

TEST(TriplingTensor, TableBuilderHeader) {
  const Table table = tripling_tensor_table(5, {{"tool", "shtool"}, {"command", "test"}});
  EXPECT_EQ(table.kind, "tripling-tensor");
  EXPECT_EQ(table.order, 5);
  EXPECT_EQ(table_meta(table).at("nonzeros").get<std::int64_t>(), 238);  // counted by hand below
  // Count canonical non-zeros independently: every i <= j <= k whose dense quadrature
  // value is non-zero.
  const std::vector<double> dense = dense_by_quadrature(5);
  const int n = sh_count(5);
  int count = 0;
  for (int i = 0; i < n; ++i)
    for (int j = i; j < n; ++j)
      for (int k = j; k < n; ++k)
        if (std::abs(dense[(static_cast<std::size_t>(i) * n + j) * n + k]) > 1e-12) ++count;
  EXPECT_EQ(count, 238);
}


// Writes both gen-tensors tables (binary and JSON encodings), reads them back through
// the validating loader, and checks their headers against the JSON Schemas (and that a
// schema rejects the other kind, so the check can fail).
TEST(Tables, WriteReadAndValidateSchemas) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("shtool_products_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const nlohmann::json generator = {{"tool", "shtool"}, {"version", "test"},
                                    {"command", "test"}, {"parameters", {{"order", 4}}}};
  const std::filesystem::path trip = dir / "tripling-tensor.shtb";
  const std::filesystem::path four = dir / "sh-fourier-tensors.json";
  ASSERT_TRUE(shtool::test::try_write(tripling_tensor_table(4, generator), trip).ok());
  ASSERT_TRUE(shtool::test::try_write(sh_fourier_tensors_table(4, kFourierTableDefaultInputs, generator), four,
                          TableEncoding::json).ok());
  const auto t = read_table(trip, {"tripling-tensor", 1, 4});
  ASSERT_TRUE(t.ok()) << t.error().message;
  const auto tt = TriplingTensor::from_table(t.value());
  ASSERT_TRUE(tt.ok()) << tt.error().message;
  EXPECT_EQ(tt.value().value, compute_tripling_tensor_exact(4).value);
  const auto f = read_table(four, {"sh-fourier-tensors", 1, 4});
  ASSERT_TRUE(f.ok()) << f.error().message;
  const auto ff = ShFourierTensors::from_table(f.value());
  ASSERT_TRUE(ff.ok()) << ff.error().message;
  EXPECT_EQ(ff.value().degree, 8 * 3);
  EXPECT_EQ(ff.value().to_sh, ShFourierTensors::compute(4, 24).to_sh);

  const std::string script = std::string(SHTOOL_SOURCE_DIR) + "/tests/validate_json_schema.py";
  const std::string schemas = std::string(SHTOOL_SOURCE_DIR) + "/schemas/";
  auto validate = [&](const std::string& schema, const std::filesystem::path& file) {
    return test::run_command({SHTOOL_PYTHON, script, schemas + schema, file.string()});
  };
  const auto r1 = validate("tripling-tensor.schema.json", trip);
  EXPECT_EQ(r1.exit_code, 0) << r1.out << r1.err;
  const auto r2 = validate("sh-fourier-tensors.schema.json", four);
  EXPECT_EQ(r2.exit_code, 0) << r2.out << r2.err;
  const auto r3 = validate("sh-fourier-tensors.schema.json", trip);
  EXPECT_EQ(r3.exit_code, 1) << "the Fourier schema accepted a tripling table: " << r3.out << r3.err;
  std::filesystem::remove_all(dir);
}

template <class T>
void check_product(double tol) {
  const int order = 7;
  const int n = sh_count(order);
  const TriplingProduct<T> product(compute_tripling_tensor_exact(order));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<T> f1(n), f2(n), f3(n), g(n);
  for (int i = 0; i < n; ++i) {
    f1[i] = static_cast<T>(u(rng));
    f2[i] = static_cast<T>(u(rng));
    f3[i] = static_cast<T>(u(rng));
  }
  product.multiply(f1, f2, g);
  // Reference: projection of the pointwise product (degree 2(N-1)) onto order N, with a
  // rule exact for the degree-3(N-1) integrand.
  const SphereQuadrature q = sphere_quadrature(3 * (order - 1));
  std::vector<double> ref(n, 0.0), y(n);
  long double integral = 0;
  for (std::size_t p = 0; p < q.weights.size(); ++p) {
    eval_sh<double>(order, q.directions[p], y);
    double a = 0, b = 0, c = 0;
    for (int i = 0; i < n; ++i) {
      a += f1[i] * y[i];
      b += f2[i] * y[i];
      c += f3[i] * y[i];
    }
    for (int i = 0; i < n; ++i) ref[i] += q.weights[p] * a * b * y[i];
    integral += q.weights[p] * a * b * c;
  }
  double err = 0, norm = 0;
  for (int i = 0; i < n; ++i) {
    err += (g[i] - ref[i]) * (g[i] - ref[i]);
    norm += ref[i] * ref[i];
  }
  EXPECT_LT(std::sqrt(err / norm), tol) << "relative L2 error of the product";
  const double got = static_cast<double>(product.integral(f1, f2, f3));
  EXPECT_NEAR(got, static_cast<double>(integral), tol * std::abs(static_cast<double>(integral)) * 10)
      << "triple product integral";
}

// Double: rounding of ~1e3 terms; float: 24-bit mantissa over the same sums.
TEST(TriplingProduct, MatchesQuadratureDouble) { check_product<double>(1e-13); }
TEST(TriplingProduct, MatchesQuadratureFloat) { check_product<float>(2e-5); }

// Orders 2..kUnrolledTriplingOrder run a generated straight-line kernel (outer-product
// form, values as literals); order 1 and 7 the gather loop. Reference: every permutation
// of every canonical entry of the exact (3j) tensor, summed densely in long double, so an
// entry the kernel missed or counted twice shows up.
template <class T>
void check_small_orders(double tol) {
  for (int order = 1; order <= kUnrolledTriplingOrder + 1; ++order) {
    const int n = sh_count(order);
    const TriplingTensor tensor = compute_tripling_tensor_exact(order);
    const TriplingProduct<T> product(tensor);
    EXPECT_EQ(product.uses_kernel(), order >= 2 && order <= kUnrolledTriplingOrder) << "order " << order;
    std::mt19937 rng(40 + order);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<T> f1(n), f2(n), g(n);
    for (int i = 0; i < n; ++i) {
      f1[i] = static_cast<T>(u(rng));
      f2[i] = static_cast<T>(u(rng));
    }
    product.multiply(f1, f2, g);
    std::vector<long double> ref(n, 0.0L);
    for (std::size_t e = 0; e < tensor.size(); ++e) {
      int p[3] = {int(tensor.index[3 * e]), int(tensor.index[3 * e + 1]), int(tensor.index[3 * e + 2])};
      std::set<std::tuple<int, int, int>> seen;
      do {
        if (seen.insert({p[0], p[1], p[2]}).second)
          ref[p[2]] += static_cast<long double>(tensor.value[e]) * f1[p[0]] * f2[p[1]];
      } while (std::next_permutation(p, p + 3));
    }
    double err = 0, norm = 0;
    for (int i = 0; i < n; ++i) {
      const double d = static_cast<double>(g[i]) - static_cast<double>(ref[i]);
      err += d * d;
      norm += static_cast<double>(ref[i] * ref[i]);
    }
    EXPECT_LT(std::sqrt(err / norm), tol) << "order " << order << ": relative L2 " << sci(std::sqrt(err / norm));
  }
}

// Double: a few dozen rounded terms per output; float: 24-bit mantissa over the same sums.
TEST(TriplingProduct, UnrolledSmallOrdersMatchDenseTensorDouble) { check_small_orders<double>(1e-15); }
TEST(TriplingProduct, UnrolledSmallOrdersMatchDenseTensorFloat) { check_small_orders<float>(1e-6); }

TEST(TriplingKernels, CommittedSourceMatchesGenerator) {
  test::expect_committed_source("tripling-kernels", kTriplingKernelsFile, tripling_kernels_source());
}

TEST(TriplingKernels, BakedEntriesAreTheExactTensor) {
  for (int order = 2; order <= kUnrolledTriplingOrder; ++order) {
    const TriplingTensor exact = compute_tripling_tensor_exact(order);
    const auto baked = detail::tripling_kernel_entries(order);
    ASSERT_EQ(baked.size(), exact.size()) << "order " << order;
    for (std::size_t e = 0; e < baked.size(); ++e) {
      EXPECT_EQ(baked[e].a, exact.index[3 * e]);
      EXPECT_EQ(baked[e].c, exact.index[3 * e + 2]);
      EXPECT_EQ(baked[e].value, exact.value[e]) << "order " << order << " entry " << e;  // round-trip literal
    }
  }
  EXPECT_TRUE(detail::tripling_kernel_entries(1).empty());
  EXPECT_EQ(detail::tripling_kernel<double>(kUnrolledTriplingOrder + 1), nullptr);
}

// The kernel serves any construction of the same tensor (the runtime's Gauss-Legendre one
// agrees with the literals to ~3e-15) and nothing else: a tensor with one value changed,
// or one entry missing, falls back to the gather loop and its product follows that tensor.
TEST(TriplingKernels, UsedOnlyForTheSameTensor) {
  const int order = 4;
  EXPECT_TRUE(TriplingProduct<double>(TriplingTensor::compute(order)).uses_kernel());
  const TriplingTensor exact = compute_tripling_tensor_exact(order);
  TriplingTensor changed = exact;
  changed.value[10] *= 1.5;
  TriplingTensor dropped = exact;
  dropped.index.erase(dropped.index.begin() + 30, dropped.index.begin() + 33);
  dropped.value.erase(dropped.value.begin() + 10);
  const auto f = test::random_inputs(order, 2, 77);
  std::vector<double> with_kernel(sh_count(order));
  TriplingProduct<double>(exact).multiply(f[0], f[1], with_kernel);
  for (const TriplingTensor* t : {&changed, &dropped}) {
    const TriplingProduct<double> product(*t);
    EXPECT_FALSE(product.uses_kernel());
    std::vector<double> got(sh_count(order)), ref(sh_count(order), 0.0);
    product.multiply(f[0], f[1], got);
    for (std::size_t e = 0; e < t->size(); ++e) {  // dense reference of that tensor
      int p[3] = {int(t->index[3 * e]), int(t->index[3 * e + 1]), int(t->index[3 * e + 2])};
      std::set<std::tuple<int, int, int>> seen;
      do {
        if (seen.insert({p[0], p[1], p[2]}).second) ref[p[2]] += t->value[e] * f[0][p[0]] * f[1][p[1]];
      } while (std::next_permutation(p, p + 3));
    }
    double diff = 0;
    for (int i = 0; i < sh_count(order); ++i) {
      EXPECT_NEAR(got[i], ref[i], 1e-14) << "coefficient " << i;
      diff = std::max(diff, std::abs(got[i] - with_kernel[i]));
    }
    EXPECT_GT(diff, 1e-6) << "the modified tensor must change the product";
  }
}

}  // namespace
}  // namespace shtool
