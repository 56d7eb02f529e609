// End-to-end tests of the shtool executable: top-level behaviour (version, help,
// missing or unknown subcommand) and `shtool eval`, run as a separate process.
//
// The reference for `eval` is the runtime's eval_sh on the same normalised direction:
// the CLI is a thin layer over it, so the values must agree to the bit (the JSON text
// has to round-trip). The runtime itself is checked against closed forms in
// test_sh.cpp; here only a few closed forms at the pole guard the wiring.
#include <algorithm>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <limits>
#include <numbers>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_test.h"
#include "shtool/sh.h"
#include "shtool/version.h"

namespace {

using namespace shtool::test;

std::uint64_t bits(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof b);
  return b;
}

std::string dir_arg(double x, double y, double z) {
  // 17 significant digits: the CLI must read back exactly the double we normalise.
  std::ostringstream s;
  s.precision(17);
  s << x << ',' << y << ',' << z;
  return s.str();
}

// Parses `shtool eval` output and checks its shape; returns the values.
std::vector<double> parse_eval_output(const CommandResult& r, int order, const std::string& what) {
  EXPECT_EQ(r.exit_code, 0) << what << "\nstderr: " << r.err;
  EXPECT_EQ(r.err, "") << what;
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(r.out);
  } catch (const nlohmann::json::exception& e) {
    ADD_FAILURE() << what << ": stdout is not JSON (" << e.what() << "): " << r.out;
    return {};
  }
  EXPECT_TRUE(j.is_object()) << what << ": " << r.out;
  EXPECT_TRUE(j.contains("order") && j["order"].is_number_integer()) << what << ": " << r.out;
  EXPECT_TRUE(j.contains("values") && j["values"].is_array()) << what << ": " << r.out;
  if (!j.is_object() || !j.contains("values") || !j["values"].is_array()) return {};
  EXPECT_EQ(j["order"], order) << what;
  std::vector<double> values;
  for (const auto& v : j["values"]) {
    EXPECT_TRUE(v.is_number_float()) << what << ": value " << v.dump() << " is not a float";
    values.push_back(v.get<double>());
  }
  EXPECT_EQ(values.size(), static_cast<std::size_t>(order) * order) << what;
  return values;
}

std::vector<double> reference_values(int order, double x, double y, double z) {
  // Same normalisation as the CLI (scale by the largest component, then divide by the
  // Euclidean norm), so the direction the
  // reference sees is bit-identical to the one the CLI evaluates.
  shtool::Vec3<double> w(x, y, z);
  w /= w.cwiseAbs().maxCoeff();
  w /= w.norm();
  std::vector<double> values(shtool::sh_count(order));
  shtool::eval_sh<double>(order, w, values);
  return values;
}

void expect_bit_equal(const std::vector<double>& got, const std::vector<double>& want,
                      const std::string& what) {
  ASSERT_EQ(got.size(), want.size()) << what;
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_EQ(bits(got[i]), bits(want[i]))
        << what << ": index " << i << " CLI " << std::setprecision(17) << got[i] << " eval_sh "
        << want[i];
}

// ---------------------------------------------------------------------------
// The helper itself (tests/run_command.h): everything below trusts what it captures.

TEST(RunCommand, CapturesStreamsSeparatelyAndExitCode) {
  const CommandResult r = shtool::test::run_shell("printf out; printf err >&2; exit 3");
  EXPECT_EQ(r.exit_code, 3);
  EXPECT_EQ(r.out, "out");
  EXPECT_EQ(r.err, "err");
  EXPECT_FALSE(r.signaled);
}

TEST(RunCommand, LargeOutputOnBothStreamsDoesNotDeadlock) {
  // 1 MiB on each stream, far more than a pipe buffer (64 KiB): reading one stream to
  // the end before the other would hang here.
  shtool::test::CommandOptions options;
  options.timeout_seconds = 60;
  const CommandResult r = shtool::test::run_shell(
      "head -c 1048576 /dev/zero | tr '\\0' e >&2 & head -c 1048576 /dev/zero | tr '\\0' o; wait",
      options);
  EXPECT_FALSE(r.timed_out);
  EXPECT_EQ(r.exit_code, 0) << r.err.substr(0, 200);
  EXPECT_EQ(r.out.size(), 1u << 20);
  EXPECT_EQ(r.out.find_first_not_of('o'), std::string::npos);
  EXPECT_EQ(r.err.size(), 1u << 20);
  EXPECT_EQ(r.err.find_first_not_of('e'), std::string::npos);
}

