// End-to-end tests of `shtool product`: closed-form products of low bands through both
// methods, file and stdin input, the accurate versus recursive multiple product, and
// clear errors (non-zero exit, message on stderr, nothing on stdout) for bad input.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_test.h"

namespace {

using namespace shtool::test;

constexpr double kPi = std::numbers::pi;
// Closed forms evaluated in double and products rounded in a few dozen operations.
constexpr double kTol = 1e-14;

CommandResult product(const std::vector<std::string>& args, const std::string& stdin_data = "") {
  std::vector<std::string> argv = {"product"};
  argv.insert(argv.end(), args.begin(), args.end());
  return run_shtool(argv, {.stdin_data = stdin_data});
}

std::vector<double> coefficients(const CommandResult& r, int order) {
  EXPECT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out);
  EXPECT_EQ(j.at("order").get<int>(), order);
  return j.at("coefficients").get<std::vector<double>>();
}

std::string inputs_json(const std::vector<std::vector<double>>& f) {
  return nlohmann::json{{"inputs", f}}.dump();
}

std::vector<double> unit(int order, int index) {
  std::vector<double> v(order * order, 0.0);
  v[index] = 1.0;
  return v;
}

TEST(CliProduct, SquareOfY10ClosedForm) {
  // (c z)^2 with c^2 = 3/(4 pi): z^2 = 1/3 + (2/3) P_2, so the product is
  // 1/sqrt(4 pi) y_0^0 + 1/sqrt(5 pi) y_2^0.
  const int order = 3;
  const std::string in = inputs_json({unit(order, 2), unit(order, 2)});
  for (const std::string method : {"tripling", "fourier", "grid", "auto"}) {
    const std::filesystem::path file = shtool::test::scratch_path("cli_product", method + ".json");
    shtool::test::write_file(file, in);
    const std::vector<double> g =
        coefficients(product({"--order", "3", "--method", method, "--in", file.string()}), order);
    ASSERT_EQ(g.size(), 9u);
    for (int i = 0; i < 9; ++i) {
      const double expected = i == 0 ? 0.5 / std::sqrt(kPi) : i == 6 ? 1.0 / std::sqrt(5.0 * kPi) : 0.0;
      EXPECT_NEAR(g[i], expected, kTol) << method << " coefficient " << i;
    }
  }
}

TEST(CliProduct, ConstantTimesFunctionFromStdin) {
  // y_0^0 = 1/sqrt(4 pi) is a constant: the product is f / sqrt(4 pi) exactly.
  const int order = 5;
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<double> f(order * order);
  for (double& x : f) x = u(rng);
  const CommandResult r = product({"--order", "5", "--in", "-"}, inputs_json({unit(order, 0), f}));
  const std::vector<double> g = coefficients(r, order);
  for (int i = 0; i < order * order; ++i) EXPECT_NEAR(g[i], f[i] / std::sqrt(4 * kPi), kTol) << i;
}

TEST(CliProduct, AccurateVersusRecursiveTripleOfY10) {
  // z^3 = (3/5) z + (2/5) P_3: the order-2 part of (c z)^3 is (3/5) c^2 y_1^0 = 9/(20 pi) y_1^0.
  // The recursive approximation truncates (c z)^2 to its constant 1/sqrt(4 pi) first and
  // gets y_1^0 / (4 pi) instead.
  const int order = 2;
  const std::string in = inputs_json({unit(order, 2), unit(order, 2), unit(order, 2)});
  const std::vector<double> accurate = coefficients(product({"--order", "2", "--method", "fourier", "--in", "-"}, in), order);
  EXPECT_NEAR(accurate[2], 9.0 / (20.0 * kPi), kTol);
  const std::vector<double> by_grid = coefficients(product({"--order", "2", "--method", "grid", "--in", "-"}, in), order);
  EXPECT_NEAR(by_grid[2], 9.0 / (20.0 * kPi), kTol);
  for (const std::string method : {"tripling", "fourier", "grid"}) {
    const std::vector<double> rec =
        coefficients(product({"--order", "2", "--method", method, "--recursive", "--in", "-"}, in), order);
    EXPECT_NEAR(rec[2], 1.0 / (4.0 * kPi), kTol) << method;
    EXPECT_NEAR(rec[0], 0.0, kTol) << method;
  }
}

TEST(CliProduct, EightInputsAndByteIdenticalOutput) {
  const int order = 4;
  std::vector<std::vector<double>> f(8, unit(order, 0));
  const std::string in = inputs_json(f);
  const CommandResult a = product({"--order", "4", "--in", "-"}, in);
  const CommandResult b = product({"--order", "4", "--in", "-"}, in);
  ASSERT_EQ(a.exit_code, 0) << a.err;
  EXPECT_EQ(a.out, b.out);
  // (1/sqrt(4 pi))^8 as a function = (4 pi)^-4 = coefficient (4 pi)^-4 * sqrt(4 pi) on y_0^0.
  const std::vector<double> g = coefficients(a, order);
  EXPECT_NEAR(g[0], std::pow(4 * kPi, -4.0) * std::sqrt(4 * kPi), 1e-18);
}

