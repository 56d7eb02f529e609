// glTF meshes: files written here with tinygltf's own writer (binary and JSON), read by
// load_mesh / load_gltf_bytes, against the OBJ they were made from (world transforms,
// normals, strips and fans, index types) and broken in every way the loader names.
#include <gtest/gtest.h>

#include <tiny_gltf.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "common/input_error.h"
#include "fit/mesh.h"
#include "scratch_files.h"

namespace {

namespace fs = std::filesystem;
using shtool::fit::load_gltf_bytes;
using shtool::fit::Mesh;

struct Primitive {
  std::vector<float> positions;  // xyz per vertex
  std::vector<float> normals;    // empty, or xyz per vertex
  std::vector<std::uint32_t> indices;
  std::vector<float> uvs;        // empty, or uv per vertex (glTF's: v down)
  int uv_type = TINYGLTF_COMPONENT_TYPE_FLOAT;  // or UNSIGNED_SHORT, normalised
  int mode = TINYGLTF_MODE_TRIANGLES;
  int index_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
};

// One buffer holding every array; one mesh of one primitive; nodes as given (the mesh on
// the last one), the scene rooted at node 0.
tinygltf::Model make_model(const Primitive& p, const std::vector<tinygltf::Node>& nodes) {
  tinygltf::Model m;
  m.asset.version = "2.0";
  tinygltf::Buffer buffer;
  auto add_view = [&](const void* data, std::size_t bytes) {
    while (buffer.data.size() % 4) buffer.data.push_back(0);
    tinygltf::BufferView v;
    v.buffer = 0;
    v.byteOffset = buffer.data.size();
    v.byteLength = bytes;
    const auto* b = static_cast<const unsigned char*>(data);
    buffer.data.insert(buffer.data.end(), b, b + bytes);
    m.bufferViews.push_back(v);
    return static_cast<int>(m.bufferViews.size() - 1);
  };
  auto add_accessor = [&](int view, int component, int type, std::size_t count) {
    tinygltf::Accessor a;
    a.bufferView = view;
    a.componentType = component;
    a.type = type;
    a.count = count;
    m.accessors.push_back(a);
    return static_cast<int>(m.accessors.size() - 1);
  };
  tinygltf::Primitive prim;
  prim.mode = p.mode;
  const std::size_t nv = p.positions.size() / 3;
  prim.attributes["POSITION"] = add_accessor(add_view(p.positions.data(), p.positions.size() * 4),
                                             TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nv);
  m.accessors.back().minValues = {-1e9, -1e9, -1e9};
  m.accessors.back().maxValues = {1e9, 1e9, 1e9};
  if (!p.normals.empty())
    prim.attributes["NORMAL"] = add_accessor(add_view(p.normals.data(), p.normals.size() * 4),
                                             TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_TYPE_VEC3, nv);
  if (!p.uvs.empty()) {
    std::vector<std::uint16_t> shorts;
    for (float f : p.uvs) shorts.push_back(static_cast<std::uint16_t>(std::lround(f * 65535.0)));
    const bool as_short = p.uv_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
    prim.attributes["TEXCOORD_0"] =
        add_accessor(as_short ? add_view(shorts.data(), shorts.size() * 2) : add_view(p.uvs.data(), p.uvs.size() * 4),
                     p.uv_type, TINYGLTF_TYPE_VEC2, nv);
    m.accessors.back().normalized = as_short;
  }
  if (!p.indices.empty()) {
    std::vector<unsigned char> bytes;
    for (std::uint32_t i : p.indices) {
      if (p.index_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE) bytes.push_back(static_cast<unsigned char>(i));
      else if (p.index_type == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT) {
        const std::uint16_t s = static_cast<std::uint16_t>(i);
        bytes.insert(bytes.end(), reinterpret_cast<const unsigned char*>(&s), reinterpret_cast<const unsigned char*>(&s) + 2);
      } else {
        bytes.insert(bytes.end(), reinterpret_cast<const unsigned char*>(&i), reinterpret_cast<const unsigned char*>(&i) + 4);
      }
    }
    prim.indices = add_accessor(add_view(bytes.data(), bytes.size()), p.index_type, TINYGLTF_TYPE_SCALAR,
                                p.indices.size());
  }
  m.buffers.push_back(buffer);
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(prim);
  m.meshes.push_back(mesh);
  m.nodes = nodes;
  m.nodes.back().mesh = 0;
  tinygltf::Scene scene;
  scene.nodes = {0};
  m.scenes.push_back(scene);
  m.defaultScene = 0;
  return m;
}

std::string to_bytes(const tinygltf::Model& m, bool binary) {
  tinygltf::TinyGLTF writer;
  std::ostringstream s;
  EXPECT_TRUE(writer.WriteGltfSceneToStream(&m, s, false, binary));
  return s.str();
}

std::string load_error(const std::string& bytes, const char* name = "bad.glb") {
  try {
    load_gltf_bytes(bytes, shtool::test::scratch_path("gltf", name));
  } catch (const shtool::InputError& e) {
    return e.what();
  }
  return "";
}

Primitive spot_primitive(const Mesh& obj) {
  Primitive p;
  for (const Eigen::Vector3d& v : obj.positions)
    for (int c = 0; c < 3; ++c) p.positions.push_back(static_cast<float>(v[c]));
  for (const Eigen::Vector3i& t : obj.triangles)
    for (int c = 0; c < 3; ++c) p.indices.push_back(static_cast<std::uint32_t>(t[c]));
  return p;
}

// TEXCOORD_0, float or normalised unsigned short, kept per triangle corner with v flipped
// to the bottom-left origin; a primitive without it leaves the mesh without UVs.
TEST(GltfMesh, TexcoordsArePerCornerWithVUp) {
  Primitive p;
  p.positions = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
  p.indices = {0, 1, 2, 0, 2, 3};
  p.uvs = {0.25f, 0.5f, 0.75f, 0.5f, 0.75f, 0.0f, 0.25f, 0.0f};
  for (int type : {TINYGLTF_COMPONENT_TYPE_FLOAT, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT}) {
    p.uv_type = type;
    const Mesh m = load_gltf_bytes(to_bytes(make_model(p, {tinygltf::Node{}}), true), "quad.glb");
    ASSERT_EQ(m.uvs.size(), 2u);
    const double tolerance = type == TINYGLTF_COMPONENT_TYPE_FLOAT ? 0.0 : 1e-5;
    EXPECT_NEAR((m.uvs[0][1] - Eigen::Vector2d(0.75, 0.5)).norm(), 0.0, tolerance);
    EXPECT_NEAR((m.uvs[1][1] - Eigen::Vector2d(0.75, 1.0)).norm(), 0.0, tolerance);
    EXPECT_NEAR((m.uvs[1][2] - Eigen::Vector2d(0.25, 1.0)).norm(), 0.0, tolerance);
  }
  p.uvs.clear();
  EXPECT_TRUE(load_gltf_bytes(to_bytes(make_model(p, {tinygltf::Node{}}), true), "quad.glb").uvs.empty());
}

// Spot through two nested nodes (a parent translation; a child T R S): every position is
// the world transform of the OBJ's, turned from glTF's +Y up into shtool's frame,
// triangles are the same, computed normals rotate.
TEST(GltfMesh, NodeTransformsGiveWorldSpace) {
  // The file's own coordinates, written into the glTF as they are.
  const Mesh obj = shtool::fit::load_obj(std::string(SHTOOL_SOURCE_DIR) + "/data/spot.obj",
                                         shtool::fit::NormalSource::automatic, shtool::UpAxis::z);
  tinygltf::Node parent, child;
  parent.translation = {0.5, -1, 2};
  parent.children = {1};
  const Eigen::Quaterniond q = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()));
  child.rotation = {q.x(), q.y(), q.z(), q.w()};
  child.translation = {1, 0, 0};
  child.scale = {2, 2, 2};
  const tinygltf::Model model = make_model(spot_primitive(obj), {parent, child});
  for (bool binary : {true, false}) {
    const Mesh m = load_gltf_bytes(to_bytes(model, binary), binary ? "spot.glb" : "spot.gltf");
    ASSERT_EQ(m.positions.size(), obj.positions.size());
    ASSERT_EQ(m.triangles.size(), obj.triangles.size());
    double worst = 0, worst_normal = 0;
    for (std::size_t v = 0; v < m.positions.size(); ++v) {
      const Eigen::Vector3d p = obj.positions[v].cast<float>().cast<double>();
      const Eigen::Vector3d expected =
          shtool::from_y_up(Eigen::Vector3d(0.5, -1, 2) + (Eigen::Vector3d(1, 0, 0) + q * (2.0 * p)));
      worst = std::max(worst, (m.positions[v] - expected).norm());
      worst_normal = std::max(worst_normal, (m.normals[v] - shtool::from_y_up(q * obj.normals[v])).norm());
    }
    for (std::size_t t = 0; t < m.triangles.size(); ++t) EXPECT_EQ(m.triangles[t], obj.triangles[t]);
    EXPECT_LT(worst, 1e-12) << binary;
    EXPECT_LT(worst_normal, 1e-5) << binary;  // normals of float positions
    EXPECT_FALSE(m.normals_from_file);
  }
}