TEST(RunCommand, StdinIsPassedAndSignalsAndTimeoutsAreReported) {
  shtool::test::CommandOptions in;
  in.stdin_data = "a b\nc\n";
  const CommandResult echoed = shtool::test::run_command({"cat"}, in);
  EXPECT_EQ(echoed.exit_code, 0);
  EXPECT_EQ(echoed.out, in.stdin_data);

  const CommandResult killed = shtool::test::run_shell("kill -SEGV $$");
  EXPECT_TRUE(killed.signaled);
  EXPECT_EQ(killed.signal, SIGSEGV);
  EXPECT_NE(killed.exit_code, 0);

  shtool::test::CommandOptions quick;
  quick.timeout_seconds = 0.2;
  const CommandResult slow = shtool::test::run_command({"sleep", "30"}, quick);
  EXPECT_TRUE(slow.timed_out);
  EXPECT_NE(slow.exit_code, 0);

  EXPECT_THROW(shtool::test::run_command({"/nonexistent/program"}), std::runtime_error);
}

// ---------------------------------------------------------------------------
// Top level

TEST(Cli, VersionPrintsProjectVersion) {
  const CommandResult r = run_shtool({"--version"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out, std::string("shtool ") + shtool::kVersion + "\n");
}

// Names of the subcommands main.cpp registers, taken from the setup_<name> declarations
// in cli_common.h (underscores become dashes: setup_fit_zh -> fit-zh).
std::set<std::string> declared_subcommands() {
  std::ifstream in(std::string(SHTOOL_SOURCE_DIR) + "/src/cli/cli_common.h");
  std::stringstream text;
  text << in.rdbuf();
  const std::string s = text.str();
  std::set<std::string> names;
  const std::regex decl(R"(void\s+setup_(\w+)\s*\(\s*CLI::App\s*\*)");
  for (auto it = std::sregex_iterator(s.begin(), s.end(), decl); it != std::sregex_iterator(); ++it) {
    std::string name = (*it)[1];
    for (char& c : name)
      if (c == '_') c = '-';
    names.insert(name);
  }
  return names;
}

// The "Subcommands:" section of CLI11's help: one "  name   description" line each.
std::set<std::string> listed_subcommands(const std::string& help) {
  std::set<std::string> names;
  const std::size_t start = help.find("Subcommands:");
  if (start == std::string::npos) return names;
  std::istringstream lines(help.substr(start));
  std::string line;
  std::getline(lines, line);  // the heading
  while (std::getline(lines, line)) {
    if (line.empty()) break;
    std::istringstream words(line);
    std::string name;
    words >> name;
    if (!name.empty()) names.insert(name);
  }
  return names;
}

std::string join(const std::set<std::string>& names) {
  std::string s;
  for (const auto& n : names) s += (s.empty() ? "" : " ") + n;
  return s;
}

TEST(Cli, HelpListsEveryDeclaredSubcommand) {
  const std::set<std::string> declared = declared_subcommands();
  // Guards the parser above: if it finds nothing the comparison below proves nothing.
  ASSERT_TRUE(declared.count("eval")) << "declared: " << join(declared);

  const CommandResult r = run_shtool({"--help"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("Usage:"), std::string::npos) << r.out;
  const std::set<std::string> listed = listed_subcommands(r.out);
  EXPECT_EQ(listed, declared) << "--help lists: " << join(listed)
                              << "\ncli_common.h declares: " << join(declared) << "\n"
                              << r.out;
}

TEST(Cli, EverySubcommandHasHelp) {
  for (const std::string& name : declared_subcommands()) {
    const CommandResult r = run_shtool({name, "--help"});
    EXPECT_EQ(r.exit_code, 0) << name << " --help\nstderr: " << r.err;
    EXPECT_NE(r.out.find("Usage:"), std::string::npos) << name << " --help:\n" << r.out;
  }
}

TEST(Cli, NoSubcommandIsAnError) {
  const CommandResult r = run_shtool({});
  EXPECT_NE(r.exit_code, 0) << "stdout: " << r.out;
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("subcommand"), std::string::npos) << "stderr: " << r.err;
}

TEST(Cli, UnknownSubcommandIsAnErrorNamingIt) {
  const CommandResult r = run_shtool({"no-such-subcommand"});
  EXPECT_NE(r.exit_code, 0) << "stdout: " << r.out;
  EXPECT_EQ(r.out, "");
  EXPECT_NE(r.err.find("no-such-subcommand"), std::string::npos)
      << "the message should name the unknown subcommand; stderr: " << r.err;
}

// Command-line errors CLI11 finds (a value outside a set, a number past its type, an
// option given twice) read as every other error: "shtool: error: ...", exit 1.
TEST(Cli, OptionErrorsReadAsOtherErrors) {
  for (const std::vector<std::string>& args : {std::vector<std::string>{"fit-zh", "m.obj", "--up", "x"},
                                               {"fit-zh", "m.obj", "--rays", "99999999999"},
                                               {"eval", "--order", "2", "--order", "3", "--dir", "0,0,1"},
                                               {"eval", "--no-such-option"}}) {
    const CommandResult r = run_shtool(args);
    EXPECT_EQ(r.exit_code, 1) << args[2];
    EXPECT_EQ(r.err.rfind("shtool: error: ", 0), 0u) << r.err;
    EXPECT_EQ(r.out, "");
  }
}

// ---------------------------------------------------------------------------
// shtool eval: values

// A result printed into a full disk or a closed stdout fails the command: `> result.json`
// must not leave a cut file behind an exit status of 0.
TEST(Cli, AResultThatCannotBeWrittenFailsTheCommand) {
  for (const std::string redirect : {"> /dev/full", ">&-"}) {
    const CommandResult r =
        run_command({"/bin/sh", "-c", "'" + kShtoolExe + "' eval --order 3 --dir 0,0,1 " + redirect});
    EXPECT_EQ(r.exit_code, 1) << redirect << ": " << r.err;
    EXPECT_NE(r.err.find("cannot write the result to standard output"), std::string::npos) << redirect << ": " << r.err;
  }
}

// An empty value is never an option's: CLI11 would read it as 0 (every core, seed 0).
TEST(Cli, EmptyValuesAreRefusedByOption) {
  for (const auto& [args, named] : std::vector<std::pair<std::vector<std::string>, std::string>>{
           {{"eval", "--order", "", "--dir", "0,0,1"}, "--order is given an empty value"},
           {{"eval", "--order=", "--dir", "0,0,1"}, "--order is given an empty value"},
           {{"light", "--type", "constant", "--order", "2", "--json", "/tmp/x.json", "--threads", ""},
            "--threads is given an empty value"}}) {
    const CommandResult r = run_shtool(args);
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find(named), std::string::npos) << r.err;
  }
}

