// End-to-end tests of `shtool fit-wrinkles`: a small map written and read back (shapes,
// the summary's figures against the table's), the same bytes on 1 and 2 threads, and bad
// options refused with a message naming the option, exit 1 and no output.
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_test.h"
#include "shtool/table.h"
#include "shtool/wrinkle_map.h"

namespace {

using namespace shtool::test;

const Scratch scratch("cli_fit_wrinkles");

// The small map's command with this optimizer.
TableAndSummaryCommand small(const std::string& optimizer) {
  return [optimizer](const fs::path& out, const fs::path& json, int threads) -> std::vector<std::string> {
    return {"fit-wrinkles", "--grid", "4", "--samples", "2", "--rays", "64", "--order", "4", "--max-evaluations", "200",
            "--optimizer", optimizer,
            "--threads", std::to_string(threads), "--out", out.string(), "--json", json.string()};
  };
}

TEST(CliFitWrinkles, WritesTheMapAndTheSummary) {
  const shtool::Result<TableAndSummary> written =
      run_table_and_summary(scratch, small("lbfgs"), "normalized RMS: global", {"wrinkle-zh", 1, 4});
  ASSERT_TRUE(written.ok()) << written.error().message;
  const shtool::Table& table = written.value().table;
  const nlohmann::json &summary = written.value().summary, &meta = written.value().meta;
  const auto shape = [&](const char* name) { return table.find(name)->shape; };
  ASSERT_NE(table.find("axes"), nullptr);
  EXPECT_EQ(shape("axes"), (std::vector<std::int64_t>{4, 4, 3, 3}));
  EXPECT_EQ(shape("coeffs"), (std::vector<std::int64_t>{4, 4, 3, 4}));
  EXPECT_EQ(shape("direct"), (std::vector<std::int64_t>{4, 4, 4}));
  EXPECT_EQ(table.find("x")->values<double>(), (std::vector<double>{0.0, 0.25, 0.5, 0.75}));
  EXPECT_EQ(table.find("depth")->values<double>().back(), 1.0);
  // Lobe coefficients of bands 0 and 1 are zero: those bands are stored directly.
  const std::vector<double> coeffs = table.find("coeffs")->values<double>();
  for (std::size_t i = 0; i < coeffs.size(); i += 4) {
    EXPECT_EQ(coeffs[i], 0.0);
    EXPECT_EQ(coeffs[i + 1], 0.0);
  }
  EXPECT_EQ(summary["normalized_rms"]["global"], meta["normalized_rms"]);
  EXPECT_EQ(summary["normalized_rms"]["per_point"], meta["per_point_normalized_rms"]);
  EXPECT_GT(summary["normalized_rms"]["global"].get<double>(), 0.0);
  EXPECT_EQ(summary["samples"], 8 * 7);
  EXPECT_EQ(summary["by_depth"].size(), 7u);
  // The header follows schemas/wrinkle-zh.schema.json (python3-jsonschema).
  expect_valid_against_schema("wrinkle-zh.schema.json", {written.value().out});
}

TEST(CliFitWrinkles, SameBytesOnOneAndTwoThreads) {
  for (const std::string optimizer : {"lbfgs", "cg"}) {
    SCOPED_TRACE(optimizer);
    expect_same_bytes_on_one_and_two_threads(scratch, small(optimizer));
  }
}

TEST(CliFitWrinkles, EveryMapWrittenLoadsOrNothingIsWritten) {
  // With few samples a cell, a lobe that carries little at one node turns freely there,
  // and neighbouring axes could spread so far that the blend passes through zero, which
  // the runtime refuses. The fit mends such a map (lobes turned to agree, weak axes moved
  // to their neighbours'); one it cannot mend is refused with nothing written. Before
  // the mend, every one of these wrote a map the runtime refused.
  const std::vector<std::vector<std::string>> settings = {
      {"--order", "4", "--lobes", "2", "--grid", "6", "--samples", "1", "--rays", "128"},
      {"--grid", "16", "--samples", "2", "--rays", "512"},
      {"--grid", "8", "--samples", "1", "--rays", "256"},
      {"--order", "6", "--lobes", "3", "--grid", "8", "--rays", "256"},
      {"--order", "4", "--lobes", "2", "--grid", "6", "--samples", "1", "--rays", "128", "--optimizer", "cg"},
  };
  int loaded = 0;
  for (std::size_t i = 0; i < settings.size(); ++i) {
    const fs::path out = scratch("mend" + std::to_string(i) + ".shtb");
    std::vector<std::string> args = {"fit-wrinkles", "--threads", "2", "--out", out.string()};
    args.insert(args.end(), settings[i].begin(), settings[i].end());
    const CommandResult r = run_shtool(args);
    if (r.exit_code == 0) {
      const shtool::Result<shtool::WrinkleMap<double>> map = shtool::WrinkleMap<double>::load(out);
      EXPECT_TRUE(map.ok()) << i << ": " << map.error().message;
      ++loaded;
    } else {
      EXPECT_EQ(r.exit_code, 1) << i;
      EXPECT_NE(r.err.find("the fitted map would not load"), std::string::npos) << r.err;
      EXPECT_FALSE(fs::exists(out)) << i;
    }
  }
  EXPECT_GE(loaded, 3);
}

TEST(CliFitWrinkles, BadOptionsAreRefusedWithoutOutput) {
  const fs::path out = scratch("bad.shtb");
  expect_all_refused("fit-wrinkles", {"--grid", "3", "--rays", "8"},
                     {
                         {{"--order", "2"}, "--order"},
                         {{"--order", "9"}, "--order"},
                         {{"--lobes", "0"}, "--lobes"},
                         {{"--lobes", "5"}, "--lobes"},
                         {{"--grid", "1"}, "--grid"},
                         {{"--samples", "0"}, "--samples"},
                         {{"--rays", "0"}, "--rays"},
                         {{"--max-depth", "0"}, "--max-depth"},
                         {{"--max-depth", "-1"}, "--max-depth"},
                         {{"--max-depth", "nan"}, "--max-depth"},
                         {{"--max-evaluations", "0"}, "--max-evaluations"},
                         {{"--seed", "-3"}, "--seed"},
                         {{"--json", out.string()}, "--json"},
                         {{"--optimizer", "bfgs"}, "--optimizer"},
                     },
                     out);
  // A folder that does not exist, and no --out at all.
  const fs::path missing = scratch("no-such-folder") / "w.shtb";
  CommandResult r = run_shtool({"fit-wrinkles", "--grid", "3", "--rays", "8", "--out", missing.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(missing));
  r = run_shtool({"fit-wrinkles", "--grid", "3"});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
}

}  // namespace