// A quad as a strip and as a fan, with every index type, and the file's normals used.
TEST(GltfMesh, StripsFansAndIndexTypes) {
  Primitive p;
  p.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  p.normals = {0, 0, 2, 0, 0, 2, 0, 0, 2, 0, 0, 2};
  for (int type : {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                   TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT}) {
    p.index_type = type;
    p.mode = TINYGLTF_MODE_TRIANGLE_STRIP;
    p.indices = {0, 1, 2, 3};
    Mesh m = load_gltf_bytes(to_bytes(make_model(p, {tinygltf::Node()}), true), "strip.glb");
    ASSERT_EQ(m.triangles.size(), 2u);
    EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
    EXPECT_EQ(m.triangles[1], Eigen::Vector3i(2, 1, 3));
    EXPECT_TRUE(m.normals_from_file);
    EXPECT_LT((m.normals[3] - Eigen::Vector3d(0, -1, 0)).norm(), 1e-15);  // glTF's +Z is shtool's -y
    p.mode = TINYGLTF_MODE_TRIANGLE_FAN;
    p.indices = {0, 1, 3, 2};
    m = load_gltf_bytes(to_bytes(make_model(p, {tinygltf::Node()}), true), "fan.glb");
    ASSERT_EQ(m.triangles.size(), 2u);
    EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 3));
    EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 3, 2));
  }
}

