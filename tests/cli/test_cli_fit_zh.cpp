// End-to-end tests of `shtool fit-zh`: the bundled spot.obj with few rays, fits of given
// vectors, output formats, and bad input (exit 1, a message, no output written).
// The fits are checked against the transfer vectors the same run saved, by rebuilding
// the SH vector of the lobes with the runtime (an independent path from the fitter's
// own residual), and the table header against schemas/zh-fit.schema.json.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <numbers>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <embree3/rtcore_config.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "cli_test.h"
#include "shtool/sh.h"
#include "shtool/table.h"
#include "shtool/zh.h"
#include "shtool/zh_fit_table.h"
#include "common/table_writer.h"

namespace {

using namespace shtool::test;

const Scratch scratch("test_cli_fit_zh");

// The generator record of a table written by fit-zh.
nlohmann::json generator_of(const fs::path& table) {
  const shtool::Result<shtool::Table> t = shtool::read_table(table, {"zh-fit", 1});
  EXPECT_TRUE(t.ok()) << (t.ok() ? "" : t.error().message);
  return t.ok() ? nlohmann::json::parse(t.value().generator) : nlohmann::json();
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
  const CommandResult r = run_shtool({"fit-zh", kSpotObj, "--rays", "16", "--order", "3", "--lobes", "2",
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

  expect_valid_against_schema("zh-fit.schema.json", {table});

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
    const CommandResult r = run_shtool({"fit-zh", "--transfer", in.string(), "--lobes", "1", "--out",
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
  // The simulation's options do nothing to given vectors, and are said to.
  const fs::path out3 = scratch("k3.json");
  const CommandResult r = run_shtool({"fit-zh", "--transfer", in.string(), "--lobes", "1", "--rays", "999", "--mode",
                                      "interreflected", "--out", scratch("k3.shtb").string(), "--json", out3.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.err.find("fit-zh: warning: --rays, --mode: nothing to do with --transfer"), std::string::npos) << r.err;
  EXPECT_EQ(read_file(out3), read_file(out1));
  const CommandResult quiet =
      run_shtool({"fit-zh", "--transfer", in.string(), "--lobes", "1", "--out", scratch("k4.shtb").string()});
  EXPECT_EQ(quiet.err.find("warning"), std::string::npos) << quiet.err;
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
    const CommandResult r = run_shtool({"fit-zh", obj.string(), "--rays", "4", "--out", out.string()});
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
  const CommandResult missing = run_shtool({"fit-zh", scratch("missing.obj").string()});
  EXPECT_EQ(missing.exit_code, 1);
  EXPECT_NE(missing.err.find("no such file"), std::string::npos) << missing.err;
  const CommandResult neither = run_shtool({"fit-zh"});
  EXPECT_EQ(neither.exit_code, 1);
  const fs::path bad = scratch("bad_transfer.json");
  std::ofstream(bad) << R"({"order": 2, "vectors": [[1, 2, 3]]})";
  const CommandResult short_vec = run_shtool({"fit-zh", "--transfer", bad.string(), "--out", scratch("b.shtb").string()});
  EXPECT_EQ(short_vec.exit_code, 1);
  EXPECT_NE(short_vec.err.find("must have 4 numbers"), std::string::npos) << short_vec.err;
  EXPECT_FALSE(fs::exists(scratch("b.shtb")));
  const CommandResult mode = run_shtool({"fit-zh", kSpotObj, "--mode", "glossy"});
  EXPECT_EQ(mode.exit_code, 1);
  EXPECT_NE(mode.err.find("--mode"), std::string::npos) << mode.err;
  // Refused before the bake (which would take a while), naming the option.
  for (const char* above : {"inf", "1e400", "-1", "nan"}) {
    const CommandResult r =
        run_shtool({"fit-zh", kSpotObj, "--restart-above", above, "--out", scratch("ra.shtb").string()});
    EXPECT_EQ(r.exit_code, 1) << above;
    EXPECT_NE(r.err.find("--restart-above must be a finite number >= 0"), std::string::npos) << above << ": " << r.err;
    EXPECT_FALSE(fs::exists(scratch("ra.shtb"))) << above;
  }
}

TEST(CliFitZh, HeaderRecordsRayTracerAndLoadedMesh) {
  const std::string spot = read_file(kSpotObj);
  const fs::path same = scratch("spot_comment.obj"), moved = scratch("spot_moved.obj");
  // Same geometry, other bytes: a comment line. Other geometry: the first vertex moved.
  std::ofstream(same) << spot << "# a comment changes the file, not the mesh\n";
  std::string edited = spot;
  const std::size_t v = edited.find("\nv ") + 1, end = edited.find('\n', v);
  ASSERT_NE(end, std::string::npos);
  std::istringstream line(edited.substr(v + 2, end - v - 2));
  double x, y, z;
  ASSERT_TRUE(line >> x >> y >> z);
  edited.replace(v, end - v, "v " + std::to_string(x + 1e-3) + " " + std::to_string(y) + " " + std::to_string(z));
  std::ofstream(moved) << edited;
  std::vector<nlohmann::json> gens;
  for (const std::string& mesh : {kSpotObj, same.string(), moved.string()}) {
    const fs::path out = scratch("header.shtb");
    const CommandResult r =
        run_shtool({"fit-zh", mesh, "--rays", "4", "--order", "2", "--lobes", "1", "--starts", "0", "--out", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    gens.push_back(generator_of(out));
  }
  const nlohmann::json& g = gens[0];
  EXPECT_EQ(g["tool"], "shtool");
  EXPECT_EQ(g["embree"]["isa"], "sse4.2");
  EXPECT_EQ(g["embree"]["version"], std::to_string(RTC_VERSION_MAJOR) + "." + std::to_string(RTC_VERSION_MINOR) + "." +
                                        std::to_string(RTC_VERSION_PATCH));
  EXPECT_EQ(g["parameters"]["mode"], "shadowed");
  EXPECT_EQ(g["parameters"]["rays"], 4);
  EXPECT_NE(g["parameters"]["input_crc32"], gens[1]["parameters"]["input_crc32"]);
  EXPECT_EQ(g["parameters"]["mesh_crc32"], gens[1]["parameters"]["mesh_crc32"]);
  EXPECT_NE(g["parameters"]["mesh_crc32"], gens[2]["parameters"]["mesh_crc32"]);

  // No rays traced, no ray tracer recorded.
  const fs::path out = scratch("header_unshadowed.shtb");
  const CommandResult r = run_shtool({"fit-zh", kSpotObj, "--mode", "unshadowed", "--rays", "4", "--order",
                               "2", "--lobes", "1", "--starts", "0", "--out", out.string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_FALSE(generator_of(out).contains("embree"));
  EXPECT_TRUE(generator_of(out)["parameters"].contains("mesh_crc32"));
}

// Small settings that still run every random path: rays rotated per vertex and a
// multi-start on every vertex (--restart-above 0).
const std::vector<std::string> kQuick = {"--rays", "8", "--order", "2", "--lobes", "2", "--starts", "1",
                                         "--restart-above", "0"};

CommandResult fit(const std::string& mesh, std::vector<std::string> extra) {
  std::vector<std::string> args = {"fit-zh", mesh};
  args.insert(args.end(), kQuick.begin(), kQuick.end());
  args.insert(args.end(), extra.begin(), extra.end());
  return run_shtool(args);
}

TEST(CliFitZh, ThreadCountDoesNotChangeABit) {
  std::vector<std::string> tables;
  for (const char* threads : {"1", "2", "3"}) {
    const fs::path out = scratch(std::string("threads") + threads + ".shtb");
    const CommandResult r = fit(kSpotObj, {"--threads", threads, "--out", out.string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    tables.push_back(read_file(out));
  }
  ASSERT_GT(tables[0].size(), 2930u * 2 * 2 * 8);
  EXPECT_EQ(tables[0], tables[1]);
  EXPECT_EQ(tables[0], tables[2]);
}

// The parts of an N-way bake, shard K written with K + 1 threads (so threads and shards
// vary together), in the encoding given.
std::vector<fs::path> bake_parts(const std::string& name, int n, const std::vector<std::string>& extra = {},
                                 const std::string& format = "binary") {
  std::vector<fs::path> parts;
  for (int k = 0; k < n; ++k) {
    const fs::path out = scratch(name + "." + std::to_string(k) + "-of-" + std::to_string(n) + ".part");
    std::vector<std::string> args = {"--shard", std::to_string(k) + "/" + std::to_string(n), "--threads",
                                     std::to_string(k % 3 + 1), "--format", format, "--out", out.string()};
    args.insert(args.end(), extra.begin(), extra.end());
    const CommandResult r = fit(kSpotObj, args);
    EXPECT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find("shard " + std::to_string(k) + "/" + std::to_string(n)), std::string::npos) << r.err;
    parts.push_back(out);
  }
  return parts;
}

CommandResult merge(const std::vector<fs::path>& parts, const fs::path& out) {
  std::vector<std::string> args = {"merge"};
  for (const fs::path& p : parts) args.push_back(p.string());
  args.insert(args.end(), {"--out", out.string()});
  return run_shtool(args);
}

TEST(CliFitZh, ShardsMergedInAnyOrderAreTheOneProcessTable) {
  const fs::path whole = scratch("whole.shtb");
  ASSERT_EQ(fit(kSpotObj, {"--out", whole.string()}).exit_code, 0);
  const std::string expected = read_file(whole);
  fs::path part;  // shard 1 of 3
  for (int n : {1, 2, 3}) {
    // JSON parts for N = 2: the encoding of a part does not change the merged bytes.
    std::vector<fs::path> parts = bake_parts("spot", n, {}, n == 2 ? "json" : "binary");
    if (n == 3) part = parts[1];
    std::reverse(parts.begin(), parts.end());
    if (n == 3) std::swap(parts[0], parts[1]);  // 1, 2, 0
    const fs::path out = scratch("merged" + std::to_string(n) + ".shtb");
    const CommandResult r = merge(parts, out);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    EXPECT_NE(r.err.find(std::to_string(n) + " parts, 2930 vertices"), std::string::npos) << r.err;
    EXPECT_EQ(read_file(out), expected) << n << " shards";
  }

  // A part says what it is, and the runtime refuses to shade it as a whole mesh.
  const shtool::Result<shtool::Table> t = shtool::read_table(part, {"zh-fit", 1});
  ASSERT_TRUE(t.ok());
  const nlohmann::json shard = nlohmann::json::parse(t.value().meta)["shard"];
  EXPECT_EQ(shard, (nlohmann::json{{"index", 1}, {"count", 3}, {"first_vertex", 976}, {"end_vertex", 1953},
                                   {"vertices", 2930}}));
  EXPECT_EQ(t.value().kind_version, "1.1");
  EXPECT_EQ(generator_of(part), generator_of(whole));
  const auto loaded = shtool::ZhFitTable<double>::load(part);
  ASSERT_FALSE(loaded.ok());
  EXPECT_NE(loaded.error().message.find("partial table"), std::string::npos) << loaded.error().message;
  ASSERT_TRUE(shtool::ZhFitTable<double>::load(whole).ok());
  expect_valid_against_schema("zh-fit.schema.json", {part, whole});
}

TEST(CliFitZh, ShardsOfTransferVectorsMerge) {
  // 5 vectors in 2 shards: rows [0, 2) and [2, 5).
  std::vector<std::vector<double>> vectors;
  for (int v = 0; v < 5; ++v) {
    std::vector<double> t(9);
    for (int i = 0; i < 9; ++i) t[i] = std::sin(1.0 + v * 9 + i);
    vectors.push_back(t);
  }
  const fs::path in = scratch("vectors.json"), whole = scratch("vectors.shtb"), merged = scratch("vectors_m.shtb");
  std::ofstream(in) << nlohmann::json{{"order", 3}, {"vectors", vectors}}.dump();
  const std::vector<std::string> opts = {"--lobes", "2", "--starts", "2", "--restart-above", "0"};
  std::vector<std::string> args = {"fit-zh", "--transfer", in.string(), "--out", whole.string()};
  args.insert(args.end(), opts.begin(), opts.end());
  ASSERT_EQ(run_shtool(args).exit_code, 0);
  std::vector<fs::path> parts;
  for (const char* k : {"1", "0"}) {
    parts.push_back(scratch(std::string("vectors.part") + k));
    args = {"fit-zh", "--transfer", in.string(), "--shard", std::string(k) + "/2", "--out", parts.back().string()};
    args.insert(args.end(), opts.begin(), opts.end());
    ASSERT_EQ(run_shtool(args).exit_code, 0);
  }
  ASSERT_EQ(merge(parts, merged).exit_code, 0);
  EXPECT_EQ(read_file(merged), read_file(whole));
}

TEST(CliFitZh, MergeRefusesPartsThatDoNotMakeOneBake) {
  const std::vector<fs::path> parts = bake_parts("refuse", 3);
  const fs::path other_seed = bake_parts("refuse_seed", 3, {"--seed", "2"})[2];
  const fs::path other_option = bake_parts("refuse_direct", 3, {"--direct"})[2];
  const fs::path other_count = bake_parts("refuse_count", 2)[1];
  // The same file under another name: the mesh CRC is the same, the file name differs.
  const std::string spot = read_file(kSpotObj);
  const fs::path moved = scratch("moved.obj");
  std::string edited = spot;
  edited.replace(edited.find("0.348799"), 8, "0.348800");  // spot's first vertex
  std::ofstream(moved) << edited;
  const fs::path other_mesh = scratch("refuse_mesh.part");
  ASSERT_EQ(fit(moved.string(), {"--shard", "2/3", "--out", other_mesh.string()}).exit_code, 0);
  const fs::path copy = scratch("refuse_copy.part"), corrupt = scratch("refuse_corrupt.part");
  fs::copy_file(parts[1], copy, fs::copy_options::overwrite_existing);
  std::string bytes = read_file(parts[2]);
  bytes[bytes.size() - 5] ^= 0x10;  // inside the last array
  std::ofstream(corrupt, std::ios::binary) << bytes;
  const fs::path whole = scratch("refuse_whole.shtb");
  ASSERT_EQ(fit(kSpotObj, {"--out", whole.string()}).exit_code, 0);
  // A JSON part's header is plain text: its shard record edited to disagree with its rows.
  const fs::path edited_range = scratch("refuse_range.part");
  ASSERT_EQ(fit(kSpotObj, {"--shard", "1/3", "--format", "json", "--out", edited_range.string()}).exit_code, 0);
  std::string json_part = read_file(edited_range);
  const std::size_t at = json_part.find("\"first_vertex\":976");
  ASSERT_NE(at, std::string::npos);
  json_part.replace(at, 18, "\"first_vertex\":975");
  std::ofstream(edited_range, std::ios::binary | std::ios::trunc) << json_part;
  // A part edited with a valid checksum: a residual that is not finite, named with its part.
  const fs::path holds_nan = scratch("refuse_nan.part");
  {
    shtool::Table t = shtool::read_table(parts[2]).value();
    for (shtool::TableArray& a : t.arrays)
      if (a.name == "residual") {
        const double nan = std::nan("");
        std::memcpy(a.data.data() + 8 * 3, &nan, 8);
      }
    std::ofstream(holds_nan, std::ios::binary)
        << shtool::encode_table(t, shtool::TableEncoding::binary, shtool::NonFinite::keep);
  }

  // A residual below zero, checksums valid: finite, but no table may hold it.
  const fs::path negative = scratch("refuse_negative.part");
  {
    shtool::Table t = shtool::read_table(parts[2]).value();
    for (shtool::TableArray& a : t.arrays)
      if (a.name == "residual") {
        const double minus = -1;
        std::memcpy(a.data.data() + 8 * 3, &minus, 8);
      }
    std::ofstream(negative, std::ios::binary) << shtool::encode_table(t);
  }
  struct Case {
    std::string name;
    std::vector<fs::path> parts;
    std::string message;
  };
  const std::vector<Case> cases = {
      {"missing", {parts[2], parts[0]}, "1 of 3 shards missing (1)"},
      {"duplicate", {parts[0], parts[1], copy, parts[2]}, "shard 1 of 3 is given twice"},
      {"same file twice", {parts[0], parts[1], parts[1], parts[2]}, "is given twice"},
      {"seed", {parts[0], parts[1], other_seed}, "generator.parameters.seed (1 vs 2)"},
      {"options", {parts[0], parts[1], other_option}, "generator.parameters.direct (false vs true)"},
      {"mesh", {parts[0], parts[1], other_mesh}, "generator.parameters.input_crc32"},
      {"shard count", {parts[0], parts[1], other_count}, "shard 0 of 3 (2930 vertices) vs shard 1 of 2"},
      {"corrupted", {parts[0], parts[1], corrupt}, "CRC"},
      {"whole table", {parts[0], whole}, "not a partial table"},
      {"edited range", {parts[0], edited_range, parts[2]}, "shard 1 of 3 covers vertices [976, 1953)"},
      {"not a table", {parts[0], kSpotObj}, "spot.obj"},
      {"not finite", {parts[0], parts[1], holds_nan}, "refuse_nan.part': array 'residual' value 3 is not finite"},
      {"names in the order of the values",
       {parts[0], parts[1], other_seed},
       "'" + parts[0].string() + "' and '" + other_seed.string() +
           "' are not parts of the same bake: generator.parameters.seed (1 vs 2)"},
      {"a value the loader refuses",
       {parts[0], parts[1], negative},
       "merge: the joined table would not load: zh-fit table:"},
  };
  for (const Case& c : cases) {
    const fs::path out = scratch("refused.shtb");
    const CommandResult r = merge(c.parts, out);
    EXPECT_EQ(r.exit_code, 1) << c.name << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << c.name << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << c.name;
  }
  // Mesh CRCs are compared too: the mesh_crc32 of the moved vertex differs from spot's.
  EXPECT_NE(generator_of(other_mesh)["parameters"]["mesh_crc32"], generator_of(parts[0])["parameters"]["mesh_crc32"]);
  // --out is required, and may not overwrite a part.
  EXPECT_EQ(run_shtool({"merge", parts[0].string()}).exit_code, 1);
  const CommandResult onto = merge({parts[0], parts[1], parts[2]}, parts[0]);
  EXPECT_EQ(onto.exit_code, 1);
  EXPECT_NE(onto.err.find("--out"), std::string::npos) << onto.err;
}

TEST(CliFitZh, BadShardOptionsAreRefusedBeforeAnyWork) {
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const fs::path j = scratch("shard.json");
  const std::vector<Case> cases = {
      {{"--shard", "3/3"}, "K must be below N"},
      {{"--shard", "1/0"}, "N must be in 1.."},
      {{"--shard", "a/b"}, "expected K/N"},
      {{"--shard", "-1/2"}, "expected K/N"},
      {{"--shard", "+1/2"}, "expected K/N"},
      {{"--shard", "1/2/3"}, "expected K/N"},
      {{"--shard", "1 /2"}, "expected K/N"},
      {{"--shard", "2"}, "expected K/N"},
      {{"--shard", "/2"}, "expected K/N"},
      {{"--shard", "0/2930"}, ""},  // as many shards as vertices: accepted
      {{"--shard", "0/2931"}, "N must be at most 2930"},
      {{"--shard", "0/2", "--mode", "interreflected"}, "cannot split an interreflected bake"},
      {{"--shard", "0/2", "--json", j.string()}, "--json is not written with --shard"},
      {{"--shard", "0/2", "--ply", j.string()}, "--ply is not written with --shard"},
      {{"--shard", "0/2", "--save-transfer", j.string()}, "--save-transfer is not written with --shard"},
  };
  for (const Case& c : cases) {
    const fs::path out = scratch("badshard.shtb");
    std::vector<std::string> args = c.args;
    args.insert(args.end(), {"--out", out.string()});
    const CommandResult r = fit(kSpotObj, args);
    const std::string what = c.args[1];
    if (c.message.empty()) {
      EXPECT_EQ(r.exit_code, 0) << what << ": " << r.err;
      fs::remove(out);
      continue;
    }
    EXPECT_EQ(r.exit_code, 1) << what << ": " << r.err;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << what << ": " << r.err;
    EXPECT_FALSE(fs::exists(out)) << what;
    EXPECT_FALSE(fs::exists(j)) << what;
  }
}

}  // namespace
