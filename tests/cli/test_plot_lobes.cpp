// scripts/plot_lobes.py (the figures of docs/lobes.md): its self-check mode. The script
// evaluates real SH on its own (Legendre-polynomial derivatives, not shtool's recurrence)
// to build A^_l for random lobe sets; here that evaluation must agree with `shtool eval`
// for bands 0..18, and the shipped tables recomputed by it must reproduce their stored
// zero counts and patterns with every direction among the search's candidates.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "run_command.h"

namespace {

using shtool::test::run_command;

const std::string kScript = std::string(SHTOOL_SOURCE_DIR) + "/scripts/plot_lobes.py";

TEST(PlotLobes, SelfCheckAgreesWithShtoolEvalAndTables) {
  ASSERT_FALSE(std::string(SHTOOL_EXE).empty()) << "shtool executable not built";
  const auto r = run_command({SHTOOL_PYTHON, kScript, "--check", "--shtool", SHTOOL_EXE}, {.timeout_seconds = 120});
  EXPECT_EQ(r.exit_code, 0) << "stdout:\n" << r.out << "\nstderr:\n" << r.err;
  EXPECT_NE(r.out.find("SH: max |script - shtool eval|"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("zero counts and patterns match"), std::string::npos) << r.out;
}

TEST(PlotLobes, SelfCheckFailsWhenShtoolFails) {
  // A failing evaluator must fail the check, not be skipped.
  const auto r = run_command({SHTOOL_PYTHON, kScript, "--check", "--shtool", "/bin/false"}, {.timeout_seconds = 120});
  EXPECT_NE(r.exit_code, 0) << r.out;
  EXPECT_NE(r.err.find("plot_lobes.py: error"), std::string::npos) << r.err;
}

TEST(PlotLobes, NoTablesIsAClearError) {
  const auto dir = std::filesystem::temp_directory_path() / "shtool_test_plot_lobes_empty";
  std::filesystem::create_directories(dir);
  const auto r = run_command({SHTOOL_PYTHON, kScript, "--check", "--tables", dir.string()}, {.timeout_seconds = 60});
  std::filesystem::remove_all(dir);
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.err.find("no zhf-bands"), std::string::npos) << r.err;
}

}  // namespace
