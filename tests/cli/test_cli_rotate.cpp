// End-to-end `shtool rotate` (src/cli/rotate.cpp): a helper table made by
// `shtool gen-tensors`, every method against the in-process reference rotation, the
// three ways of giving a rotation, the three ways of giving coefficients, and bad input
// (exit code 1, nothing on stdout, a message naming the problem).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_test.h"
#include "test_util.h"
#include "shtool/euler.h"
#include "shtool/rotation.h"
#include "shtool/rotation_helpers.h"
#include "shtool/sh.h"

namespace shtool {
namespace {

using namespace test;

// Order of the helper table the tests generate; commands use orders up to this.
constexpr int kTableOrder = 8;

// A scratch folder with a helper table from `shtool gen-tensors`, made once.
class CliRotate : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new std::filesystem::path(test::scratch_path("cli_rotate", "tables"));
    std::filesystem::create_directories(*dir_);
    const std::vector<std::string> args = {"gen-tensors", "--order", std::to_string(kTableOrder), "--out",
                                           dir_->string(), "--what", "rotation"};
    const CommandResult r = run_shtool(args);
    ASSERT_EQ(r.exit_code, 0) << describe_command(args) << "\nstderr: " << r.err;
    table_ = new std::filesystem::path(*dir_ / "rotation-helpers.shtb");
    ASSERT_TRUE(std::filesystem::exists(*table_));
    const std::vector<std::string> json_args = {"gen-tensors", "--order", std::to_string(kTableOrder), "--out",
                                                (*dir_ / "json").string(), "--format", "json"};
    const CommandResult rj = run_shtool(json_args);
    ASSERT_EQ(rj.exit_code, 0) << describe_command(json_args) << "\nstderr: " << rj.err;
    Result<RotationHelpers> loaded = RotationHelpers::load(*table_);
    ASSERT_TRUE(loaded) << loaded.error().message;
    helpers_ = new std::shared_ptr<const RotationHelpers>(
        std::make_shared<const RotationHelpers>(std::move(loaded).value()));
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete table_;
    delete helpers_;
    dir_ = table_ = nullptr;
    helpers_ = nullptr;
  }
  static std::filesystem::path* dir_;
  static std::filesystem::path* table_;
  static std::shared_ptr<const RotationHelpers>* helpers_;
};
std::filesystem::path* CliRotate::dir_ = nullptr;
std::filesystem::path* CliRotate::table_ = nullptr;
std::shared_ptr<const RotationHelpers>* CliRotate::helpers_ = nullptr;

// 17 significant digits: the CLI must read back exactly the doubles used here.
std::string list(const std::vector<double>& v) {
  std::ostringstream s;
  s.precision(17);
  for (std::size_t i = 0; i < v.size(); ++i) s << (i ? "," : "") << v[i];
  return s.str();
}

std::string matrix_list(const Mat3<double>& r) {
  return list({r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)});
}

double distance(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.size(); ++i) s += (a[i] - b[i]) * (a[i] - b[i]);
  return std::sqrt(s);
}

struct Rotated {
  std::string method;
  std::vector<double> coefficients;
};

// Parses the documented output {"order": N, "method": name, "coefficients": [...]}.
Rotated parse_output(const CommandResult& r, int order, const std::string& what) {
  EXPECT_EQ(r.exit_code, 0) << what << "\nstderr: " << r.err;
  const nlohmann::json j = nlohmann::json::parse(r.out, nullptr, false);
  EXPECT_FALSE(j.is_discarded()) << what << ": stdout is not JSON: " << r.out;
  if (j.is_discarded() || !j.is_object()) return {};
  EXPECT_EQ(j.value("order", -1), order) << what;
  Rotated out;
  out.method = j.value("method", std::string());
  if (j.contains("coefficients") && j["coefficients"].is_array())
    for (const auto& v : j["coefficients"]) out.coefficients.push_back(v.get<double>());
  EXPECT_EQ(out.coefficients.size(), static_cast<std::size_t>(sh_count(order))) << what << ": " << r.out;
  out.coefficients.resize(sh_count(order), 0.0);
  return out;
}

