// `shtool fit-zh --gltf`: the .glb is read back with tinygltf and every attribute compared
// with what the same run wrote elsewhere (the --json fits, the --save-transfer DC, the
// mesh as shtool loads it); the Khronos glTF validator checks the file and three.js's
// GLTFLoader reads it, both in node; refusals name the problem and write nothing.
#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>
#include <numbers>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "fit/mesh.h"
#include "node_consumers.h"
#include "cli_test.h"

namespace {

using namespace shtool::test;

const Scratch scratch("test_cli_fit_zh_gltf");

// One bake of spot.obj with its .glb, --json fits and --save-transfer vectors.
struct Bake {
  std::string name;
  int order, lobes;
  bool direct;
  std::vector<std::string> extra;
  fs::path glb() const { return scratch(name + ".glb"); }
  fs::path json() const { return scratch(name + ".json"); }
  fs::path transfer() const { return scratch(name + "_t.json"); }
};

const std::vector<Bake>& bakes() {
  // Order 6 and 5 leave zero padding in the last VEC4 of coefficients; direct with 3
  // lobes stores DC and the linear band, with 1 lobe the DC only.
  static const std::vector<Bake> list = {
      {"plain", 6, 4, false, {}},
      {"direct", 5, 3, true, {"--direct"}},
      {"direct_dc", 2, 1, true, {"--direct", "--starts", "0"}},
  };
  static bool baked = false;
  if (!baked) {
    for (const Bake& b : list) {
      std::vector<std::string> args = {"fit-zh",          kSpotObj,
                                       "--rays",          "64",
                                       "--order",         std::to_string(b.order),
                                       "--lobes",         std::to_string(b.lobes),
                                       "--gltf",          b.glb().string(),
                                       "--json",          b.json().string(),
                                       "--save-transfer", b.transfer().string(),
                                       "--out",           scratch(b.name + ".shtb").string()};
      args.insert(args.end(), b.extra.begin(), b.extra.end());
      const CommandResult r = run_shtool(args);
      EXPECT_EQ(r.exit_code, 0) << r.err;
    }
    baked = true;
  }
  return list;
}

// The floats of accessor `index`, checked to be `type` floats, `count` of them, tightly
// packed in their own buffer view.
std::vector<float> floats(const tinygltf::Model& m, int index, int type, std::size_t count) {
  const tinygltf::Accessor& a = m.accessors.at(index);
  EXPECT_EQ(a.componentType, TINYGLTF_COMPONENT_TYPE_FLOAT);
  EXPECT_EQ(a.type, type);
  EXPECT_EQ(a.count, count);
  EXPECT_FALSE(a.normalized);
  const tinygltf::BufferView& v = m.bufferViews.at(a.bufferView);
  EXPECT_EQ(v.target, TINYGLTF_TARGET_ARRAY_BUFFER);
  const std::size_t n = a.count * tinygltf::GetNumComponentsInType(a.type);
  EXPECT_EQ(v.byteStride, 0u);
  EXPECT_GE(v.byteLength, a.byteOffset + n * sizeof(float));
  std::vector<float> out(n);
  std::memcpy(out.data(), m.buffers.at(v.buffer).data.data() + v.byteOffset + a.byteOffset, n * sizeof(float));
  return out;
}

tinygltf::Model load(const fs::path& glb) {
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, glb.string())) << err;
  EXPECT_EQ(warn, "");
  return m;
}