TEST(GltfMesh, BadFilesAreRefusedByName) {
  Primitive quad;
  quad.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  quad.indices = {0, 1, 2, 2, 1, 3};
  const tinygltf::Model good = make_model(quad, {tinygltf::Node()});
  EXPECT_EQ(load_error(to_bytes(good, true)), "");

  tinygltf::Model m = good;
  m.accessors[0].count = 1000;  // past its buffer view
  EXPECT_NE(load_error(to_bytes(m, true)).find("reads past the end"), std::string::npos) << load_error(to_bytes(m, true));

  m = good;
  m.meshes[0].primitives[0].mode = TINYGLTF_MODE_POINTS;
  EXPECT_NE(load_error(to_bytes(m, true)).find("no triangle primitive"), std::string::npos);

  m = good;
  float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(m.buffers[0].data.data() + 4, &nan, 4);
  EXPECT_NE(load_error(to_bytes(m, true)).find("not finite"), std::string::npos);

  m = good;
  std::uint32_t big = 7;
  std::memcpy(m.buffers[0].data.data() + m.bufferViews[1].byteOffset, &big, 4);
  EXPECT_NE(load_error(to_bytes(m, true)).find("past the 4 vertices"), std::string::npos);

  m = good;
  m.nodes[0].children = {0};
  EXPECT_NE(load_error(to_bytes(m, true)).find("cycle"), std::string::npos);

  // A node with two parents (each level doubling the instances) is refused.
  m = good;
  m.nodes.resize(3);
  m.nodes[0].mesh = -1;
  m.nodes[0].children = {1, 2};
  m.nodes[1].children = {2};
  m.nodes[2].mesh = 0;
  EXPECT_NE(load_error(to_bytes(m, true)).find("reached twice"), std::string::npos) << load_error(to_bytes(m, true));

  m = good;
  m.bufferViews[0].byteStride = 8;  // below the 12 bytes of a float VEC3
  EXPECT_NE(load_error(to_bytes(m, true)).find("byteStride"), std::string::npos) << load_error(to_bytes(m, true));

  m = good;
  m.scenes.clear();
  m.defaultScene = -1;
  EXPECT_NE(load_error(to_bytes(m, true)).find("no scene"), std::string::npos);

  // JSON naming an external buffer that is not there.
  m = good;
  std::string json = to_bytes(m, false);
  const std::size_t uri = json.find("\"uri\"");
  ASSERT_NE(uri, std::string::npos);
  const std::size_t start = json.find('"', uri + 5), end = json.find('"', start + 1);
  json.replace(start, end - start + 1, "\"missing.bin\"");
  EXPECT_NE(load_error(json, "external.gltf").find("cannot read glTF"), std::string::npos) << load_error(json);

  // The magic, then no container version 2.
  EXPECT_NE(load_error("glTF garbage").find("GLB container version"), std::string::npos) << load_error("glTF garbage");
}

// The tool on a .glb end to end: load_mesh recognises it by content and name.
TEST(GltfMesh, LoadMeshFindsGltfByContent) {
  Primitive quad;
  quad.positions = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
  quad.indices = {0, 1, 2, 2, 1, 3};
  const fs::path glb = shtool::test::scratch_path("gltf", "quad.bin");  // no telling extension
  {
    std::ofstream f(glb, std::ios::binary);
    f << to_bytes(make_model(quad, {tinygltf::Node()}), true);
  }
  const Mesh m = shtool::fit::load_mesh(glb);
  EXPECT_EQ(m.triangles.size(), 2u);
}

}  // namespace