std::vector<double> library_rotate(int order, const Mat3<double>& r, RotationMethod method,
                                   const std::vector<double>& f, std::shared_ptr<const RotationHelpers> h,
                                   double tol = kDefaultRotationTolerance, RotationMethod* chosen = nullptr) {
  ShRotation<double> rotation(order, std::move(h));
  EXPECT_TRUE(rotation.set(r, method, tol));
  std::vector<double> out(f.size());
  rotation.apply(f, out);
  if (chosen) *chosen = rotation.method();
  return out;
}

// Infinity norm of the off-diagonal part of D2 (bands < order): bounds its spectral
// norm, which is what the 1.5th order expansion leaves out (rotation.h).
double offdiag_d2_norm(const RotationHelpers& h, int order) {
  double worst = 0;
  for (int l = 0; l < order; ++l)
    for (int m = -l; m <= l; ++m) {
      double row = 0;
      if (m - 2 >= -l) row += std::abs(h.ddy_off2[sh_index(l, m)]);
      if (m + 2 <= l) row += std::abs(h.ddy_off2[sh_index(l, m + 2)]);
      worst = std::max(worst, row);
    }
  return worst;
}

// Exact methods relative to ||f||: rounding only (measured ~1e-15 at N = 8).
constexpr double kExactTol = 1e-12;

TEST_F(CliRotate, EveryMethodMatchesTheLibraryAndTheReference) {
  std::mt19937_64 rng(11);
  const int order = 6;
  const std::vector<double> f = random_coeffs(order, rng);
  // A modest tilt so that the Taylor methods are usable but not exact.
  const Mat3<double> r = matrix_from_zyz<double>({0.4, 0.05, -1.3});
  const std::vector<double> ref = library_rotate(order, r, RotationMethod::reference, f, nullptr);
  for (const char* name : {"reference", "zxzxz", "taylor1", "taylor1.5", "taylor2", "auto"}) {
    const std::vector<std::string> args = {"rotate",   "--order",  std::to_string(order), "--method", name,
                                           "--matrix", matrix_list(r), "--coeffs", list(f),
                                           "--tables", table_->string(), "--tol", "1e-4"};
    const std::string what = describe_command(args);
    const Rotated got = parse_output(run_shtool(args), order, what);
    const RotationMethod method = *rotation_method_from_name(name);
    RotationMethod chosen;
    const std::vector<double> lib = library_rotate(order, r, method, f, *helpers_, 1e-4, &chosen);
    EXPECT_EQ(got.method, rotation_method_name(chosen)) << what;
    // The CLI is the library plus exact (round-trip) number I/O: identical bits.
    for (int i = 0; i < sh_count(order); ++i) EXPECT_EQ(got.coefficients[i], lib[i]) << what << " i " << i;
    const double bound = taylor_error_bound(chosen, order, 0.05, offdiag_d2_norm(**helpers_, order));
    EXPECT_LE(distance(got.coefficients, ref), (bound + kExactTol) * norm(f)) << what;
    if (chosen == RotationMethod::taylor1 || chosen == RotationMethod::taylor2) {
      // Not exact: the error is visible (so the comparison above can fail).
      EXPECT_GT(distance(got.coefficients, ref), 1e-8 * norm(f)) << what;
    }
  }
}

