// End-to-end tests of `shtool fit-zh`: the bundled spot.obj with few rays, fits of given
// vectors, output formats, and bad input (exit 1, a message, no output written).
// The fits are checked against the transfer vectors the same run saved, by rebuilding
// the SH vector of the lobes with the runtime (an independent path from the fitter's
// own residual), and the table header against schemas/zh-fit.schema.json.
#include <cmath>
#include <cstdlib>
#include <iterator>
#include <numbers>

#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "run_command.h"
#include "shtool/sh.h"
#include "shtool/table.h"
#include "shtool/zh.h"

namespace {

using shtool::test::CommandResult;
namespace fs = std::filesystem;

const std::string kExe = SHTOOL_EXE;
const std::string kSource = SHTOOL_SOURCE_DIR;

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("shtool_test_cli_fit_zh_" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir / name;
}

CommandResult run(std::vector<std::string> args) {
  args.insert(args.begin(), kExe);
  shtool::test::CommandOptions options;
  options.timeout_seconds = 120;  // only turns a hang into a failure
  CommandResult r = shtool::test::run_command(args, options);
  EXPECT_FALSE(r.signaled) << shtool::test::describe_command(args) << " killed by signal " << r.signal;
  return r;
}

nlohmann::json read_json(const fs::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

// ||sum of lobes - t||, rebuilt with the runtime's add_zh_lobe_to_sh.
double rebuilt_residual(const nlohmann::json& fit, const std::vector<double>& t, int order) {
  std::vector<double> sh(t.size(), 0.0);
  for (const nlohmann::json& lobe : fit["lobes"]) {
    const std::vector<double> a = lobe["axis"].get<std::vector<double>>();
    const std::vector<double> c = lobe["coeffs"].get<std::vector<double>>();
    EXPECT_EQ(static_cast<int>(c.size()), order);
    shtool::add_zh_lobe_to_sh(Eigen::Vector3d(a[0], a[1], a[2]), c, sh);
  }
  if (fit.contains("direct")) {
    const std::vector<double> d = fit["direct"].get<std::vector<double>>();
    for (std::size_t i = 0; i < d.size(); ++i) sh[i] += d[i];
  }
  double r = 0;
  for (std::size_t i = 0; i < t.size(); ++i) r += (sh[i] - t[i]) * (sh[i] - t[i]);
  return std::sqrt(r);
}

TEST(CliFitZh, SpotEndToEnd) {
  const fs::path table = scratch("spot.shtb"), json = scratch("spot.json"), saved = scratch("spot_t.json"),
                 ply = scratch("spot.ply");
  const CommandResult r = run({"fit-zh", kSource + "/data/spot.obj", "--rays", "16", "--order", "3", "--lobes", "2",
                               "--starts", "0", "--out", table.string(), "--json", json.string(), "--save-transfer",
                               saved.string(), "--ply", ply.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("normalized RMS"), std::string::npos) << r.err;

  const nlohmann::json fits = read_json(json), transfer = read_json(saved);
  ASSERT_EQ(fits["order"], 3);
  ASSERT_EQ(fits["lobes"], 2);
  const std::size_t count = transfer["vectors"].size();
  ASSERT_EQ(fits["fits"].size(), count);
  ASSERT_GT(count, 1000u);
  double sum_res = 0, sum_norm = 0;
  for (std::size_t v = 0; v < count; v += 97) {
    const nlohmann::json& f = fits["fits"][v];
    const std::vector<double> t = transfer["vectors"][v].get<std::vector<double>>();
    ASSERT_EQ(f["lobes"].size(), 2u);
    // Both residuals sum 9 squared differences of O(1) values: 1e-13 is rounding.
    EXPECT_NEAR(f["residual"].get<double>(), rebuilt_residual(f, t, 3), 1e-13) << "vertex " << v;
    double n = 0;
    for (double x : t) n += x * x;
    EXPECT_NEAR(f["norm"].get<double>(), std::sqrt(n), 1e-15) << "vertex " << v;
    sum_res += std::pow(f["residual"].get<double>(), 2);
    sum_norm += n;
    // Spot is closed: DC of the transfer is in (0, unshadowed value].
    EXPECT_GT(t[0], 0.0);
    EXPECT_LE(t[0], 0.5 / std::sqrt(std::numbers::pi) * (1 + 1e-12));
  }
  // Two lobes fit smooth diffuse transfer well ([4] Fig. 3: 0.123 at order 6).
  EXPECT_LT(std::sqrt(sum_res / sum_norm), 0.15);

  // The table holds the same numbers, bit for bit.
  const shtool::Result<shtool::Table> loaded = shtool::read_table(table, {"zh-fit", 1, 3});
  ASSERT_TRUE(loaded.ok()) << loaded.error().message;
  const std::vector<double> residual = loaded.value().get<double>("residual").value();
  const std::vector<double> axes = loaded.value().get<double>("axes").value();
  ASSERT_EQ(residual.size(), count);
  EXPECT_EQ(residual[5], fits["fits"][5]["residual"].get<double>());
  EXPECT_EQ(axes[3 * 2 + 1], fits["fits"][1]["lobes"][0]["axis"][1].get<double>());
  ASSERT_TRUE(loaded.value().get<std::uint32_t>("vertex_index").ok());

  const std::string cmd = std::string(SHTOOL_PYTHON) + " '" + kSource + "/tests/validate_json_schema.py' '" + kSource +
                          "/schemas/zh-fit.schema.json' '" + table.string() + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;

  std::ifstream p(ply);
  std::string magic;
  p >> magic;
  EXPECT_EQ(magic, "ply");
}

TEST(CliFitZh, TransferFileWithKnownLobeAndDeterminism) {
  // One vector made of a single order-4 lobe along (0, 0.6, 0.8) with g* = (1, 0.5,
  // -0.25, 0.1): fitted exactly with one lobe.
  const Eigen::Vector3d axis(0, 0.6, 0.8);
  const std::vector<double> g = {1, 0.5, -0.25, 0.1};
  std::vector<double> t(16, 0.0);
  shtool::add_zh_lobe_to_sh(axis, g, t);
  const fs::path in = scratch("known.json"), out1 = scratch("k1.json"), out2 = scratch("k2.json");
  std::ofstream(in) << nlohmann::json{{"order", 4}, {"vectors", {t, t}}}.dump();
  for (const fs::path& out : {out1, out2}) {
    const CommandResult r = run({"fit-zh", "--transfer", in.string(), "--lobes", "1", "--out",
                                 scratch("k.shtb").string(), "--json", out.string(), "--threads",
                                 out == out1 ? "1" : "2"});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  const nlohmann::json f = read_json(out1);
  const std::vector<double> a = f["fits"][0]["lobes"][0]["axis"].get<std::vector<double>>();
  // The fit is exact to BFGS tolerance (~1e-6 relative in the residual).
  EXPECT_NEAR(std::abs(a[1] * 0.6 + a[2] * 0.8), 1.0, 1e-6);
  EXPECT_LT(f["fits"][0]["residual"].get<double>(), 1e-5);
  std::ifstream s1(out1), s2(out2);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(s1), {}), std::string(std::istreambuf_iterator<char>(s2), {}));
}

TEST(CliFitZh, BadInputExitsOneWithAMessageAndNoOutput) {
  struct Case {
    std::string name, obj, message;
  };
  const std::vector<Case> cases = {
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "refers to vertex 4"},
      {"nofaces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"},
      {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "no usable triangle"},
  };
  for (const Case& c : cases) {
    const fs::path obj = scratch(c.name), out = scratch(c.name + ".shtb");
    std::ofstream(obj) << c.obj;
    const CommandResult r = run({"fit-zh", obj.string(), "--rays", "4", "--out", out.string()});
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
  const CommandResult missing = run({"fit-zh", scratch("missing.obj").string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("no such file"), std::string::npos) << missing.err;
  const CommandResult neither = run({"fit-zh"});
  EXPECT_EQ(neither.exit_code, 1);
  const fs::path bad = scratch("bad_transfer.json");
  std::ofstream(bad) << R"({"order": 2, "vectors": [[1, 2, 3]]})";
  const CommandResult short_vec = run({"fit-zh", "--transfer", bad.string(), "--out", scratch("b.shtb").string()});
  EXPECT_EQ(short_vec.exit_code, 1);
  EXPECT_NE(short_vec.err.find("must have 4 numbers"), std::string::npos) << short_vec.err;
  EXPECT_FALSE(fs::exists(scratch("b.shtb")));
  const CommandResult mode = run({"fit-zh", kSource + "/data/spot.obj", "--mode", "glossy"});
  EXPECT_EQ(mode.exit_code, 1);
  EXPECT_NE(mode.err.find("--mode"), std::string::npos) << mode.err;
}

}  // namespace
