// End-to-end tests of `shtool fit-glossy` and `render --shading glossy`: the table and
// its summary (shapes, the schema, the figures), the same bytes on 1 and 2 threads, the
// furnace of a flat Phong surface seen along its normal (albedo 1), render picking the
// glossy shading from the table, and bad requests refused with a message, exit 1 and no
// output.
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "lighting/image_io.h"
#include "cli_test.h"
#include "shtool/glossy.h"
#include "shtool/table.h"

namespace {

using namespace shtool::test;

const Scratch scratch("cli_fit_glossy");

std::vector<std::string> small(const fs::path& out, const fs::path& json, int threads) {
  return {"fit-glossy", kSpotObj, "--rays", "64", "--view-resolution", "8", "--lobes", "3", "--effort", "1",
          "--threads", std::to_string(threads), "--out", out.string(), "--json", json.string()};
}

TEST(CliFitGlossy, WritesTheTableAndTheSummary) {
  const shtool::Result<TableAndSummary> written =
      run_table_and_summary(scratch, small, "normalized RMS: SVD", {"glossy-zh", 1, 4});
  ASSERT_TRUE(written.ok()) << written.error().message;
  const nlohmann::json &summary = written.value().summary, &meta = written.value().meta;
  const shtool::Result<shtool::GlossyFit<double>> fit = shtool::GlossyFit<double>::from_table(written.value().table);
  ASSERT_TRUE(fit.ok()) << fit.error().message;
  EXPECT_EQ(fit.value().vertices, 2930u);
  EXPECT_EQ(fit.value().terms, 6);
  EXPECT_EQ(fit.value().view_resolution, 8);
  EXPECT_EQ(fit.value().rows.lobes, 3);
  EXPECT_EQ(fit.value().rows.direct_count, 4);  // DC and the linear band, stored from 3 lobes on
  EXPECT_EQ(summary["normalized_rms"]["svd"], meta["svd_normalized_rms"]);
  EXPECT_EQ(summary["normalized_rms"]["zh"], meta["zh_normalized_rms"]);
  EXPECT_EQ(summary["singular_values"].size(), 16u);
  // Six of sixteen singular values keep most, not all, of B (0.307 here; 0.617 with
  // three); the fit adds little.
  const double svd = summary["normalized_rms"]["svd"], zh = summary["normalized_rms"]["zh"];
  EXPECT_GT(svd, 0.2);
  EXPECT_LT(svd, 0.45);
  EXPECT_LT(zh, 0.05);
  EXPECT_NEAR(summary["normalized_rms"]["total"].get<double>(), std::hypot(svd, zh), 1e-15);
  expect_valid_against_schema("glossy-zh.schema.json", {written.value().out});
}

TEST(CliFitGlossy, SameBytesOnOneAndTwoThreads) { expect_same_bytes_on_one_and_two_threads(scratch, small); }

TEST(CliFitGlossy, FlatPhongSurfaceSeenAlongItsNormalHasAlbedoOne) {
  // A square facing +z under constant radiance 1, seen from 5 units up with a 2 degree
  // field of view: every pixel's view is within 1.5 degrees of the normal, and the u(v)
  // texels around the normal within 2.5, where the normalised Phong lobe's albedo is 1 to
  // 1e-3. With all 16 SVD terms the shading is B's
  // DC column exactly, up to the bilinear u(v) look-up; with 3 terms the truncation shows.
  const fs::path mesh = scratch("square.obj");
  std::ofstream(mesh) << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n";
  const fs::path light = scratch("white.json");
  ASSERT_EQ(run_shtool({"light", "--type", "constant", "--color", "1,1,1", "--order", "4", "--json", light.string()}).exit_code,
            0);
  for (const std::string terms : {"16", "3"}) {
    const fs::path table = scratch("square" + terms + ".shtb"), image = scratch("square" + terms + ".exr");
    // The square is written in shtool's frame: --up z.
    CommandResult r = run_shtool({"fit-glossy", mesh.string(), "--up", "z", "--brdf", "phong", "--roughness",
                           "0.30151134457776363", "--mode", "unshadowed", "--terms", terms, "--lobes", "1", "--out",
                           table.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run_shtool({"render", mesh.string(), "--up", "z", "--fit", table.string(), "--light", light.string(), "--camera", "0,0,5,0,0,0,0,1,0",
             "--fov", "2", "--width", "32", "--height", "32", "--out", image.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const shtool::lighting::Image img = read_image(image);
    double worst = 0;
    for (std::size_t p = 0; p < std::size_t(img.width) * img.height; ++p)
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(img.texels[p * img.channels + c] - 1.0));
    if (terms == "16")
      EXPECT_LT(worst, 2e-3);
    else
      EXPECT_GT(worst, 0.05);
  }
}

TEST(CliFitGlossy, RenderShadesTheTableAsGlossy) {
  const fs::path table = scratch("r.shtb"), json = scratch("r.json"), light = scratch("sun.json");
  ASSERT_EQ(run_shtool(small(table, json, 2)).exit_code, 0);
  ASSERT_EQ(run_shtool({"light", "--type", "directional", "--dir", "0,0.25,1", "--order", "4", "--json", light.string()}).exit_code, 0);
  const fs::path a = scratch("auto.exr"), b = scratch("glossy.exr");
  CommandResult r = run_shtool({"render", kSpotObj, "--fit", table.string(), "--light", light.string(), "--width", "48",
                         "--height", "48", "--out", a.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_shtool({"render", kSpotObj, "--fit", table.string(), "--light", light.string(), "--width", "48", "--height", "48",
           "--shading", "glossy", "--threads", "1", "--out", b.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_file(a), read_file(b));
  const shtool::lighting::Image img = read_image(a);
  double brightest = 0;
  for (float v : img.texels) brightest = std::max(brightest, double(v));
  EXPECT_GT(brightest, 0.1);
  // A diffuse table is not a glossy one; another mesh's table is refused.
  const fs::path diffuse = scratch("d.shtb");
  ASSERT_EQ(run_shtool({"fit-zh", kSpotObj, "--order", "4", "--rays", "16", "--lobes", "1", "--out", diffuse.string()}).exit_code,
            0);
  const fs::path bad = scratch("bad.exr");
  r = run_shtool({"render", kSpotObj, "--fit", diffuse.string(), "--light", light.string(), "--shading", "glossy", "--out",
           bad.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("glossy-zh"), std::string::npos) << r.err;
  const fs::path square = scratch("other.obj");
  std::ofstream(square) << "v -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nf 1 2 3\nf 1 3 4\n";
  r = run_shtool({"render", square.string(), "--fit", table.string(), "--light", light.string(), "--out", bad.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("another mesh"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(bad));
}

// A flat grid whose OBJ carries normals tilted 27 degrees off its face: baked with
// --normals computed, it must be drawn with computed normals too (the glossy frames are
// the bake's), so it renders as the same grid written without normals. And a pose without
// normals of a rest mesh with them, both in the same place, turns no lobe.
TEST(CliFitGlossy, TheBakesNormalsAreTheOnesDrawnAndDeformed) {
  std::string v, f, fn;
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i) v += "v " + std::to_string(i - 1.5) + " " + std::to_string(j - 1.5) + " 0\n";
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) {
      const int a = 4 * j + i + 1, b = a + 1, c = a + 5, d = a + 4;
      for (const auto& t : {std::array<int, 3>{a, b, c}, std::array<int, 3>{a, c, d}}) {
        f += "f " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
        fn += "f " + std::to_string(t[0]) + "//1 " + std::to_string(t[1]) + "//1 " + std::to_string(t[2]) + "//1\n";
      }
    }
  const fs::path plain = scratch("grid.obj"), tilted = scratch("grid_vn.obj"), light = scratch("grid_light.json");
  std::ofstream(plain) << v << f;
  std::ofstream(tilted) << v << "vn 0.5 0 1\n" << fn;
  ASSERT_EQ(run_shtool({"light", "--type", "directional", "--dir", "1,0,1", "--order", "4", "--json", light.string()})
                .exit_code,
            0);
  const fs::path a = scratch("grid.shtb"), b = scratch("grid_vn.shtb");
  for (const auto& [mesh, table, normals] : {std::tuple{plain, a, "auto"}, std::tuple{tilted, b, "computed"}}) {
    const CommandResult r = run_shtool({"fit-glossy", mesh.string(), "--up", "z", "--rays", "64", "--mode",
                                        "unshadowed", "--lobes", "1", "--normals", normals, "--out", table.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
  }
  std::vector<std::vector<float>> images;
  for (const auto& [mesh, table] : {std::pair{plain, a}, std::pair{tilted, b}}) {
    const fs::path image = scratch("grid_" + table.stem().string() + ".exr");
    const CommandResult r =
        run_shtool({"render", mesh.string(), "--up", "z", "--fit", table.string(), "--light", light.string(),
                    "--camera", "-2,0,2,0,0,0,0,0,1", "--width", "32", "--height", "32", "--out", image.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    images.push_back(read_image(image).texels);
  }
  EXPECT_EQ(images[0], images[1]);

  // The same with a bake that required the file's normals: its pose need not have them.
  for (const std::string normals : {"auto", "file"}) {
    const fs::path fit = scratch("grid_vn_" + normals + ".zh.shtb"), moved = scratch("grid_moved.shtb");
    CommandResult r = run_shtool({"fit-zh", tilted.string(), "--up", "z", "--order", "3", "--lobes", "1", "--rays",
                                  "16", "--normals", normals, "--out", fit.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    r = run_shtool({"deform", fit.string(), "--rest", tilted.string(), "--pose", plain.string(), "--up", "z", "--out",
                    moved.string()});
    ASSERT_EQ(r.exit_code, 0) << normals << ": " << r.err;
    // acos of a trace within rounding of 3: 2e-8; the file's normals against computed
    // ones gave 0.47.
    const std::size_t at = r.err.find("largest frame rotation ");
    ASSERT_NE(at, std::string::npos) << r.err;
    EXPECT_LT(std::stod(r.err.substr(at + 23)), 1e-6) << normals << ": " << r.err;
  }
}

TEST(CliFitGlossy, BadOptionsAreRefusedWithoutOutput) {
  const fs::path out = scratch("bad.shtb");
  const std::vector<Refused> cases = {
      {{"--order", "1"}, "--order"},         {{"--order", "9"}, "--order"},
      {{"--terms", "0"}, "--terms"},         {{"--terms", "17"}, "--terms"},
      {{"--lobes", "0"}, "--lobes"},         {{"--view-resolution", "1"}, "--view-resolution"},
      {{"--rays", "0"}, "--rays"},           {{"--roughness", "0.01"}, "--roughness"},
      {{"--roughness", "nan"}, "--roughness"}, {{"--roughness", "1.5"}, "--roughness"},
      {{"--f0", "-0.1"}, "--f0"},            {{"--brdf", "ward"}, "--brdf"},
      {{"--effort", "5"}, "--effort"},       {{"--json", out.string()}, "--json"},
      {{"--mode", "interreflected"}, "--mode"}, {{"--view-resolution", "2", "--terms", "5"}, "--terms"},
  };
  expect_all_refused("fit-glossy", {kSpotObj, "--rays", "8"}, cases, out);
  const fs::path missing = scratch("no-such-folder") / "g.shtb";
  CommandResult r = run_shtool({"fit-glossy", kSpotObj, "--rays", "8", "--out", missing.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--out"), std::string::npos) << r.err;
  r = run_shtool({"fit-glossy", scratch("no-such-mesh.obj").string(), "--out", out.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_FALSE(fs::exists(out));
  r = run_shtool({"fit-glossy", kSpotObj, "--out", kSpotObj});
  EXPECT_EQ(r.exit_code, 1);
}

}  // namespace