TEST(CliEval, ValuesEqualRuntimeBitForBit) {
  struct Case {
    int order;
    double x, y, z;
  };
  // Unnormalised directions in every octant, near the poles and on the equator, and
  // orders from the smallest to the largest supported.
  const Case cases[] = {
      {1, 0.3, -0.5, 0.8},   {2, -1.0, 0.0, 0.0},       {3, 0.1, 0.2, 0.3},
      {4, -0.7, -0.2, -0.4}, {5, 1e-9, 2e-9, -1.0},     {6, 3.0, 4.0, 0.0},
      {8, -2.5, 1.25, 7.0},  {10, 0.577, 0.577, -0.577}, {128, 0.48, -0.6, 0.64},
  };
  for (const Case& c : cases) {
    const std::vector<std::string> args = {"eval", "--order", std::to_string(c.order), "--dir",
                                           dir_arg(c.x, c.y, c.z)};
    const std::string what = describe_command(args);
    const std::vector<double> got = parse_eval_output(run_shtool(args), c.order, what);
    expect_bit_equal(got, reference_values(c.order, c.x, c.y, c.z), what);
  }
}

TEST(CliEval, Order30Gives900Values) {
  const std::vector<std::string> args = {"eval", "--order", "30", "--dir", "0.2,-0.9,0.4"};
  const std::vector<double> got = parse_eval_output(run_shtool(args), 30, describe_command(args));
  ASSERT_EQ(got.size(), 900u);
  for (std::size_t i = 0; i < got.size(); ++i)
    EXPECT_TRUE(std::isfinite(got[i])) << "index " << i << ": " << got[i];
  expect_bit_equal(got, reference_values(30, 0.2, -0.9, 0.4), describe_command(args));
}

TEST(CliEval, DirectionIsNormalised) {
  const CommandResult unit = run_shtool({"eval", "--order", "6", "--dir", "0,0,1"});
  const CommandResult scaled = run_shtool({"eval", "--order", "6", "--dir", "0,0,5"});
  const std::vector<double> a = parse_eval_output(unit, 6, "--dir 0,0,1");
  const std::vector<double> b = parse_eval_output(scaled, 6, "--dir 0,0,5");
  expect_bit_equal(b, a, "--dir 0,0,5 vs --dir 0,0,1");
  EXPECT_EQ(scaled.out, unit.out);

  // Independent of eval_sh: at the north pole y_l^0 = sqrt((2l+1)/(4 pi)) (P_l(1) = 1)
  // and every m != 0 term carries sin(t) = 0.
  // Tolerance: the constants pass through a few multiplications and a sqrt, so a few ulp.
  const double kPoleTol = 8 * std::numeric_limits<double>::epsilon();
  ASSERT_EQ(b.size(), 36u);
  for (int l = 0; l < 6; ++l) {
    for (int m = -l; m <= l; ++m) {
      const double want = m == 0 ? std::sqrt((2 * l + 1) / (4 * std::numbers::pi)) : 0.0;
      const double got = b[shtool::sh_index(l, m)];
      EXPECT_NEAR(got, want, kPoleTol * std::max(1.0, std::abs(want)))
          << "y_" << l << "^" << m << " at --dir 0,0,5: " << std::setprecision(17) << got
          << " vs " << want;
    }
  }
  // The printed text itself: y_0^0 = 1 / (2 sqrt(pi)) to 17 significant digits.
  EXPECT_NE(scaled.out.find("0.28209479177387814"), std::string::npos) << scaled.out;
}