TEST(CliFitZhGltf, AttributesAreTheFitsOfTheSameRun) {
  const shtool::fit::Mesh mesh = shtool::fit::load_mesh(kSpotObj);
  const std::size_t n = mesh.positions.size();
  for (const Bake& b : bakes()) {
    SCOPED_TRACE(b.name);
    const tinygltf::Model m = load(b.glb());
    ASSERT_EQ(m.scenes.size(), 1u);
    ASSERT_EQ(m.nodes.size(), 1u);
    ASSERT_EQ(m.meshes.size(), 1u);
    ASSERT_EQ(m.meshes[0].primitives.size(), 1u);
    EXPECT_EQ(m.scenes[0].nodes, std::vector<int>{0});
    EXPECT_EQ(m.nodes[0].mesh, 0);
    EXPECT_TRUE(m.nodes[0].matrix.empty() && m.nodes[0].translation.empty() && m.nodes[0].rotation.empty());
    const tinygltf::Value& extras = m.meshes[0].extras.Get("shtool_zh_fit");
    EXPECT_EQ(extras.Get("order").GetNumberAsInt(), b.order);
    EXPECT_EQ(extras.Get("lobes").GetNumberAsInt(), b.lobes);
    EXPECT_EQ(extras.Get("direct").Get<bool>(), b.direct);
    const tinygltf::Primitive& p = m.meshes[0].primitives[0];
    EXPECT_EQ(p.mode, TINYGLTF_MODE_TRIANGLES);

    // Exactly the documented attributes.
    const int groups = (b.order + 3) / 4;
    std::set<std::string> expected = {"POSITION", "NORMAL", "COLOR_0"};
    for (int k = 0; k < b.lobes; ++k) {
      expected.insert("_ZH_AXIS_" + std::to_string(k));
      for (int j = 0; j < groups; ++j) expected.insert("_ZH_COEFFS_" + std::to_string(k) + "_" + std::to_string(j));
    }
    if (b.direct) expected.insert("_ZH_DIRECT");
    std::set<std::string> got;
    for (const auto& [name, index] : p.attributes) got.insert(name);
    EXPECT_EQ(got, expected);

    // The mesh shtool baked, as floats in glTF's frame (x, z, -y); indices the smallest
    // type that holds them.
    const std::vector<float> pos = floats(m, p.attributes.at("POSITION"), TINYGLTF_TYPE_VEC3, n);
    const std::vector<float> nrm = floats(m, p.attributes.at("NORMAL"), TINYGLTF_TYPE_VEC3, n);
    std::vector<double> lo(3, INFINITY), hi(3, -INFINITY);
    for (std::size_t v = 0; v < n; ++v)
      for (int c = 0; c < 3; ++c) {
        ASSERT_EQ(pos[v * 3 + c], static_cast<float>(shtool::to_y_up(mesh.positions[v])[c]));
        ASSERT_EQ(nrm[v * 3 + c], static_cast<float>(shtool::to_y_up(mesh.normals[v])[c]));
        lo[c] = std::min<double>(lo[c], pos[v * 3 + c]);
        hi[c] = std::max<double>(hi[c], pos[v * 3 + c]);
      }
    EXPECT_EQ(m.accessors[p.attributes.at("POSITION")].minValues, lo);
    EXPECT_EQ(m.accessors[p.attributes.at("POSITION")].maxValues, hi);
    const tinygltf::Accessor& ia = m.accessors.at(p.indices);
    ASSERT_EQ(ia.componentType, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT);  // 2930 vertices
    ASSERT_EQ(ia.count, mesh.triangles.size() * 3);
    const tinygltf::BufferView& iv = m.bufferViews.at(ia.bufferView);
    EXPECT_EQ(iv.target, TINYGLTF_TARGET_ELEMENT_ARRAY_BUFFER);
    std::vector<std::uint16_t> idx(ia.count);
    std::memcpy(idx.data(), m.buffers[0].data.data() + iv.byteOffset + ia.byteOffset, idx.size() * 2);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(idx[t * 3 + c], mesh.triangles[t][c]) << "triangle " << t;

    // COLOR_0: the transfer DC over the unshadowed DC 1/(2 sqrt(pi)), clamped.
    const nlohmann::json transfer = nlohmann::json::parse(read_file(b.transfer()));
    const std::vector<float> colour = floats(m, p.attributes.at("COLOR_0"), TINYGLTF_TYPE_VEC3, n);
    int clamped = 0;
    for (std::size_t v = 0; v < n; ++v) {
      const double grey = transfer["vectors"][v][0].get<double>() * 2 * std::sqrt(std::numbers::pi);
      clamped += grey > 1 + 1e-12;  // not the rounding of an unoccluded vertex's sum
      for (int c = 0; c < 3; ++c) ASSERT_NEAR(colour[v * 3 + c], std::clamp(grey, 0.0, 1.0), 1e-6) << v;
    }
    // 64 cosine-weighted rays give the unshadowed DC exactly, shadowed less: none clamped.
    EXPECT_EQ(clamped, 0);

    // Axes and coefficients: the --json fits as float, padding zero.
    const nlohmann::json fits = nlohmann::json::parse(read_file(b.json()))["fits"];
    ASSERT_EQ(fits.size(), n);
    for (int k = 0; k < b.lobes; ++k) {
      const std::string lobe = std::to_string(k);
      const std::vector<float> axis = floats(m, p.attributes.at("_ZH_AXIS_" + lobe), TINYGLTF_TYPE_VEC3, n);
      for (std::size_t v = 0; v < n; ++v) {
        const std::vector<double> a = fits[v]["lobes"][k]["axis"].get<std::vector<double>>();
        const Eigen::Vector3d in_gltf = shtool::to_y_up(Eigen::Vector3d(a[0], a[1], a[2]));
        for (int c = 0; c < 3; ++c) ASSERT_EQ(axis[v * 3 + c], static_cast<float>(in_gltf[c])) << v;
      }
      for (int j = 0; j < groups; ++j) {
        const std::vector<float> g =
            floats(m, p.attributes.at("_ZH_COEFFS_" + lobe + "_" + std::to_string(j)), TINYGLTF_TYPE_VEC4, n);
        for (std::size_t v = 0; v < n; ++v)
          for (int c = 0; c < 4; ++c) {
            const int l = 4 * j + c;
            ASSERT_EQ(g[v * 4 + c],
                      l < b.order ? static_cast<float>(fits[v]["lobes"][k]["coeffs"][l].get<double>()) : 0.0f)
                << "vertex " << v << " lobe " << k << " band " << l;
          }
      }
    }
    if (b.direct) {
      const std::vector<float> d = floats(m, p.attributes.at("_ZH_DIRECT"), TINYGLTF_TYPE_VEC4, n);
      for (std::size_t v = 0; v < n; ++v) {
        std::vector<double> stored = fits[v]["direct"].get<std::vector<double>>();
        ASSERT_EQ(stored.size(), b.lobes >= 3 ? 4u : 1u);
        // Band 1 in glTF coordinates (y = -z', z = y'): (y_1^-1, y_1^0, y_1^1) of shtool's
        // (f_-1, f_0, f_1) become (-f_0, f_-1, f_1).
        if (stored.size() == 4) stored = {stored[0], -stored[2], stored[1], stored[3]};
        for (std::size_t c = 0; c < 4; ++c)
          ASSERT_EQ(d[v * 4 + c], c < stored.size() ? static_cast<float>(stored[c]) : 0.0f) << v;
      }
    }
  }
}