TEST_F(CliRotate, AutoIsTheDefaultAndReportsItsChoice) {
  std::mt19937_64 rng(12);
  const int order = 5;
  const std::vector<double> f = random_coeffs(order, rng);
  // No tilt: the first-order Taylor step is exact and cheapest.
  const Rotated flat = parse_output(
      run_shtool({"rotate", "--order", "5", "--zyz", "0.3,0,0.2", "--coeffs", list(f), "--tables", table_->string()}),
      order, "zyz 0.3,0,0.2");
  EXPECT_EQ(flat.method, "taylor1");
  // A large tilt at the default tolerance: an exact method.
  const Rotated steep = parse_output(
      run_shtool({"rotate", "--order", "5", "--zyz", "0.3,1.2,0.2", "--coeffs", list(f), "--tables", table_->string()}),
      order, "zyz 0.3,1.2,0.2");
  EXPECT_EQ(steep.method, "zxzxz");
  const std::vector<double> ref =
      library_rotate(order, matrix_from_zyz<double>({0.3, 1.2, 0.2}), RotationMethod::reference, f, nullptr);
  EXPECT_LE(distance(steep.coefficients, ref), kExactTol * norm(f));
}

TEST_F(CliRotate, QuaternionMatrixAndZyzGiveTheSameRotation) {
  std::mt19937_64 rng(13);
  const int order = kTableOrder;
  const std::vector<double> f = random_coeffs(order, rng);
  for (const auto& [a, b, g] : {std::tuple{0.7, 1.1, -2.3}, std::tuple{-0.5, 0.0, 0.25},
                                std::tuple{2.0, std::numbers::pi, 1.0}, std::tuple{0.1, 3e-9, -0.1}}) {
    const Eigen::Quaterniond q = Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(b, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(g, Eigen::Vector3d::UnitZ());
    const Mat3<double> r = matrix_from_zyz<double>({a, b, g});
    const std::vector<double> want = library_rotate(order, r, RotationMethod::reference, f, nullptr);
    for (const char* method : {"reference", "zxzxz"}) {
      const std::vector<std::vector<std::string>> forms = {
          {"--zyz", list({a, b, g})},
          {"--quat", list({q.w(), q.x(), q.y(), q.z()})},
          {"--matrix", matrix_list(r)}};
      for (const auto& form : forms) {
        std::vector<std::string> args = {"rotate", "--order", std::to_string(order), "--method", method,
                                         "--coeffs", list(f), "--tables", table_->string()};
        args.insert(args.end(), form.begin(), form.end());
        const std::string what = describe_command(args);
        const Rotated got = parse_output(run_shtool(args), order, what);
        EXPECT_EQ(got.method, method) << what;
        // The three inputs differ by rounding (quaternion -> matrix, trig of the angles).
        EXPECT_LE(distance(got.coefficients, want), kExactTol * norm(f)) << what;
      }
    }
  }
}

TEST_F(CliRotate, CoefficientsFromFileAndStdinEqualCommandLine) {
  std::mt19937_64 rng(14);
  const int order = 4;
  const std::vector<double> f = random_coeffs(order, rng);
  const std::vector<std::string> base = {"rotate", "--order", "4", "--quat", list({0.5, 0.5, -0.5, 0.5}),
                                         "--tables", table_->string(), "--method", "zxzxz"};
  std::vector<std::string> a1 = base;
  a1.insert(a1.end(), {"--coeffs", list(f)});
  const Rotated direct = parse_output(run_shtool(a1), order, describe_command(a1));

  const nlohmann::json doc = {{"coefficients", f}};
  const std::filesystem::path file = *dir_ / "in coeffs.json";  // a space in the name
  std::ofstream(file) << doc.dump();
  std::vector<std::string> a2 = base;
  a2.insert(a2.end(), {"--in", file.string()});
  const Rotated from_file = parse_output(run_shtool(a2), order, describe_command(a2));

  std::vector<std::string> a3 = base;
  a3.insert(a3.end(), {"--in", "-"});
  const Rotated from_stdin = parse_output(run_shtool(a3, {.stdin_data = doc.dump()}), order, describe_command(a3));

  for (int i = 0; i < sh_count(order); ++i) {
    EXPECT_EQ(from_file.coefficients[i], direct.coefficients[i]) << i;
    EXPECT_EQ(from_stdin.coefficients[i], direct.coefficients[i]) << i;
  }
  // Independent value: the quaternion (1/2)(1, 1, -1, 1) is a 120-degree turn about
  // (1, -1, 1); band 0 is invariant.
  EXPECT_DOUBLE_EQ(direct.coefficients[0], f[0]);
}

TEST_F(CliRotate, JsonEncodedTableWorksToo) {
  std::mt19937_64 rng(15);
  const int order = 5;
  const std::vector<double> f = random_coeffs(order, rng);
  const Mat3<double> r = matrix_from_zyz<double>({1.0, 0.8, 0.3});
  const std::vector<std::string> args = {"rotate", "--order", "5", "--method", "zxzxz", "--matrix", matrix_list(r),
                                         "--coeffs", list(f), "--tables",
                                         (*dir_ / "json" / "rotation-helpers.json").string()};
  const Rotated got = parse_output(run_shtool(args), order, describe_command(args));
  const std::vector<double> lib = library_rotate(order, r, RotationMethod::zxzxz, f, *helpers_);
  for (int i = 0; i < sh_count(order); ++i) EXPECT_EQ(got.coefficients[i], lib[i]) << i;
}

// ---------------------------------------------------------------------------
// Bad input.

struct BadCase {
  std::string name;
  std::vector<std::string> args;  // after "rotate"
  std::vector<std::string> message_contains;
  std::string stdin_data;
};

void expect_fails(const BadCase& c) {
  std::vector<std::string> args = {"rotate"};
  args.insert(args.end(), c.args.begin(), c.args.end());
  const CommandResult r = run_shtool(args, {.stdin_data = c.stdin_data});
  const std::string what = c.name + ": " + describe_command(args);
  EXPECT_EQ(r.exit_code, 1) << what << "\nstdout: " << r.out << "\nstderr: " << r.err;
  EXPECT_EQ(r.out, "") << what << ": no partial output on error";
  EXPECT_NE(r.err.find("error"), std::string::npos) << what << ": " << r.err;
  for (const std::string& needle : c.message_contains)
    EXPECT_NE(r.err.find(needle), std::string::npos)
        << what << ": stderr should mention '" << needle << "'; stderr: " << r.err;
}

TEST_F(CliRotate, BadInputFailsWithAMessage) {
  const std::string t = table_->string();
  const std::string c9 = "1,0,0,0,0,0,0,0,0";
  const std::vector<std::string> ok_rot = {"--zyz", "0.1,0.2,0.3"};
  auto with = [&](std::vector<std::string> a, const std::vector<std::string>& more) {
    a.insert(a.end(), more.begin(), more.end());
    return a;
  };
  const std::vector<std::string> base = {"--order", "3", "--tables", t};

  // Files for --in and corrupted tables.
  const std::filesystem::path nan_json = *dir_ / "nan.json";
  std::ofstream(nan_json) << R"({"coefficients": [1, NaN, 0, 0, 0, 0, 0, 0, 0]})";
  const std::filesystem::path inf_json = *dir_ / "inf.json";
  std::ofstream(inf_json) << R"({"coefficients": [1, 1e999, 0, 0, 0, 0, 0, 0, 0]})";
  const std::filesystem::path str_json = *dir_ / "str.json";
  std::ofstream(str_json) << R"({"coefficients": [1, "2", 0, 0, 0, 0, 0, 0, 0]})";
  const std::filesystem::path short_json = *dir_ / "short.json";
  std::ofstream(short_json) << R"({"coefficients": [1, 2, 3]})";
  const std::filesystem::path no_key_json = *dir_ / "nokey.json";
  std::ofstream(no_key_json) << R"({"coeffs": [1, 0, 0, 0, 0, 0, 0, 0, 0]})";

  std::string bytes;
  {
    std::ifstream in(*table_, std::ios::binary);
    bytes.assign(std::istreambuf_iterator<char>(in), {});
  }
  ASSERT_GT(bytes.size(), 200u);
  const std::filesystem::path flipped = *dir_ / "flipped.shtb";
  {
    std::string b = bytes;
    b[b.size() - 9] ^= 0x40;  // inside the last array's data
    std::ofstream(flipped, std::ios::binary) << b;
  }
  const std::filesystem::path truncated = *dir_ / "truncated.shtb";
  std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  const std::filesystem::path garbage = *dir_ / "garbage.shtb";
  std::ofstream(garbage, std::ios::binary) << "this is not a table";

  const std::vector<BadCase> cases = {
      {"non-orthonormal matrix",
       with(base, {"--matrix", "1,0,0,0,1,0,0,0,1.1", "--coeffs", c9}),
       {"--matrix", "not orthonormal"}},
      {"scaled rotation",
       with(base, {"--matrix", "0,-2,0,2,0,0,0,0,2", "--coeffs", c9}),
       {"--matrix", "not orthonormal"}},
      {"reflection", with(base, {"--matrix", "1,0,0,0,1,0,0,0,-1", "--coeffs", c9}), {"--matrix", "reflection"}},
      {"matrix with 8 numbers", with(base, {"--matrix", "1,0,0,0,1,0,0,0", "--coeffs", c9}), {"--matrix", "9"}},
      {"non-unit quaternion", with(base, {"--quat", "1,0.1,0,0", "--coeffs", c9}), {"--quat", "unit"}},
      {"zero quaternion", with(base, {"--quat", "0,0,0,0", "--coeffs", c9}), {"--quat", "unit"}},
      {"quaternion with 3 numbers", with(base, {"--quat", "1,0,0", "--coeffs", c9}), {"--quat", "4"}},
      {"zyz with 2 angles", with(base, {"--zyz", "1,2", "--coeffs", c9}), {"--zyz", "3"}},
      {"NaN in a rotation", with(base, {"--zyz", "1,nan,2", "--coeffs", c9}), {"--zyz", "nan"}},
      {"missing rotation", with(base, {"--coeffs", c9}), {"--quat", "--matrix", "--zyz"}},
      {"two rotations", with(base, {"--zyz", "0,0,0", "--quat", "1,0,0,0", "--coeffs", c9}), {"exactly one of --quat"}},
      {"too few coefficients",
       with(base, with(ok_rot, {"--coeffs", "1,2,3,4,5,6,7,8"})),
       {"expected 9 coefficients", "got 8"}},
      {"too many coefficients",
       with(base, with(ok_rot, {"--coeffs", c9 + ",1"})),
       {"expected 9 coefficients", "got 10"}},
      {"NaN coefficient", with(base, with(ok_rot, {"--coeffs", "1,NaN,0,0,0,0,0,0,0"})), {"--coeffs", "NaN"}},
      {"infinite coefficient", with(base, with(ok_rot, {"--coeffs", "1,inf,0,0,0,0,0,0,0"})), {"--coeffs", "inf"}},
      {"empty coefficient", with(base, with(ok_rot, {"--coeffs", "1,,0,0,0,0,0,0,0"})), {"--coeffs"}},
      {"NaN in the --in file", with(base, with(ok_rot, {"--in", nan_json.string()})), {"--in", "JSON"}},
      {"overflowing number in the --in file", with(base, with(ok_rot, {"--in", inf_json.string()})), {"--in", "JSON"}},
      {"string in the --in file", with(base, with(ok_rot, {"--in", str_json.string()})), {"--in", "numbers"}},
      {"short --in file", with(base, with(ok_rot, {"--in", short_json.string()})), {"expected 9", "got 3"}},
      {"--in file without coefficients",
       with(base, with(ok_rot, {"--in", no_key_json.string()})),
       {"--in", "coefficients"}},
      {"missing --in file",
       with(base, with(ok_rot, {"--in", (*dir_ / "absent.json").string()})),
       {"--in", "absent.json"}},
      {"bad JSON on stdin", with(base, with(ok_rot, {"--in", "-"})), {"--in", "JSON"}, "{\"coefficients\": [1,"},
      {"nothing on stdin", with(base, with(ok_rot, {"--in", "-"})), {"--in -: standard input is empty"}},
      {"both --coeffs and --in",
       with(base, with(ok_rot, {"--coeffs", c9, "--in", short_json.string()})),
       {"exactly one of --coeffs, --in"}},
      {"neither --coeffs nor --in", with(base, ok_rot), {"exactly one of --coeffs, --in"}},
      {"unknown method", with(base, with(ok_rot, {"--method", "taylor3", "--coeffs", c9})), {"--method", "taylor3"}},
      {"negative tolerance", with(base, with(ok_rot, {"--tol", "-1", "--coeffs", c9})), {"--tol"}},
      {"order 0", {"--order", "0", "--zyz", "0,0,0", "--coeffs", "1", "--tables", t}, {"--order", "0"}},
      {"missing table",
       {"--order", "3", "--zyz", "0,1,0", "--coeffs", c9, "--tables", (*dir_ / "none.shtb").string()},
       {"none.shtb"}},
      {"corrupted table (flipped bit)",
       {"--order", "3", "--zyz", "0,1,0", "--coeffs", c9, "--tables", flipped.string()},
       {"flipped.shtb"}},
      {"truncated table",
       {"--order", "3", "--zyz", "0,1,0", "--coeffs", c9, "--tables", truncated.string()},
       {"truncated.shtb"}},
      {"not a table",
       {"--order", "3", "--zyz", "0,1,0", "--coeffs", c9, "--tables", garbage.string()},
       {"garbage.shtb"}},
      {"table for fewer bands",
       {"--order", std::to_string(kTableOrder + 1), "--zyz", "0,1,0", "--coeffs",
        list(std::vector<double>(sh_count(kTableOrder + 1), 0.5)), "--tables", t},
       {"covers order " + std::to_string(kTableOrder)}},
  };
  for (const BadCase& c : cases) expect_fails(c);
}

TEST_F(CliRotate, ReferenceNeedsNoTable) {
  // The reference method is self-contained: a missing table does not matter.
  const std::vector<std::string> args = {"rotate", "--order", "2", "--method", "reference", "--zyz",
                                         "0,1.5707963267948966,0", "--coeffs", "0,0,1,0",
                                         "--tables", (*dir_ / "none.shtb").string()};
  const Rotated got = parse_output(run_shtool(args), 2, describe_command(args));
  // Ry(+90) takes z to x: y_1^0 = c z becomes c x = -y_1^1.
  EXPECT_NEAR(got.coefficients[3], -1.0, 1e-15);
  EXPECT_NEAR(got.coefficients[2], 0.0, 1e-15);
}

TEST_F(CliRotate, ZhfMethodsWithTheShippedLobesMatchTheReference) {
  // Zonal-harmonic factorisation ([1] Eq. 10) and its signal-tailored form (Eq. 11)
  // with the shipped shared-lobe table: exact up to rounding amplified by cond(Y_l)
  // (<= ~50 for the shipped tables), so 1e-10 relative to ||f||.
  std::mt19937_64 rng(5);
  for (int order : {3, 6, 8}) {
    const std::vector<double> f = random_coeffs(order, rng);
    const std::string zyz = "0.4,2.1,-1.3";
    std::vector<std::string> base = {"rotate", "--order", std::to_string(order), "--zyz", zyz,
                                     "--coeffs", list(f), "--method"};
    auto run = [&](const std::string& method) {
      std::vector<std::string> args = base;
      args.push_back(method);
      return parse_output(run_shtool(args), order, describe_command(args));
    };
    const Rotated ref = run("reference");
    for (const std::string method : {"zhf", "zhf-tailored"}) {
      const Rotated got = run(method);
      EXPECT_EQ(got.method, method);
      EXPECT_LT(distance(got.coefficients, ref.coefficients), 1e-10 * norm(f))
          << method << " order " << order;
    }
  }
}

}  // namespace
}  // namespace shtool
