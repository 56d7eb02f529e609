// scripts/plot_lobes.py (the figures of docs/lobes.md): its self-check mode. The script
// evaluates real SH on its own (Legendre-polynomial derivatives, not shtool's recurrence)
// to build A^_l for random lobe sets; here that evaluation must agree with `shtool eval`
// for bands 0..18, and the shipped tables recomputed by it must reproduce their stored
// zero counts and patterns with every direction among the search's candidates.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "cli_test.h"

namespace {

using namespace shtool::test;

// A function, not a global: a global built from kSourceDir (an inline variable of
// another header) may be initialised before it, and clang at -O0 does so.
std::string script() { return shtool::test::kSourceDir + "/scripts/plot_lobes.py"; }

TEST(PlotLobes, SelfCheckAgreesWithShtoolEvalAndTables) {
  ASSERT_FALSE(kShtoolExe.empty()) << "shtool executable not built";
  const auto r = run_checked({SHTOOL_PYTHON, script(), "--check", "--shtool", kShtoolExe});
  EXPECT_EQ(r.exit_code, 0) << "stdout:\n" << r.out << "\nstderr:\n" << r.err;
  EXPECT_NE(r.out.find("SH: max |script - shtool eval|"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("zero counts and patterns match"), std::string::npos) << r.out;
}

TEST(PlotLobes, SelfCheckFailsWhenShtoolFails) {
  // A failing evaluator must fail the check, not be skipped.
  const auto r = run_checked({SHTOOL_PYTHON, script(), "--check", "--shtool", "/bin/false"});
  EXPECT_NE(r.exit_code, 0) << r.out;
  EXPECT_NE(r.err.find("plot_lobes.py: error"), std::string::npos) << r.err;
}

TEST(PlotLobes, NoTablesIsAClearError) {
  const auto dir = shtool::test::empty_folder_for_this_test(shtool::test::Scratch("plot_lobes"));
  const auto r = run_checked({SHTOOL_PYTHON, script(), "--check", "--tables", dir.string()});
  EXPECT_EQ(r.exit_code, 1) << r.out;
  EXPECT_NE(r.err.find("no zhf-bands"), std::string::npos) << r.err;
}

}  // namespace
