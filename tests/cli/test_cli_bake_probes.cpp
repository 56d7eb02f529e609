// End-to-end tests of `shtool bake-probes`: the table and --json of a white furnace read
// back by the runtime loader (ProbeGrid<float> and <double>), the schema, --threejs (the
// atlas of the same run's coefficients), OBJ scenes with
// .mtl materials and --up, the same bytes on 1 and 2 threads, bad scenes, grids,
// bounds and options refused with a message, exit 1 and no output, --encoding l1 and
// zh3 (with --zh3-fit and --zh3-axis) through the table, --json, the loader, --threejs and
// merge, and the loader's reading of kind_version 1.0 and 1.1 tables.
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_test.h"
#include "common/table_writer.h"
#include "interop/three_probe_grid.h"
#include "probe_scenes.h"
#include "shtool/probe_grid.h"
#include "shtool/table.h"

namespace {

using namespace shtool::test;
constexpr double kPi = std::numbers::pi;

const Scratch scratch("cli_bake_probes");

// A closed box, walls of albedo 0.5 emitting 1: every probe's radiance is 1 + 0.5 + 0.25
// for two bounces, in every direction (test_probes.cpp, WhiteFurnace...), up to the noise
// of emitter sampling.
fs::path furnace() {
  const fs::path path = scratch("furnace.gltf");
  ProbeTestScene t;
  const int m = t.material({{0.5, 0.5, 0.5}, {0.5, 0.5, 0.5}, 2.0, false});
  t.box(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1), m, true);
  t.write(path);
  return path;
}

// The --threejs input of a baked grid (order 3), its coefficients still to be filled.
shtool::interop::ThreeProbeGridInput three_grid(std::array<int, 3> resolution, const Eigen::Vector3d& min,
                                                const Eigen::Vector3d& max) {
  shtool::interop::ThreeProbeGridInput g;
  g.resolution = resolution;
  g.min = min;
  g.max = max;
  g.order = 3;
  return g;
}

// The files --threejs wrote in `dir` are, byte for byte, those of `g`.
void expect_three_files(const fs::path& dir, const shtool::interop::ThreeProbeGridInput& g, const std::string& why) {
  const shtool::interop::ThreeProbeGridFiles want = shtool::interop::three_probe_grid_files(g);
  EXPECT_EQ(read_file(dir / "probes.json"), want.json);
  EXPECT_TRUE(read_file(dir / "probes.bin") == want.atlas) << why;
}

TEST(CliBakeProbes, FurnaceTableJsonAndLoader) {
  const fs::path scene = furnace(), out = scratch("f.shtb"), json = scratch("f.json");
  const CommandResult r = run_shtool({"bake-probes", scene.string(), "--grid", "3,2,2", "--bounds",
                                      "-0.9,-0.8,-0.7,0.9,0.8,0.7", "--samples", "512", "--bounces", "2", "--order",
                                      "3", "--out", out.string(), "--json", json.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const double L = 1.75;
  const nlohmann::json doc = read_json(json);
  EXPECT_EQ(doc["order"], 3);
  EXPECT_EQ(doc["quantity"], "radiance");
  EXPECT_EQ(doc["channels"], nlohmann::json({"r", "g", "b"}));
  EXPECT_EQ(doc["resolution"], nlohmann::json({3, 2, 2}));
  EXPECT_EQ(doc["bounds"]["min"], nlohmann::json({-0.9, -0.8, -0.7}));
  EXPECT_EQ(doc["bounds"]["max"], nlohmann::json({0.9, 0.8, 0.7}));
  ASSERT_EQ(doc["probes"].size(), 12u);
  // Index order: ix fastest, then iy, then iz; cell centres.
  const nlohmann::json& p5 = doc["probes"][5];  // ix 2, iy 1, iz 0
  EXPECT_EQ(p5["index"], nlohmann::json({2, 1, 0}));
  EXPECT_NEAR(p5["position"][0].get<double>(), -0.9 + 2.5 * 0.6, 1e-15);
  EXPECT_NEAR(p5["position"][1].get<double>(), -0.8 + 1.5 * 0.8, 1e-15);
  EXPECT_NEAR(p5["position"][2].get<double>(), -0.7 + 0.5 * 0.7, 1e-15);
  for (const nlohmann::json& p : doc["probes"]) {
    EXPECT_EQ(p["valid"], true);
    ASSERT_EQ(p["coefficients"].size(), 9u);
    // Emitter sampling's noise: at most 1.4 % of c_00 measured at 512 samples (seed 1).
    for (int c = 0; c < 3; ++c)
      EXPECT_NEAR(p["coefficients"][0][c].get<double>(), std::sqrt(4 * kPi) * L, 0.03 * std::sqrt(4 * kPi) * L);
  }
  expect_valid_against_schema("probe-grid.schema.json", {out});

  const shtool::Result<shtool::ProbeGrid<double>> g = shtool::ProbeGrid<double>::load(out);
  ASSERT_TRUE(g.ok()) << g.error().message;
  const shtool::ProbeGrid<double>& grid = g.value();
  EXPECT_EQ(grid.order, 3);
  EXPECT_EQ(grid.resolution, (std::array<int, 3>{3, 2, 2}));
  ASSERT_EQ(grid.probe_count(), 12u);
  for (std::size_t p = 0; p < 12; ++p) {
    const nlohmann::json& jp = doc["probes"][p];
    EXPECT_TRUE(grid.is_valid(p));
    for (int a = 0; a < 3; ++a) EXPECT_EQ(grid.position(p)[a], jp["position"][a].get<double>());
    const auto c = grid.coefficients_of(p);
    for (int k = 0; k < 9; ++k)
      for (int ch = 0; ch < 3; ++ch) EXPECT_EQ(c[k * 3 + ch], jp["coefficients"][k][ch].get<double>());
    // Irradiance of uniform radiance L is pi L at every normal; the emitter samples' noise
    // moves it by at most 2.2 % (measured, 512 samples); a wrong A_0 moves it by O(L).
    for (const auto& n : {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0.6, -0.8, 0), Eigen::Vector3d(0, 0, -1)}) {
      const Eigen::Vector3d e = grid.irradiance(p, n);
      for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(e[ch], kPi * L, 0.05 * kPi * L);
    }
  }
  // Trilinear sampling: at a probe's centre, its own coefficients; between two probes,
  // their mean; beyond the outermost centres, clamped.
  std::vector<double> s(27);
  grid.sample(grid.position(5), s);
  for (int k = 0; k < 27; ++k) EXPECT_NEAR(s[k], grid.coefficients_of(5)[k], 1e-15);
  grid.sample((grid.position(0) + grid.position(1)) / 2, s);
  for (int k = 0; k < 27; ++k)
    EXPECT_NEAR(s[k], (grid.coefficients_of(0)[k] + grid.coefficients_of(1)[k]) / 2, 1e-15);
  grid.sample(Eigen::Vector3d(-50, -50, -50), s);
  for (int k = 0; k < 27; ++k) EXPECT_NEAR(s[k], grid.coefficients_of(0)[k], 1e-15);

  const shtool::Result<shtool::ProbeGrid<float>> gf = shtool::ProbeGrid<float>::load(out);
  ASSERT_TRUE(gf.ok()) << gf.error().message;
  EXPECT_EQ(gf.value().coefficients_of(3)[0], static_cast<float>(grid.coefficients_of(3)[0]));

  // The generator record: the scene's CRC and every option.
  const shtool::Result<shtool::Table> t = shtool::read_table(out, {"probe-grid", 1, 3});
  ASSERT_TRUE(t.ok()) << t.error().message;
  const nlohmann::json gen = nlohmann::json::parse(t.value().generator);
  EXPECT_EQ(gen["command"], "shtool bake-probes");
  EXPECT_EQ(gen["parameters"]["samples"], 512);
  EXPECT_EQ(gen["parameters"]["bounces"], 2);
  EXPECT_EQ(gen["parameters"]["bounds_from"], "option");
  EXPECT_TRUE(gen["parameters"]["input_crc32"].is_number_integer());
}

// --threejs writes three.js's files of the very coefficients --json holds (the writer's
// layout, frame and basis are checked against three's own code in test_three_probe_grid),
// and refuses what it cannot write with nothing written.
TEST(CliBakeProbes, ThreeJsFilesAreTheAtlasOfTheSameRun) {
  const fs::path scene = scratch("sun_plane.gltf"), out = scratch("t.shtb"), json = scratch("t.json"),
                 dir = scratch("three");
  ProbeTestScene t;
  const int m = t.material({{0.6, 0.5, 0.4}, {0, 0, 0}, 1.0, true});  // glTF: the floor y = 0, a sun
  t.quad(Eigen::Vector3d(-4, 0, -4), Eigen::Vector3d(-4, 0, 4), Eigen::Vector3d(4, 0, 4), Eigen::Vector3d(4, 0, -4), m);
  t.light({{"type", "directional"}, {"intensity", 3.0}, {"color", {1.0, 0.9, 0.8}}}, Eigen::Vector3d(0, 5, 0),
          Eigen::Vector3d(0.3, -0.866, 0.4));
  t.write(scene);
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::vector<std::string> base = {"bake-probes", scene.string(), "--grid", "3,2,4", "--bounds",
                                         "-1,-1,0.2,1,1,1.4", "--samples", "64", "--bounces", "1"};
  std::vector<std::string> args = base;
  args.insert(args.end(), {"--out", out.string(), "--json", json.string(), "--threejs", dir.string()});
  const CommandResult r = run_shtool(args);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json doc = read_json(json);
  shtool::interop::ThreeProbeGridInput g = three_grid({3, 2, 4}, Eigen::Vector3d(-1, -1, 0.2), Eigen::Vector3d(1, 1, 1.4));
  for (const nlohmann::json& p : doc["probes"])
    for (const nlohmann::json& row : p["coefficients"])
      for (int c = 0; c < 3; ++c) g.coefficients.push_back(row[c].get<double>());
  expect_three_files(dir, g, "the atlas is not the one of the run's coefficients");
  const nlohmann::json three = read_json(dir / "probes.json");
  EXPECT_EQ(three["resolution"], nlohmann::json({3, 4, 2}));  // three = (x, z, -y)

  // A shard has no whole grid; a missing folder cannot hold the files.
  args = base;
  args.insert(args.end(), {"--shard", "0/2", "--threejs", dir.string()});
  expect_refused(args[0], std::vector<std::string>(args.begin() + 1, args.end()), "--threejs needs the whole grid",
                 scratch("t_shard.shtb"));
  args = base;
  args.insert(args.end(), {"--threejs", (dir / "missing").string()});
  expect_refused(args[0], std::vector<std::string>(args.begin() + 1, args.end()), "--threejs",
                 scratch("t_missing.shtb"));
  EXPECT_FALSE(fs::exists(dir / "missing"));
}

TEST(CliBakeProbes, LoaderRefusesAnotherKindAndBrokenGrids) {
  const fs::path scene = furnace(), out = scratch("k.shtb");
  ASSERT_EQ(run_shtool({"bake-probes", scene.string(), "--grid", "2,2,2", "--samples", "16", "--out", out.string()})
                .exit_code,
            0);
  shtool::Table t = shtool::read_table(out).value();
  EXPECT_TRUE(shtool::ProbeGrid<double>::from_table(t).ok());
  shtool::Table wrong = t;
  wrong.kind = "zh-fit";
  EXPECT_FALSE(shtool::ProbeGrid<double>::from_table(wrong).ok());
  shtool::Table flipped = t;
  for (auto& a : flipped.arrays)
    if (a.name == "bounds") a = shtool::TableArray::from<double>("bounds", {2, 3}, std::vector<double>{1, 1, 1, 0, 0, 0});
  const auto r = shtool::ProbeGrid<double>::from_table(flipped);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("bounds"), std::string::npos) << r.error().message;
  shtool::Table bad_flag = t;
  for (auto& a : bad_flag.arrays)
    if (a.name == "valid") a = shtool::TableArray::from<std::uint8_t>("valid", {2, 2, 2}, std::vector<std::uint8_t>(8, 2));
  EXPECT_FALSE(shtool::ProbeGrid<double>::from_table(bad_flag).ok());
  // The default bounds are the scene's box.
  const nlohmann::json meta = nlohmann::json::parse(t.meta);
  EXPECT_EQ(meta["bounds"]["min"], nlohmann::json({-1.0, -1.0, -1.0}));
  EXPECT_EQ(meta["bounds"]["max"], nlohmann::json({1.0, 1.0, 1.0}));
}