TEST(CliFitZhGltf, ShtoolReadsTheSameMeshBack) {
  const shtool::fit::Mesh baked = shtool::fit::load_mesh(kSpotObj);
  const shtool::fit::Mesh back = shtool::fit::load_mesh(bakes()[0].glb());
  ASSERT_EQ(back.positions.size(), baked.positions.size());
  ASSERT_EQ(back.triangles.size(), baked.triangles.size());
  EXPECT_TRUE(back.normals_from_file);
  for (std::size_t v = 0; v < baked.positions.size(); ++v) {
    ASSERT_EQ(back.positions[v], baked.positions[v].cast<float>().cast<double>()) << v;
    ASSERT_NEAR((back.normals[v] - baked.normals[v]).norm(), 0.0, 1e-6) << v;
  }
  for (std::size_t t = 0; t < baked.triangles.size(); ++t) ASSERT_EQ(back.triangles[t], baked.triangles[t]) << t;
}

// The Khronos glTF validator (npm gltf-validator) on every bake: no error, no warning.
TEST(CliFitZhGltf, KhronosValidatorFindsNoError) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  for (const Bake& b : bakes()) {
    const CommandResult r = shtool::test::run_command(
        {"node", (shtool::test::node_consumers_dir() / "validate_gltf.mjs").string(), b.glb().string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json report = nlohmann::json::parse(r.out);
    const nlohmann::json& issues = report["issues"];
    EXPECT_EQ(issues["numErrors"], 0) << issues.dump(1);
    EXPECT_EQ(issues["numWarnings"], 0) << issues.dump(1);
    // The validator read the file as meant: one primitive with every attribute.
    EXPECT_EQ(report["info"]["drawCallCount"], 1) << report.dump(1);
    std::cout << b.name << ": " << report["validatorVersion"].get<std::string>() << ", " << issues["numInfos"]
              << " infos, " << issues["numHints"] << " hints " << issues["messages"].dump() << '\n';
  }
}

// three.js's GLTFLoader, as an engine reads the file: every attribute under its
// documented three.js name with the floats the file holds, the indices, the extras.
TEST(CliFitZhGltf, ThreeJsReadsTheAttributes) {
  SHTOOL_REQUIRE_NODE_CONSUMERS();
  for (const Bake& b : bakes()) {
    SCOPED_TRACE(b.name);
    const CommandResult r = shtool::test::run_command(
        {"node", (shtool::test::node_consumers_dir() / "read_gltf_three.mjs").string(), b.glb().string()});
    ASSERT_EQ(r.exit_code, 0) << r.err;
    const nlohmann::json three = nlohmann::json::parse(r.out);
    EXPECT_EQ(three["meshes"], 1);
    EXPECT_EQ(three["vertexColors"], true);  // COLOR_0 turns them on
    EXPECT_EQ(three["userData"]["shtool_zh_fit"]["order"], b.order);
    const tinygltf::Model m = load(b.glb());
    const tinygltf::Primitive& p = m.meshes[0].primitives[0];
    const std::map<std::string, std::string> standard = {
        {"POSITION", "position"}, {"NORMAL", "normal"}, {"COLOR_0", "color"}};
    ASSERT_EQ(three["attributes"].size(), p.attributes.size());
    for (const auto& [name, index] : p.attributes) {
      std::string lower = name;
      std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
      const std::string three_name = standard.count(name) ? standard.at(name) : lower;
      ASSERT_TRUE(three["attributes"].contains(three_name)) << name << " as " << three_name;
      const nlohmann::json& a = three["attributes"][three_name];
      const tinygltf::Accessor& acc = m.accessors[index];
      const std::vector<float> want = floats(m, index, acc.type, acc.count);
      EXPECT_EQ(a["itemSize"], tinygltf::GetNumComponentsInType(acc.type)) << name;
      ASSERT_EQ(a["values"].size(), want.size()) << name;
      for (std::size_t i = 0; i < want.size(); ++i)
        ASSERT_EQ(a["values"][i].get<double>(), want[i]) << name << " " << i;
    }
    const shtool::fit::Mesh mesh = shtool::fit::load_mesh(kSpotObj);
    ASSERT_EQ(three["index"].size(), mesh.triangles.size() * 3);
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
      for (int c = 0; c < 3; ++c) ASSERT_EQ(three["index"][t * 3 + c], mesh.triangles[t][c]);
  }
}

// Refused before any work, with the reason, and nothing written.
TEST(CliFitZhGltf, RefusalsNameTheProblemAndWriteNothing) {
  const fs::path glb = scratch("refused.glb"), out = scratch("refused.shtb");
  const fs::path vectors = scratch("vectors.json");
  shtool::test::write_file(vectors, R"({"order": 2, "vectors": [[0.8, 0.1, 0.2, 0.3]]})");
  struct Case {
    std::vector<std::string> args;
    std::string message;
  };
  const std::vector<Case> cases = {
      {{"--transfer", vectors.string(), "--gltf", glb.string()}, "--gltf needs a mesh (not --transfer)"},
      {{kSpotObj, "--shard", "0/2", "--gltf", glb.string()}, "--gltf is not written with --shard"},
      // Binary glTF is written under a .glb name only (loaders go by the name); that
      // check comes first, so a table's or the input's name is refused by it.
      {{kSpotObj, "--gltf", out.string()}, "the output is binary glTF, so its name must end in .glb"},
      {{kSpotObj, "--gltf", kSpotObj}, "the output is binary glTF, so its name must end in .glb"},
      {{kSpotObj, "--gltf", scratch("refused.gltf").string()},
       "--gltf " + scratch("refused.gltf").string() + ": the output is binary glTF"},
      {{kSpotObj, "--gltf", scratch("no_such_folder/x.glb").string()}, "--gltf"},
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = {"fit-zh", "--rays", "8", "--order", "2", "--lobes", "1", "--out", out.string()};
    args.insert(args.end(), c.args.begin(), c.args.end());
    const CommandResult r = run_shtool(args);
    EXPECT_EQ(r.exit_code, 1) << c.message;
    EXPECT_NE(r.err.find(c.message), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("fit-zh: "), std::string::npos) << "refused after the bake: " << r.err;
    EXPECT_FALSE(fs::exists(glb));
    EXPECT_FALSE(fs::exists(out));
  }
}

}  // namespace