TEST(CliEval, NegativeOrderAndDirectionAsSeparateArguments) {
  // A direction starting with '-' must be taken as the option's value, not as a flag.
  const std::vector<std::string> args = {"eval", "--order", "2", "--dir", "-1,0,0"};
  const std::vector<double> got = parse_eval_output(run_shtool(args), 2, describe_command(args));
  expect_bit_equal(got, reference_values(2, -1, 0, 0), describe_command(args));
  // y_1^1 = -c x with c = sqrt(3 / (4 pi)): positive at x = -1.
  ASSERT_EQ(got.size(), 4u);
  EXPECT_NEAR(got[3], std::sqrt(3 / (4 * std::numbers::pi)), 4 * std::numeric_limits<double>::epsilon());
}

// ---------------------------------------------------------------------------
// shtool eval: bad input. Exit code 1, nothing on stdout, a message naming the problem.

struct BadInput {
  std::vector<std::string> args;
  std::vector<std::string> message_contains;  // every one must appear in stderr
};

void PrintTo(const BadInput& b, std::ostream* os) { *os << describe_command(b.args); }

class CliEvalBadInput : public ::testing::TestWithParam<BadInput> {};

TEST_P(CliEvalBadInput, FailsCleanly) {
  const BadInput& bad = GetParam();
  std::vector<std::string> args = {"eval"};
  args.insert(args.end(), bad.args.begin(), bad.args.end());
  const CommandResult r = run_shtool(args);
  const std::string what = describe_command(args);
  EXPECT_EQ(r.exit_code, 1) << what << "\nstderr: " << r.err;
  EXPECT_EQ(r.out, "") << what << ": no partial output on error";
  EXPECT_FALSE(r.err.empty()) << what;
  for (const std::string& needle : bad.message_contains)
    EXPECT_NE(r.err.find(needle), std::string::npos)
        << what << ": stderr should mention '" << needle << "'; stderr: " << r.err;
}

INSTANTIATE_TEST_SUITE_P(
    Cli, CliEvalBadInput,
    ::testing::Values(
        BadInput{{"--order", "3", "--dir", "0,0,0"}, {"--dir", "non-zero"}},
        BadInput{{"--order", "3", "--dir", "-0,0,0"}, {"--dir", "non-zero"}},
        BadInput{{"--order", "3", "--dir", "nan,0,1"}, {"--dir", "nan"}},
        BadInput{{"--order", "3", "--dir", "0,NaN,1"}, {"--dir", "NaN"}},
        BadInput{{"--order", "3", "--dir", "inf,0,1"}, {"--dir", "inf"}},
        BadInput{{"--order", "3", "--dir", "0,0,-inf"}, {"--dir", "inf"}},
        BadInput{{"--order", "3", "--dir", "1e999,0,1"}, {"--dir", "1e999"}},
        BadInput{{"--order", "3", "--dir", "1,2"}, {"--dir", "3"}},
        BadInput{{"--order", "3", "--dir", "1,,2"}, {"--dir", "1,,2"}},
        BadInput{{"--order", "3", "--dir", "a,b,c"}, {"--dir", "a"}},
        BadInput{{"--order", "3", "--dir", "1,2,3,4"}, {"--dir", "3", "4"}},
        BadInput{{"--order", "3", "--dir", "1,2,3x"}, {"--dir", "3x"}},
        BadInput{{"--order", "3", "--dir", ""}, {"--dir"}},
        BadInput{{"--order", "0", "--dir", "0,0,1"}, {"--order", "0"}},
        BadInput{{"--order", "-1", "--dir", "0,0,1"}, {"--order", "-1"}},
        BadInput{{"--order", "129", "--dir", "0,0,1"}, {"--order", "129"}},
        BadInput{{"--order", "3"}, {"--dir"}}),
    [](const ::testing::TestParamInfo<BadInput>& info) {
      return "case" + std::to_string(info.index);
    });

}  // namespace