TEST(CliBakeProbes, SameBytesOnOneAndTwoThreads) {
  ProbeTestScene t;
  const int walls = t.material({{0.7, 0.5, 0.3}});
  t.box(Eigen::Vector3d(-2, 0, -2), Eigen::Vector3d(2, 3, 2), walls, true);
  t.box(Eigen::Vector3d(-0.3, 0, -0.3), Eigen::Vector3d(0.3, 1, 0.3), walls, false);
  t.light({{"type", "point"}, {"intensity", 5.0}}, Eigen::Vector3d(1, 2, 1), Eigen::Vector3d(0, -1, 0));
  const fs::path scene = scratch("room.gltf");
  t.write(scene);
  expect_same_bytes_on_one_and_two_threads(scratch, [&](const fs::path& out, const fs::path& json, int threads) {
    return std::vector<std::string>{"bake-probes", scene.string(), "--grid", "3,2,3", "--samples", "64", "--threads",
                                    std::to_string(threads), "--seed", "11", "--out", out.string(), "--json", json.string()};
  });
}

// Three shards joined by merge: the one-process table byte for byte, with a probe inside
// a solid cube (invalid, filled only when the parts are joined).
TEST(CliBakeProbes, ShardsMergeToTheOneProcessTable) {
  const fs::path scene = scratch("solid.gltf");
  write_solid_cube_scene(scene);
  const std::vector<std::string> common = {"bake-probes", scene.string(), "--grid", "3,3,3", "--bounds",
                                           "-1.5,-1.5,-1.5,1.5,1.5,1.5", "--samples", "64", "--order", "2"};
  auto run = [&](std::vector<std::string> extra) {
    std::vector<std::string> a = common;
    a.insert(a.end(), extra.begin(), extra.end());
    return run_shtool(a);
  };
  const fs::path whole = scratch("whole.shtb"), whole_json = scratch("whole.json"), whole_three = scratch("whole3");
  fs::create_directories(whole_three);
  ASSERT_EQ(run({"--out", whole.string(), "--json", whole_json.string(), "--threejs", whole_three.string()}).exit_code,
            0);
  std::vector<std::string> merge = {"merge"};
  for (const char* k : {"2", "0", "1"}) {
    const fs::path part = scratch(std::string("part") + k + ".shtb");
    const CommandResult r = run({"--shard", std::string(k) + "/3", "--out", part.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("invalid probes (stored unfilled: merge fills them)"), std::string::npos) << r.err;
    expect_valid_against_schema("probe-grid.schema.json", {part});
    EXPECT_FALSE(shtool::ProbeGrid<double>::load(part).ok()) << "a partial table must not load as a grid";
    merge.push_back(part.string());
  }
  const fs::path merged = scratch("merged.shtb"), merged_json = scratch("merged.json"), merged_three = scratch("merged3");
  fs::remove_all(merged_three);
  fs::create_directories(merged_three);
  merge.insert(merge.end(), {"--out", merged.string(), "--json", merged_json.string(), "--threejs", merged_three.string()});
  const CommandResult r = run_shtool(merge);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(read_file(merged), read_file(whole));
  // The whole grid's other outputs, as the one process writes them.
  EXPECT_EQ(read_file(merged_json), read_file(whole_json));
  for (const char* f : {"probes.json", "probes.bin"})
    EXPECT_EQ(read_file(merged_three / f), read_file(whole_three / f)) << f;
  // fit-zh's parts take neither.
  const fs::path tetra = scratch("tetra.obj"), tetra_part = scratch("tetra.part.shtb");
  write_file(tetra, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
  ASSERT_EQ(run_shtool({"fit-zh", tetra.string(), "--order", "2", "--lobes", "1", "--rays", "16", "--shard", "0/1",
                        "--out", tetra_part.string()})
                .exit_code,
            0);
  expect_refused("merge", {tetra_part.string(), "--json", scratch("zh.json").string()}, "--json: only for the parts",
                 scratch("zh_merged.shtb"));
  const shtool::ProbeGrid<double> g = shtool::ProbeGrid<double>::load(merged).value();
  EXPECT_FALSE(g.is_valid(13));
  // A shard missing: refused, nothing written.
  fs::remove(merged);
  const CommandResult missing =
      run_shtool({"merge", scratch("part0.shtb").string(), scratch("part2.shtb").string(), "--out", merged.string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("shard 1 of 3 is missing"), std::string::npos) << missing.err;
  EXPECT_FALSE(fs::exists(merged));
  // A shard given twice is named as such (once "shard 2 is missing or given twice").
  expect_refused("merge",
                 {scratch("part0.shtb").string(), scratch("part1.shtb").string(), scratch("part1.shtb").string(),
                  scratch("part2.shtb").string()},
                 "shard 1 of 3 is given twice", merged);
  expect_refused("bake-probes", {scene.string(), "--grid", "3,3,3", "--shard", "0/2", "--json", scratch("j.json").string()},
                 "--json needs the whole grid", scratch("p.shtb"));
  expect_refused("bake-probes", {scene.string(), "--grid", "1,1,2", "--shard", "0/3"}, "more shards than", scratch("p.shtb"));
  expect_refused("bake-probes", {scene.string(), "--grid", "1,1,2", "--shard", "3/3"}, "K must be below N", scratch("p.shtb"));
}

// OBJ: Kd and Ke from the .mtl, the furnace again (faces wound inward, y up by default).
TEST(CliBakeProbes, ObjWithMtlMaterials) {
  const fs::path dir = empty_folder_for_this_test(scratch);
  write_file(dir / "box.mtl", "newmtl wall\nKd 0.25 0.5 0.75\nKe 1 1 1\n");
  std::string obj = "mtllib box.mtl\n";
  for (int x : {-1, 1})
    for (int y : {-1, 1})
      for (int z : {-1, 1}) obj += "v " + std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
  // Vertex (x, y, z) in {-1, 1}^3 is number 1 + 4 i + 2 j + k; faces wound inward.
  obj += "usemtl wall\n"
         "f 1 3 4 2\nf 5 6 8 7\nf 1 2 6 5\nf 3 7 8 4\nf 1 5 7 3\nf 2 4 8 6\n";
  write_file(dir / "box.obj", obj);
  const fs::path out = dir / "o.shtb", json = dir / "o.json";
  const CommandResult r = run_shtool({"bake-probes", (dir / "box.obj").string(), "--grid", "1,1,1", "--bounds",
                                      "-0.5,-0.5,-0.5,0.5,0.5,0.5", "--samples", "256", "--bounces", "1", "--out",
                                      out.string(), "--json", json.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json doc = read_json(json);
  ASSERT_EQ(doc["probes"][0]["valid"], true) << "faces wound outward?";
  const double kd[3] = {0.25, 0.5, 0.75};
  for (int c = 0; c < 3; ++c)
    // Emitter sampling's noise: 1.6 % measured at 256 samples; the channels differ by 15 %.
    EXPECT_NEAR(doc["probes"][0]["coefficients"][0][c].get<double>(), std::sqrt(4 * kPi) * (1 + kd[c]),
                0.04 * std::sqrt(4 * kPi) * (1 + kd[c]))
        << c;
}

// The .mtl's colours are read from its text: one number stands for all three (the MTL
// format's rule, once read as r 0 0), and a value that is not a finite number, or a
// library the OBJ names that is not there, is refused (tinyobjloader alone reads "nan"
// and "abc" as 0, and a missing library baked at the default 0.8, all without a word).
TEST(CliBakeProbes, ObjMaterialColoursAreReadOrRefused) {
  const fs::path dir = empty_folder_for_this_test(scratch);
  write_file(dir / "t.obj", "mtllib m.mtl\nusemtl a\nv -5 -5 0\nv 5 -5 0\nv 0 5 0\nf 1 2 3\n");
  must(run_shtool({"light", "--type", "constant", "--order", "3", "--json", (dir / "sky.json").string()}));
  // A floor under a constant sky: what it reflects is Kd times the sky.
  const std::vector<std::string> args = {
      (dir / "t.obj").string(),     "--up",      "z", "--env", (dir / "sky.json").string(), "--grid", "1,1,1",
      "--bounds=-1,-1,0.5,1,1,1.5", "--samples", "64"};
  auto bake = [&](const std::string& mtl) {
    write_file(dir / "m.mtl", "newmtl a\n" + mtl + "\n");
    std::vector<std::string> argv = {"bake-probes"};
    argv.insert(argv.end(), args.begin(), args.end());
    argv.insert(argv.end(), {"--out", (dir / "o.shtb").string()});
    must(run_shtool(argv));
    return read_file(dir / "o.shtb");
  };
  const std::string one = bake("Kd 0.5"), three = bake("Kd 0.5 0.5 0.5");
  EXPECT_TRUE(one == three) << "Kd 0.5 is not read as 0.5 0.5 0.5";
  EXPECT_FALSE(one == bake("Kd 0.5 0 0"));
  for (const auto& [mtl, message] : std::vector<std::pair<std::string, std::string>>{
           {"Kd 0.5 nan 0.5", "material 'a' (its library's line 2): Kd nan is not a finite number"},
           {"Kd 0.5 inf 0.5", "Kd inf is not a finite number"},
           {"Kd 0.5 abc 0.5", "Kd 'abc' is not a number"},
           {"Kd 0.5 0.5", "Kd has 2 numbers"},
           {"Ke nan 0 0", "Ke nan is not a finite number"},
           {"Kd 0.5 1e39 0.5", "Kd 1e39 is not a finite number (or is beyond float range)"}}) {
    write_file(dir / "m.mtl", "newmtl a\n" + mtl + "\n");
    expect_refused("bake-probes", args, message, dir / "bad.shtb");
  }
  std::filesystem::remove(dir / "m.mtl");
  expect_refused("bake-probes", args, "its material library 'm.mtl' (mtllib) is not beside it", dir / "bad.shtb");
}

// What glTF's specification forbids is refused, not read some other way: a required
// extension shtool does not implement (the texture coordinates KHR_texture_transform
// moves), another major version, node arrays of the wrong length (once ignored), a
// rotation that is not a unit quaternion (zero was taken as the identity), an albedo past
// the schema's 1 (it gains energy at every bounce), a TRIANGLES list that is not whole
// triangles (its tail was dropped), and a scene moved past single precision's reach (once
// "degenerate").
TEST(CliBakeProbes, GltfThatBreaksItsSpecificationIsRefused) {
  const nlohmann::json doc = nlohmann::json::parse(read_file(furnace()));
  const std::vector<std::pair<std::function<void(nlohmann::json&)>, std::string>> edits = {
      {[](nlohmann::json& j) { j["extensionsRequired"] = {"KHR_texture_transform"}; },
       "requires the glTF extension KHR_texture_transform"},
      {[](nlohmann::json& j) { j["asset"]["version"] = "3.0"; }, "asset.version '3.0': glTF 2.x is read"},
      {[](nlohmann::json& j) {
         j["nodes"][0]["matrix"] = {1, 0, 0};
       },
       "node 0's matrix has 3 numbers (16 expected)"},
      {[](nlohmann::json& j) {
         j["nodes"][0]["translation"] = {1, 0};
       },
       "node 0's translation has 2 numbers"},
      {[](nlohmann::json& j) {
         j["nodes"][0]["rotation"] = {0, 0, 0, 0};
       },
       "node 0's rotation is not a unit quaternion"},
      {[](nlohmann::json& j) {
         j["nodes"][0]["rotation"] = {0, 0, 0, 2};
       },
       "(length 2)"},
      {[](nlohmann::json& j) {
         j["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] = {5, 5, 5, 1};
       },
       "material 0 baseColorFactor must be at most 1"},
      {[](nlohmann::json& j) { j["accessors"][0]["count"] = 2; },
       "a TRIANGLES primitive of 2 vertices, not a multiple of 3"},
      {[](nlohmann::json& j) {
         j["nodes"][0]["translation"] = {1e20, 0, 0};
       },
       "lies beyond +-1e15"},
  };
  for (const auto& [edit, message] : edits) {
    nlohmann::json j = doc;
    edit(j);
    const fs::path scene = scratch("spec.gltf");
    write_file(scene, j.dump());
    expect_refused("bake-probes", {scene.string(), "--grid", "1,1,1", "--samples", "8"}, message, scratch("spec.shtb"));
  }
  // Within the tolerance a printed quaternion keeps, the rotation is read.
  nlohmann::json j = doc;
  j["nodes"][0]["rotation"] = {0, 0, 0, 1.0000004};
  write_file(scratch("spec.gltf"), j.dump());
  must(run_shtool({"bake-probes", scratch("spec.gltf").string(), "--grid", "1,1,1", "--samples", "8", "--out",
                   scratch("spec.shtb").string()}));
}

TEST(CliBakeProbes, RefusesBadScenesGridsBoundsAndOptions) {
  const fs::path scene = furnace(), out = scratch("refused.shtb");
  const std::string s = scene.string();
  const std::vector<std::string> base = {s, "--samples", "8"};
  expect_all_refused(
      "bake-probes", base,
      {
          {{"--grid", "0,2,2"}, "--grid: each count must be in 1..1024"},
          {{"--grid", "2,-1,2"}, "--grid: each count must be in 1..1024"},
          {{"--grid", "2,x,2"}, "--grid: 'x' is not a whole number"},
          {{"--grid", "2,2.5,2"}, "--grid: '2.5' is not a whole number"},
          {{"--grid", "2,2"}, "--grid must be NX,NY,NZ"},
          {{"--grid", "2,2,2,"}, "--grid must be NX,NY,NZ"},
          {{"--grid", "1024,1024,1024"}, "more than 16777216"},
          {{"--grid", "2,2,2", "--bounds", "0,0,0,1,1,0"}, "--bounds: min z (0) must be below max z (0)"},
          {{"--grid", "2,2,2", "--bounds", "2,0,0,1,1,1"}, "--bounds: min x (2) must be below max x (1)"},
          {{"--grid", "2,2,2", "--bounds", "0,0,0,1,1"}, "--bounds must be X0,Y0,Z0,X1,Y1,Z1"},
          {{"--grid", "2,2,2", "--bounds", "0,0,0,1,1,nan"}, "is not a finite number"},
          {{"--grid", "2,2,2", "--bounds=-1e19,-1,0.5,1e19,1,1.5"}, "--bounds: -1e19 lies beyond +-1e15"},
          {{"--grid", "2,2,2", "--order", "0"}, "--order must be in 1..8"},
          {{"--grid", "2,2,2", "--order", "9"}, "--order must be in 1..8"},
          {{"--grid", "2,2,2", "--bounces", "-1"}, "--bounces must be in 0..64"},
          {{"--grid", "2,2,2", "--seed", "-3"}, "must not be negative"},
          {{"--grid", "2,2,2", "--seed", "18446744073709551616"}, "must be at most 18446744073709551615"},
          {{"--grid", "2,2,2", "--up", "z"}, "glTF is +Y up"},
      },
      out);
  expect_refused("bake-probes", {s, "--grid", "2,2,2", "--samples", "0"}, "--samples must be in 1..1048576", out);
  expect_refused("bake-probes", {scratch("missing.gltf").string(), "--grid", "2,2,2"}, "no such file", out);
  write_file(scratch("garbage.obj"), "v 0 0 0\nf 1 2 3\n");
  expect_refused("bake-probes", {scratch("garbage.obj").string(), "--grid", "2,2,2"}, "refers to vertex 2", out);
  // Embree traces in single precision and refuses ray origins past about 1.8e18.
  write_file(scratch("far.obj"), "v -1 0 -1\nv -1 0 1\nv 1e19 0 1\nf 1 2 3\n");
  expect_refused("bake-probes", {scratch("far.obj").string(), "--grid", "2,2,2"},
                 "vertex 3 (1e+19, -1, 0) lies beyond +-1e15", out);
  write_file(scratch("broken.gltf"), "{\"asset\": {\"version\": \"2.0\"}, \"scenes\": [");
  expect_refused("bake-probes", {scratch("broken.gltf").string(), "--grid", "2,2,2"}, "cannot read glTF", out);
  // A light of a type the bake does not know is left out, and said so.
  ProbeTestScene area;
  area.quad(Eigen::Vector3d(-1, 0, 1), Eigen::Vector3d(1, 0, 1), Eigen::Vector3d(1, 0, -1), Eigen::Vector3d(-1, 0, -1),
            area.material({}));
  area.light({{"type", "area"}, {"intensity", 5.0}}, Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, -1, 0));
  area.write(scratch("area.gltf"));
  const fs::path area_out = scratch("area.shtb");
  const CommandResult lit = run_shtool({"bake-probes", scratch("area.gltf").string(), "--grid", "2,2,2", "--samples", "4",
                                        "--bounds=-1,-1,-1,1,1,1", "--out", area_out.string()});
  EXPECT_EQ(lit.exit_code, 0) << lit.err;
  EXPECT_NE(lit.err.find("1 KHR_lights_punctual light(s) of a type other than directional, point or spot left out"),
            std::string::npos)
      << lit.err;
  // A flat scene needs --bounds.
  ProbeTestScene flat;
  flat.quad(Eigen::Vector3d(-1, 0, 1), Eigen::Vector3d(1, 0, 1), Eigen::Vector3d(1, 0, -1), Eigen::Vector3d(-1, 0, -1),
            flat.material({}));
  flat.write(scratch("flat.gltf"));
  expect_refused("bake-probes", {scratch("flat.gltf").string(), "--grid", "2,2,2"}, "flat along z: give --bounds", out);
  // --env must hold radiance.
  const fs::path irr = scratch("irr.json");
  write_file(irr, R"({"order": 1, "quantity": "irradiance", "channels": ["r", "g", "b"], "window": {"type": "none"},
                      "coefficients": [[1, 1, 1]]})");
  expect_refused("bake-probes", {s, "--samples", "8", "--grid", "2,2,2", "--env", irr.string()}, "--env needs radiance",
                 out);
  // --out must not replace the scene; --json beside a bad request is not written either.
  const fs::path json = scratch("refused.json");
  fs::remove(json);
  const CommandResult r = run_shtool({"bake-probes", s, "--grid", "0,1,1", "--json", json.string(), "--out", out.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_FALSE(fs::exists(json));
  const CommandResult same = run_shtool({"bake-probes", s, "--grid", "1,1,1", "--out", s});
  EXPECT_EQ(same.exit_code, 1) << same.err;
  EXPECT_TRUE(fs::exists(scene));
}

}  // namespace

// --encoding l1 and zh3: the table and --json hold exactly the encoding of the l2 bake of
// the same seed (the encodings run on the filled l2 coefficients, so bit for bit), the
// loader reconstructs irradiance with probe_encoding.h's functions on them (float and
// double), zh3's --threejs atlas is three's order-3 form of the ZH3 probe, and shards
// joined by merge give the one-process table of each encoding.
namespace {

// The probe-grid loader refuses t, with `needle` in its message.
void expect_grid_refused(const shtool::Table& t, const std::string& needle) {
  const auto r = shtool::ProbeGrid<double>::from_table(t);
  ASSERT_FALSE(r.ok()) << "accepted a table it should refuse (" << needle << ")";
  EXPECT_NE(r.error().message.find(needle), std::string::npos) << r.error().message;
}

// The encoding room (tests/support/probe_scenes.h).
fs::path encoding_room() {
  const fs::path path = scratch("enc_room.gltf");
  write_encoding_room_scene(path);
  return path;
}

std::vector<std::string> bake_args(const fs::path& scene, const std::string& encoding, const fs::path& out,
                                   std::vector<std::string> extra = {}) {
  std::vector<std::string> a = {"bake-probes", scene.string(), "--grid", "3,3,2", "--bounds", "-1.5,-1.5,0.3,1.5,1.5,2.7",
                                "--samples", "64", "--bounces", "2", "--seed", "5", "--encoding", encoding,
                                "--out", out.string()};
  a.insert(a.end(), extra.begin(), extra.end());
  return a;
}

// Shards 1/2 and 0/2 of the bake, each valid against the schema, joined by merge into
// `merged`: the bytes of the one-process table `whole`.
void expect_shards_join_to(const fs::path& scene, const std::string& encoding, const std::vector<std::string>& extra,
                           const std::string& stem, const fs::path& merged, const fs::path& whole) {
  std::vector<std::string> merge = {"merge"};
  for (const char* k : {"1", "0"}) {
    const fs::path part = scratch(stem + k + ".shtb");
    std::vector<std::string> args = extra;
    args.insert(args.end(), {"--shard", std::string(k) + "/2"});
    const CommandResult r = run_shtool(bake_args(scene, encoding, part, args));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expect_valid_against_schema("probe-grid.schema.json", {part});
    merge.push_back(part.string());
  }
  merge.insert(merge.end(), {"--out", merged.string()});
  const CommandResult r = run_shtool(merge);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_TRUE(read_file(merged) == read_file(whole)) << encoding << ": the joined shards differ from one process";
}

const std::vector<Eigen::Vector3d>& test_normals() {
  static const std::vector<Eigen::Vector3d> n = {Eigen::Vector3d(0, 0, 1), Eigen::Vector3d(0, 0, -1),
                                                 Eigen::Vector3d(0.6, -0.8, 0), Eigen::Vector3d(-0.48, 0.6, 0.64),
                                                 Eigen::Vector3d(1, 0, 0)};
  return n;
}

}  // namespace

TEST(CliBakeProbes, EncodingsAreTheEncodingOfTheL2Bake) {
  using shtool::ProbeEncoding;
  const fs::path scene = encoding_room();
  const fs::path l2 = scratch("enc_l2.shtb"), l1 = scratch("enc_l1.shtb"), zh3 = scratch("enc_zh3.shtb");
  const fs::path l1_json = scratch("enc_l1.json"), zh3_json = scratch("enc_zh3.json");
  ASSERT_EQ(run_shtool(bake_args(scene, "l2", l2)).exit_code, 0);
  CommandResult r = run_shtool(bake_args(scene, "l1", l1, {"--json", l1_json.string()}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  r = run_shtool(bake_args(scene, "zh3", zh3, {"--json", zh3_json.string()}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  expect_valid_against_schema("probe-grid.schema.json", {l2, l1, zh3});

  const shtool::ProbeGrid<double> g2 = shtool::ProbeGrid<double>::load(l2).value();
  const auto g1 = shtool::ProbeGrid<double>::load(l1);
  const auto g3 = shtool::ProbeGrid<double>::load(zh3);
  ASSERT_TRUE(g1.ok()) << g1.error().message;
  ASSERT_TRUE(g3.ok()) << g3.error().message;
  EXPECT_EQ(g2.encoding, ProbeEncoding::l2);
  EXPECT_EQ(g2.order, 3);
  EXPECT_EQ(g1.value().encoding, ProbeEncoding::l1);
  EXPECT_EQ(g1.value().order, 2);
  EXPECT_EQ(g3.value().encoding, ProbeEncoding::zh3);
  EXPECT_EQ(g3.value().order, 2);
  EXPECT_EQ(g3.value().zh3_axis, shtool::Zh3Axis::luminance);
  ASSERT_EQ(g2.probe_count(), 18u);
  EXPECT_EQ(g1.value().valid, g2.valid);
  EXPECT_EQ(g3.value().valid, g2.valid);
  std::size_t invalid = 0;
  for (std::size_t p = 0; p < 18; ++p) invalid += g2.is_valid(p) ? 0 : 1;
  EXPECT_GE(invalid, 1u) << "no probe inside the block: the fill before the encoding is not exercised";

  const shtool::ProbeGrid<float> f1 = shtool::ProbeGrid<float>::load(l1).value();
  const shtool::ProbeGrid<float> f3 = shtool::ProbeGrid<float>::load(zh3).value();
  const nlohmann::json d1 = read_json(l1_json), d3 = read_json(zh3_json);
  EXPECT_EQ(d1["encoding"], "l1");
  EXPECT_EQ(d1["order"], 2);
  EXPECT_EQ(d3["encoding"], "zh3");
  EXPECT_EQ(d3["zh3_axis"], "luminance");
  EXPECT_EQ(d3["zh3_fit"], "explicit");
  double largest_l1_band = 0, largest_zonal = 0;
  for (std::size_t p = 0; p < 18; ++p) {
    const auto c2 = g2.coefficients_of(p);
    const shtool::L1Probe<double> want1 = shtool::encode_l1(c2);
    const shtool::Zh3Probe<double> want3 =
        shtool::encode_zh3(c2, shtool::Zh3Axis::luminance, shtool::Zh3Fit::explicit_fit);
    const auto c1 = g1.value().coefficients_of(p), c3 = g3.value().coefficients_of(p);
    ASSERT_EQ(c1.size(), 12u);
    ASSERT_EQ(c3.size(), 15u);
    for (int k = 0; k < 12; ++k) {
      EXPECT_EQ(c1[k], c2[k]) << "probe " << p << " value " << k;
      EXPECT_EQ(c3[k], want3.l1.coefficients[k]) << "probe " << p << " value " << k;
      EXPECT_EQ(d1["probes"][p]["coefficients"][k / 3][k % 3].get<double>(), c2[k]);
      EXPECT_EQ(d3["probes"][p]["coefficients"][k / 3][k % 3].get<double>(), c2[k]);
      if (k >= 3) largest_l1_band = std::max(largest_l1_band, std::abs(c2[k]));
    }
    ASSERT_EQ(d1["probes"][p]["coefficients"].size(), 4u);
    EXPECT_FALSE(d1["probes"][p].contains("zonal"));
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(c3[12 + c], want3.zonal[c]) << "probe " << p << " channel " << c;
      EXPECT_EQ(d3["probes"][p]["zonal"][c].get<double>(), want3.zonal[c]);
      largest_zonal = std::max(largest_zonal, std::abs(want3.zonal[c]));
    }
    // The loader's irradiance is probe_encoding.h's on the stored probe, in each precision.
    shtool::L1Probe<float> want1f;
    shtool::Zh3Probe<float> want3f;
    for (int k = 0; k < 12; ++k) want1f.coefficients[k] = want3f.l1.coefficients[k] = static_cast<float>(c2[k]);
    for (int c = 0; c < 3; ++c) want3f.zonal[c] = static_cast<float>(want3.zonal[c]);
    for (const Eigen::Vector3d& n : test_normals()) {
      const Eigen::Vector3f nf = n.cast<float>();
      EXPECT_EQ(g1.value().irradiance(p, n), shtool::l1_nonlinear_irradiance(want1, n)) << "probe " << p;
      EXPECT_EQ(g3.value().irradiance(p, n), shtool::zh3_irradiance(want3, shtool::Zh3Axis::luminance, n))
          << "probe " << p;
      EXPECT_EQ(f1.irradiance(p, nf), shtool::l1_nonlinear_irradiance(want1f, nf)) << "probe " << p;
      EXPECT_EQ(f3.irradiance(p, nf), shtool::zh3_irradiance(want3f, shtool::Zh3Axis::luminance, nf)) << "probe " << p;
      // At a probe's centre the trilinear sample is the probe (to the rounding of the
      // centre's grid coordinate).
      for (const shtool::ProbeGrid<double>* g : {&g1.value(), &g3.value()})
        EXPECT_LT((g->irradiance_at(g->position(p), n) - g->irradiance(p, n)).norm(),
                  1e-12 * (1 + g->irradiance(p, n).norm()))
            << "probe " << p;
    }
  }
  EXPECT_GT(largest_l1_band, 0.1) << "a scene without directional light does not test the L1 band";
  EXPECT_GT(largest_zonal, 0.01) << "a scene without band 2 does not test the zonal coefficient";
  // Between two probes, zh3's sample is the mean of both probes' stored values (zonal
  // ones included) and irradiance_at reconstructs from it.
  const shtool::ProbeGrid<double>& z = g3.value();
  std::vector<double> mid(15);
  const Eigen::Vector3d x = (z.position(0) + z.position(1)) / 2;
  z.sample(x, mid);
  for (int k = 0; k < 15; ++k) EXPECT_NEAR(mid[k], (z.coefficients_of(0)[k] + z.coefficients_of(1)[k]) / 2, 1e-12);
  EXPECT_EQ(z.irradiance_at(x, Eigen::Vector3d(0, 0, 1)), z.irradiance_of(mid, Eigen::Vector3d(0, 0, 1)));

  // The generator record and meta name the encoding; inspect shows them and the zonal array.
  const shtool::Table t3 = shtool::read_table(zh3).value();
  EXPECT_EQ(nlohmann::json::parse(t3.generator)["parameters"]["encoding"], "zh3");
  EXPECT_EQ(nlohmann::json::parse(t3.meta)["encoding"], "zh3");
  const CommandResult inspect = run_shtool({"inspect", zh3.string()});
  ASSERT_EQ(inspect.exit_code, 0) << inspect.err;
  EXPECT_NE(inspect.out.find("\"encoding\": \"zh3\""), std::string::npos) << inspect.out;
  EXPECT_NE(inspect.out.find("zonal  f64  shape [2, 3, 3, 3]"), std::string::npos) << inspect.out;
}

TEST(CliBakeProbes, EncodedShardsMergeToTheOneProcessTable) {
  const fs::path scene = encoding_room();
  for (const char* encoding : {"l1", "zh3"}) {
    const std::string e = encoding;
    const fs::path whole = scratch("encw_" + e + ".shtb"), merged = scratch("encm_" + e + ".shtb");
    ASSERT_EQ(run_shtool(bake_args(scene, e, whole)).exit_code, 0);
    expect_shards_join_to(scene, e, {}, "encp_" + e, merged, whole);
  }
}

TEST(CliBakeProbes, Zh3ThreeJsAtlasIsTheOrder3FormOfTheZh3Probes) {
  const fs::path scene = encoding_room(), out = scratch("enc3.shtb"), json = scratch("enc3.json"),
                 dir = scratch("three_zh3");
  fs::remove_all(dir);
  fs::create_directories(dir);
  const CommandResult r = run_shtool(bake_args(scene, "zh3", out, {"--json", json.string(), "--threejs", dir.string()}));
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const nlohmann::json doc = read_json(json);
  shtool::interop::ThreeProbeGridInput g =
      three_grid({3, 3, 2}, Eigen::Vector3d(-1.5, -1.5, 0.3), Eigen::Vector3d(1.5, 1.5, 2.7));
  for (const nlohmann::json& p : doc["probes"]) {
    shtool::Zh3Probe<double> probe;
    for (int k = 0; k < 12; ++k) probe.l1.coefficients[k] = p["coefficients"][k / 3][k % 3].get<double>();
    for (int c = 0; c < 3; ++c) probe.zonal[c] = p["zonal"][c].get<double>();
    g.coefficients.insert(g.coefficients.end(), probe.l1.coefficients.begin(), probe.l1.coefficients.end());
    const std::array<double, 15> band2 = shtool::zh3_band2(probe, shtool::Zh3Axis::luminance);
    g.coefficients.insert(g.coefficients.end(), band2.begin(), band2.end());
    // three's linear irradiance of the order-3 form is the ZH3 irradiance: A_l applied to it.
    for (const Eigen::Vector3d& n : test_normals()) {
      std::vector<double> y(9);
      shtool::eval_sh<double>(3, n, y);
      const double a[3] = {kPi, 2 * kPi / 3, kPi / 4};
      const Eigen::Vector3d want = shtool::zh3_irradiance(probe, shtool::Zh3Axis::luminance, n);
      for (int c = 0; c < 3; ++c) {
        double e = 0;
        for (int k = 0; k < 9; ++k) e += a[k == 0 ? 0 : k < 4 ? 1 : 2] * g.coefficients[g.coefficients.size() - 27 + k * 3 + c] * y[k];
        EXPECT_NEAR(e, want[c], 1e-12 * (1 + std::abs(want[c])));
      }
    }
  }
  expect_three_files(dir, g, "the atlas is not the order-3 form of the zh3 probes");
}

TEST(CliBakeProbes, RefusesUnknownOrMeaninglessEncodings) {
  const fs::path scene = furnace(), out = scratch("enc_refused.shtb"), dir = scratch("three_l1");
  fs::create_directories(dir);
  const std::vector<std::string> base = {scene.string(), "--grid", "2,2,2", "--samples", "8"};
  expect_all_refused("bake-probes", base,
                     {
                         {{"--encoding", "l3"}, "--encoding: 'l3' is not one of l2, l1, zh3"},
                         {{"--encoding", "ZH3"}, "--encoding: 'ZH3' is not one of l2, l1, zh3"},
                         {{"--encoding", "l1", "--order", "1"}, "--encoding l1 needs --order 2 or more"},
                         {{"--encoding", "zh3", "--order", "2"}, "--encoding zh3 needs --order 3 or more"},
                         {{"--encoding", "l1", "--threejs", dir.string()}, "--threejs with --encoding l1"},
                     },
                     out);
  EXPECT_TRUE(fs::is_empty(dir));
  // The loader refuses an encoded table that does not hold what its encoding says.
  ASSERT_EQ(run_shtool({"bake-probes", scene.string(), "--grid", "2,1,1", "--samples", "8", "--encoding", "zh3",
                        "--out", out.string()})
                .exit_code,
            0);
  const shtool::Table t = shtool::read_table(out).value();
  ASSERT_TRUE(shtool::ProbeGrid<double>::from_table(t).ok());
  shtool::Table no_zonal = t;
  std::erase_if(no_zonal.arrays, [](const shtool::TableArray& a) { return a.name == "zonal"; });
  expect_grid_refused(no_zonal, "zonal");
  shtool::Table unknown = t;
  nlohmann::json meta = nlohmann::json::parse(t.meta);
  meta["encoding"] = "l9";
  unknown.meta = meta.dump();
  expect_grid_refused(unknown, "not one of l2, l1, zh3");
  shtool::Table l1_order3 = t;
  meta["encoding"] = "l1";
  l1_order3.meta = meta.dump();
  l1_order3.order = 3;
  expect_grid_refused(l1_order3, "stores order 2");
}

// --zh3-fit and --zh3-axis: each choice's table and --json hold exactly the library's
// encoding of the l2 bake of the same seed (hallucinated: the L1 band alone, no zonal
// array), the loader (double and float) gives zh3_irradiance of the zonal coefficient the
// choice stands for, also between probes, and --threejs writes the order-3 form of it.
TEST(CliBakeProbes, Zh3FitAndAxisChoicesAreTheEncodingOfTheL2Bake) {
  using shtool::Zh3Axis;
  using shtool::Zh3Fit;
  const fs::path scene = encoding_room(), l2 = scratch("choice_l2.shtb");
  ASSERT_EQ(run_shtool(bake_args(scene, "l2", l2)).exit_code, 0);
  const shtool::ProbeGrid<double> g2 = shtool::ProbeGrid<double>::load(l2).value();
  EXPECT_EQ(shtool::read_table(l2).value().kind_version, "1.1");
  struct Choice {
    const char* fit;
    const char* axis;
    Zh3Fit f;
    Zh3Axis a;
  };
  for (const Choice& ch : {Choice{"hallucinated", "luminance", Zh3Fit::hallucinated, Zh3Axis::luminance},
                           Choice{"hallucinated", "per-channel", Zh3Fit::hallucinated, Zh3Axis::per_channel},
                           Choice{"explicit", "per-channel", Zh3Fit::explicit_fit, Zh3Axis::per_channel}}) {
    const std::string name = std::string(ch.fit) + "_" + ch.axis;
    SCOPED_TRACE(name);
    const bool hallucinated = ch.f == Zh3Fit::hallucinated;
    const fs::path out = scratch("choice_" + name + ".shtb"), json = scratch("choice_" + name + ".json"),
                   dir = scratch("three_" + name);
    fs::remove_all(dir);
    fs::create_directories(dir);
    const CommandResult r = run_shtool(bake_args(
        scene, "zh3", out,
        {"--zh3-fit", ch.fit, "--zh3-axis", ch.axis, "--json", json.string(), "--threejs", dir.string()}));
    ASSERT_EQ(r.exit_code, 0) << r.err;
    expect_valid_against_schema("probe-grid.schema.json", {out});
    const shtool::Table t = shtool::read_table(out).value();
    EXPECT_EQ(t.kind_version, "1.1");
    EXPECT_EQ(t.order, 2);
    EXPECT_EQ(t.find("zonal") != nullptr, !hallucinated);
    const nlohmann::json meta = nlohmann::json::parse(t.meta), gen = nlohmann::json::parse(t.generator);
    EXPECT_EQ(meta["zh3_fit"], ch.fit);
    EXPECT_EQ(meta["zh3_axis"], ch.axis);
    EXPECT_EQ(gen["parameters"]["zh3_fit"], ch.fit);
    EXPECT_EQ(gen["parameters"]["zh3_axis"], ch.axis);
    const nlohmann::json doc = read_json(json);
    EXPECT_EQ(doc["encoding"], "zh3");
    EXPECT_EQ(doc["zh3_fit"], ch.fit);
    EXPECT_EQ(doc["zh3_axis"], ch.axis);

    const auto g = shtool::ProbeGrid<double>::load(out);
    const auto f = shtool::ProbeGrid<float>::load(out);
    ASSERT_TRUE(g.ok()) << g.error().message;
    ASSERT_TRUE(f.ok()) << f.error().message;
    EXPECT_EQ(g.value().zh3_fit, ch.f);
    EXPECT_EQ(g.value().zh3_axis, ch.a);
    EXPECT_EQ(f.value().zh3_fit, ch.f);
    ASSERT_EQ(g.value().values_per_probe(), hallucinated ? 12u : 15u);
    EXPECT_EQ(g.value().valid, g2.valid);
    shtool::interop::ThreeProbeGridInput three =
        three_grid({3, 3, 2}, Eigen::Vector3d(-1.5, -1.5, 0.3), Eigen::Vector3d(1.5, 1.5, 2.7));
    double largest_zonal = 0;
    for (std::size_t p = 0; p < g2.probe_count(); ++p) {
      const auto c2 = g2.coefficients_of(p);
      const shtool::Zh3Probe<double> want = shtool::encode_zh3(c2, ch.a, ch.f);
      // float: the stored values rounded, the hallucinated coefficient made in float.
      shtool::Zh3Probe<float> wantf;
      for (int k = 0; k < 12; ++k) wantf.l1.coefficients[k] = static_cast<float>(c2[k]);
      for (int k = 0; k < 3; ++k)
        wantf.zonal[k] = hallucinated ? shtool::zh3_hallucinated_zonal(wantf.l1, ch.a, k)
                                      : static_cast<float>(want.zonal[k]);
      const auto c = g.value().coefficients_of(p);
      for (int k = 0; k < 12; ++k) {
        EXPECT_EQ(c[k], c2[k]) << "probe " << p << " value " << k;
        EXPECT_EQ(doc["probes"][p]["coefficients"][k / 3][k % 3].get<double>(), c2[k]);
      }
      EXPECT_EQ(doc["probes"][p].contains("zonal"), !hallucinated);
      for (int k = 0; k < 3; ++k) {
        if (!hallucinated) EXPECT_EQ(c[12 + k], want.zonal[k]) << "probe " << p;
        if (!hallucinated) EXPECT_EQ(doc["probes"][p]["zonal"][k].get<double>(), want.zonal[k]);
        largest_zonal = std::max(largest_zonal, std::abs(want.zonal[k]));
      }
      for (const Eigen::Vector3d& n : test_normals()) {
        EXPECT_EQ(g.value().irradiance(p, n), shtool::zh3_irradiance(want, ch.a, n)) << "probe " << p;
        const Eigen::Vector3f nf = n.cast<float>();
        EXPECT_EQ(f.value().irradiance(p, nf), shtool::zh3_irradiance(wantf, ch.a, nf))
            << "probe " << p;
      }
      three.coefficients.insert(three.coefficients.end(), want.l1.coefficients.begin(), want.l1.coefficients.end());
      const std::array<double, 15> band2 = shtool::zh3_band2(want, ch.a);
      three.coefficients.insert(three.coefficients.end(), band2.begin(), band2.end());
    }
    EXPECT_GT(largest_zonal, 0.01) << "the zonal coefficients are not exercised";
    expect_three_files(dir, three, "the atlas is not the order-3 form of the probes' ZH3");
    // Between two probes the hallucinated variant derives its zonal coefficient from the
    // interpolated L1 band (what a shader does after filtering the L1 texture), which is
    // not the mean of the two probes' hallucinated coefficients.
    const shtool::ProbeGrid<double>& z = g.value();
    const Eigen::Vector3d x = (z.position(0) + z.position(1)) / 2, n(0.6, -0.8, 0);
    std::vector<double> mid(z.values_per_probe());
    z.sample(x, mid);
    shtool::Zh3Probe<double> m;
    std::copy_n(mid.begin(), 12, m.l1.coefficients.begin());
    for (int k = 0; k < 3; ++k)
      m.zonal[k] = hallucinated ? shtool::zh3_hallucinated_zonal(m.l1, ch.a, k) : mid[12 + k];
    EXPECT_EQ(z.irradiance_at(x, n), shtool::zh3_irradiance(m, ch.a, n));
  }
}

// 1.0 tables (before --zh3-fit) still load: l2 without meta.encoding, zh3 without
// meta.zh3_fit (explicit); a 1.1 zh3 table must name its fit; another major is refused by
// from_table and by load; a hallucinated table must not carry a zonal array.
TEST(CliBakeProbes, LoaderReadsKindVersion10And11AndRefusesANewerMajor) {
  const fs::path scene = encoding_room(), zh3 = scratch("kv_zh3.shtb"), hal = scratch("kv_hal.shtb");
  ASSERT_EQ(run_shtool(bake_args(scene, "zh3", zh3)).exit_code, 0);
  ASSERT_EQ(run_shtool(bake_args(scene, "zh3", hal, {"--zh3-fit", "hallucinated"})).exit_code, 0);
  const shtool::Table t = shtool::read_table(zh3).value(), h = shtool::read_table(hal).value();
  const shtool::ProbeGrid<double> now = shtool::ProbeGrid<double>::from_table(t).value();
  const nlohmann::json meta = nlohmann::json::parse(t.meta);

  shtool::Table old = t;
  old.kind_version = "1.0";
  nlohmann::json m = meta;
  m.erase("zh3_fit");
  old.meta = m.dump();
  auto g = shtool::ProbeGrid<double>::from_table(old);
  ASSERT_TRUE(g.ok()) << g.error().message;
  EXPECT_EQ(g.value().zh3_fit, shtool::Zh3Fit::explicit_fit);
  EXPECT_EQ(g.value().coefficients, now.coefficients);
  shtool::Table old_l2 = old;
  m.erase("encoding");
  m.erase("zh3_axis");
  old_l2.meta = m.dump();
  old_l2.arrays.pop_back();  // zonal
  g = shtool::ProbeGrid<double>::from_table(old_l2);
  ASSERT_TRUE(g.ok()) << g.error().message;
  EXPECT_EQ(g.value().encoding, shtool::ProbeEncoding::l2);

  shtool::Table unnamed = old;
  unnamed.kind_version = "1.1";
  expect_grid_refused(unnamed, "meta.zh3_fit is missing");
  // A later minor only adds: read by the same rules.
  shtool::Table later = t;
  later.kind_version = "1.7";
  EXPECT_TRUE(shtool::ProbeGrid<float>::from_table(later).ok());

  shtool::Table newer = t;
  newer.kind_version = "2.0";
  expect_grid_refused(newer, "kind_version 2.0 is not readable: this reader knows 1.x (up to 1.1); a newer "
                             "shtool wrote it");
  const fs::path newer_file = scratch("kv_2.shtb");
  shtool::write_table(newer, newer_file);
  const auto loaded = shtool::ProbeGrid<float>::load(newer_file);
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().message.find("version 2.0"), std::string::npos) << loaded.error().message;
  EXPECT_NE(loaded.error().message.find(newer_file.string()), std::string::npos) << loaded.error().message;

  shtool::Table hal_zonal = h;
  hal_zonal.arrays.push_back(t.arrays.back());
  ASSERT_EQ(hal_zonal.arrays.back().name, "zonal");
  expect_grid_refused(hal_zonal, "array 'zonal' in a grid whose encoding stores none");
  // The schema refuses both too (and accepts the 1.0 zh3 table without zh3_fit).
  const std::string source = SHTOOL_SOURCE_DIR;
  for (const auto& [table, valid] : {std::pair<const shtool::Table*, bool>{&hal_zonal, false},
                                     std::pair<const shtool::Table*, bool>{&unnamed, false},
                                     std::pair<const shtool::Table*, bool>{&old, true}}) {
    const fs::path file = scratch("kv_schema.json");
    shtool::write_table(*table, file, shtool::TableEncoding::json);
    const CommandResult v = run_command({SHTOOL_PYTHON, source + "/tests/validate_json_schema.py",
                                         source + "/schemas/probe-grid.schema.json", file.string()});
    EXPECT_EQ(v.exit_code, valid ? 0 : 1) << table->meta << "\n" << v.out << v.err;
  }
  shtool::Table unknown_fit = h;
  nlohmann::json hm = nlohmann::json::parse(h.meta);
  hm["zh3_fit"] = "solved";
  unknown_fit.meta = hm.dump();
  expect_grid_refused(unknown_fit, "not 'explicit' or 'hallucinated'");
}

TEST(CliBakeProbes, RefusesZh3ChoicesOutsideZh3AndUnknownOnes) {
  const fs::path scene = furnace(), out = scratch("choice_refused.shtb");
  const std::vector<std::string> base = {scene.string(), "--grid", "2,2,2", "--samples", "8"};
  expect_all_refused(
      "bake-probes", base,
      {
          {{"--zh3-fit", "hallucinated"}, "--zh3-fit applies to --encoding zh3 only (the grid's encoding is l2"},
          {{"--encoding", "l1", "--zh3-axis", "per-channel"},
           "--zh3-axis applies to --encoding zh3 only (the grid's encoding is l1"},
          {{"--encoding", "l2", "--zh3-fit", "explicit"}, "--zh3-fit applies to --encoding zh3 only"},
          {{"--encoding", "zh3", "--zh3-fit", "solved"}, "--zh3-fit: 'solved' is not one of explicit, hallucinated"},
          {{"--encoding", "zh3", "--zh3-axis", "red"}, "--zh3-axis: 'red' is not one of luminance, per-channel"},
          {{"--encoding", "zh3", "--zh3-fit", "explicit", "--order", "2"},
           "--encoding zh3 needs --order 3 or more (its zonal coefficient is fitted to band 2)"},
      },
      out);
  // The hallucinated variant needs the L1 band only.
  const CommandResult r = run_shtool({"bake-probes", scene.string(), "--grid", "2,1,1", "--samples", "8", "--order",
                                      "2", "--encoding", "zh3", "--zh3-fit", "hallucinated", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("encoding zh3 hallucinated, luminance axis"), std::string::npos) << r.err;
  EXPECT_EQ(shtool::ProbeGrid<double>::load(out).value().zh3_fit, shtool::Zh3Fit::hallucinated);
}

TEST(CliBakeProbes, Zh3ChoicesShardsMergeToTheOneProcessTable) {
  const fs::path scene = encoding_room(), whole = scratch("choicew.shtb"), merged = scratch("choicem.shtb");
  const std::vector<std::string> choice = {"--zh3-fit", "hallucinated", "--zh3-axis", "per-channel"};
  ASSERT_EQ(run_shtool(bake_args(scene, "zh3", whole, choice)).exit_code, 0);
  expect_shards_join_to(scene, "zh3", choice, "choicep", merged, whole);
  EXPECT_EQ(shtool::ProbeGrid<double>::load(merged).value().zh3_axis, shtool::Zh3Axis::per_channel);
}