TEST(CliProduct, AccurateTriplingChainEqualsFourierAndGrid) {
  // Three independent accurate routes for k >= 2 inputs: the tripling tensor chained at
  // growing orders, the Fourier divide and conquer, and the grid quadrature (also the
  // default, auto). Random-looking inputs with every coefficient non-zero, so that every
  // band of every step contributes.
  for (const auto& [order, k] : {std::pair{2, 3}, std::pair{4, 3}, std::pair{3, 8}, std::pair{7, 2},
                                 std::pair{5, 5}}) {
    std::vector<std::vector<double>> f(k, std::vector<double>(order * order));
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < order * order; ++i) f[j][i] = std::sin(1.0 + 7.0 * j + 3.1 * i);
    const std::string in = inputs_json(f);
    const std::string n = std::to_string(order);
    const std::vector<double> t = coefficients(product({"--order", n, "--method", "tripling", "--in", "-"}, in), order);
    for (const std::string method : {"fourier", "grid", "auto"}) {
      const std::vector<double> q = coefficients(product({"--order", n, "--method", method, "--in", "-"}, in), order);
      double diff = 0, norm = 0;
      for (int i = 0; i < order * order; ++i) {
        diff += (t[i] - q[i]) * (t[i] - q[i]);
        norm += q[i] * q[i];
      }
      // All are exact up to rounding: relative 1e-12 leaves ~1000 ulp for sums of many terms.
      EXPECT_LT(std::sqrt(diff / norm), 1e-12) << method << ", order " << order << ", k " << k;
    }
  }
}

struct BadCase {
  std::vector<std::string> args;
  std::string stdin_data;
  std::string message;  // a fragment the error must contain
};

TEST(CliProduct, BadInputIsAClearError) {
  const std::string ok2 = inputs_json({unit(2, 0), unit(2, 1)});
  std::vector<BadCase> cases = {
      {{"--order", "2", "--in", "-"}, R"({"inputs": [[1,0,0,0],[0,1,0]]})", "input 2 has 3 coefficients"},
      {{"--order", "2", "--in", "-"}, R"({"inputs": [[1,0,0,0],[0,1,0,null]]})", "not a number"},
      {{"--order", "2", "--in", "-"}, R"({"inputs": [[1,0,0,0],[0,1,0,"NaN"]]})", "not a number"},
      {{"--order", "2", "--in", "-"}, R"({"inputs": [[1,0,0,0],[0,1,0,NaN]]})", "not valid JSON"},
      {{"--order", "2", "--in", "-"}, R"({"inputs": [[1,0,0,0],[0,1,0,1e999]]})", "overflow"},
      {{"--order", "2", "--in", "-"}, R"({"inputs": [[1,0,0,0]]})", "1 inputs given"},
      {{"--order", "1", "--in", "-"}, R"({"inputs": [[1],[1],[1],[1],[1],[1],[1],[1],[1]]})", "9 inputs given"},
      {{"--order", "2", "--in", "-"}, R"([[1,0,0,0],[0,1,0,0]])", "expected a JSON object"},
      {{"--order", "2", "--in", "-"}, "{\"inputs\": [[1,0,0,0],", "not valid JSON"},
      {{"--order", "2", "--in", "/nonexistent/x.json"}, "", "no such file"},
      {{"--order", "0", "--in", "-"}, ok2, "--order 0"},
      {{"--order", "65", "--in", "-"}, ok2, "--order 65"},
      {{"--order", "2", "--method", "wavelet", "--in", "-"}, ok2, "--method must be"},
      {{"--order", "33", "--method", "tripling", "--in", "-"}, ok2, "orders up to 32"},
      {{"--order", "12", "--method", "tripling", "--in", "-"},
       inputs_json(std::vector<std::vector<double>>(8, unit(12, 0))),
       "needs tripling tensors of order 45"},
      {{"--order", "2", "--in", "-"}, R"({"inputs": [[1e300,0,0,0],[1e300,0,0,0]]})", "overflows"},
      {{"--order", "7", "--method", "grid", "--in", "-"},
       inputs_json({std::vector<double>(49, 1e300), std::vector<double>(49, 1e300)}),
       "overflows"},
      {{"--order", "2", "--method", "Grid", "--in", "-"}, ok2, "auto, tripling, fourier or grid"},
      // Nothing on stdin is said as such, not as JSON that ended early.
      {{"--order", "2", "--in", "-"}, "", "--in -: standard input is empty"},
  };
  for (const BadCase& c : cases) {
    const CommandResult r = product(c.args, c.stdin_data);
    EXPECT_EQ(r.exit_code, 1) << c.stdin_data << "\n" << r.err;
    EXPECT_TRUE(r.out.empty()) << "partial output: " << r.out;
    EXPECT_NE(r.err.find("error"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos)
        << "stderr '" << r.err << "' lacks '" << c.message << "'";
  }
}

TEST(CliProduct, ClosedStdinIsNamed) {
  const CommandResult r = run_shtool({"product", "--order", "2", "--in", "-"}, {.no_stdin = true});
  EXPECT_EQ(r.exit_code, 1) << r.err;
  EXPECT_TRUE(r.out.empty()) << r.out;
  EXPECT_NE(r.err.find("--in -: standard input is closed"), std::string::npos) << r.err;
}

}  // namespace
