// Meshes in their own frame, end to end: a glTF is +Y up (its specification), an OBJ is
// y-up unless --up z says it is written in shtool's z-up frame; both are baked, rendered
// and written back in the frame they came in. The references are geometric: a quad
// facing up has the unshadowed transfer of a cosine lobe about +z (only y_0^0 and y_1^0),
// one facing glTF -Z about +y; a quad facing up is lit by the zenith and dark under the
// nadir; a glTF written from a glTF input has the input's positions bit for bit.
#include <tiny_gltf.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "fit/gltf_model.h"
#include "lighting/image_io.h"
#include "cli_test.h"
#include "shtool/table.h"

namespace {

using namespace shtool::test;

const Scratch scratch("mesh_frames");

// A 2 x 2 quad in the plane through the origin spanned by `a` and `b`, as two triangles
// counter-clockwise seen from a x b (its front). Coordinates are small integers, exact
// in float, so the OBJ and the glTF hold the same numbers.
struct Quad {
  std::vector<float> positions;  // xyz per corner
  std::vector<std::uint32_t> indices = {0, 1, 2, 0, 2, 3};
};

Quad quad(const std::array<float, 3>& a, const std::array<float, 3>& b) {
  Quad q;
  const float s[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
  for (const auto& c : s)
    for (int k = 0; k < 3; ++k) q.positions.push_back(c[0] * a[k] + c[1] * b[k]);
  return q;
}

fs::path write_obj(const Quad& q, const std::string& name) {
  std::ostringstream s;
  for (std::size_t v = 0; v < q.positions.size() / 3; ++v)
    s << "v " << q.positions[3 * v] << ' ' << q.positions[3 * v + 1] << ' ' << q.positions[3 * v + 2] << '\n';
  for (std::size_t t = 0; t < q.indices.size(); t += 3)
    s << "f " << q.indices[t] + 1 << ' ' << q.indices[t + 1] + 1 << ' ' << q.indices[t + 2] + 1 << '\n';
  const fs::path p = scratch(name);
  shtool::test::write_file(p, s.str());
  return p;
}

// The quad as a .glb written by tinygltf, no node transform.
fs::path write_glb(const Quad& q, const std::string& name) {
  tinygltf::Model m;
  m.asset.version = "2.0";
  tinygltf::Buffer buffer;
  const auto* p = reinterpret_cast<const unsigned char*>(q.positions.data());
  buffer.data.assign(p, p + q.positions.size() * 4);
  const auto* i = reinterpret_cast<const unsigned char*>(q.indices.data());
  buffer.data.insert(buffer.data.end(), i, i + q.indices.size() * 4);
  m.buffers.push_back(buffer);
  m.bufferViews.resize(2);
  m.bufferViews[0].buffer = 0;
  m.bufferViews[0].byteLength = q.positions.size() * 4;
  m.bufferViews[1].buffer = 0;
  m.bufferViews[1].byteOffset = q.positions.size() * 4;
  m.bufferViews[1].byteLength = q.indices.size() * 4;
  m.accessors.resize(2);
  m.accessors[0].bufferView = 0;
  m.accessors[0].componentType = TINYGLTF_COMPONENT_TYPE_FLOAT;
  m.accessors[0].type = TINYGLTF_TYPE_VEC3;
  m.accessors[0].count = q.positions.size() / 3;
  m.accessors[0].minValues = {-1, -1, -1};
  m.accessors[0].maxValues = {1, 1, 1};
  m.accessors[1].bufferView = 1;
  m.accessors[1].componentType = TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT;
  m.accessors[1].type = TINYGLTF_TYPE_SCALAR;
  m.accessors[1].count = q.indices.size();
  tinygltf::Primitive prim;
  prim.attributes["POSITION"] = 0;
  prim.indices = 1;
  prim.mode = TINYGLTF_MODE_TRIANGLES;
  tinygltf::Mesh mesh;
  mesh.primitives.push_back(prim);
  const fs::path path = scratch(name);
  shtool::test::write_file(path, shtool::fit::write_single_mesh_gltf(m, mesh, true));
  return path;
}

// The POSITION floats of the first primitive of a .glb.
std::vector<float> glb_positions(const fs::path& path) {
  tinygltf::Model m;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, path.string())) << err;
  const tinygltf::Accessor& a = m.accessors.at(m.meshes.at(0).primitives.at(0).attributes.at("POSITION"));
  const tinygltf::BufferView& v = m.bufferViews.at(a.bufferView);
  std::vector<float> out(a.count * 3);
  std::memcpy(out.data(), m.buffers.at(v.buffer).data.data() + v.byteOffset + a.byteOffset, out.size() * 4);
  return out;
}

// fit-zh of `mesh`, unshadowed, order 2, one lobe: the transfer vectors (4 per vertex).
std::vector<double> bake(const fs::path& mesh, const std::string& name, std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {"fit-zh", mesh.string(), "--order", "2", "--lobes", "1", "--mode", "unshadowed",
                                   "--rays", "256", "--out", scratch(name + ".shtb").string(), "--save-transfer",
                                   scratch(name + ".t.json").string()};
  args.insert(args.end(), extra.begin(), extra.end());
  const CommandResult r = run_shtool(args);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  std::vector<double> t;
  const nlohmann::json doc = nlohmann::json::parse(read_file(scratch(name + ".t.json")));
  for (const auto& row : doc["vectors"])
    for (double x : row) t.push_back(x);
  return t;
}

// Every vertex's transfer is a cosine lobe about `axis` (shtool's frame): band 1 is
// c (-a_y, a_z, -a_x) times |band 1| (y_1^-1 = -c y, y_1^0 = c z, y_1^1 = -c x).
void expect_lobe_along(const std::vector<double>& t, const Eigen::Vector3d& axis, const std::string& what) {
  ASSERT_EQ(t.size() % 4, 0u);
  ASSERT_FALSE(t.empty());
  const Eigen::Vector3d expected_band1(-axis.y(), axis.z(), -axis.x());
  for (std::size_t v = 0; v < t.size(); v += 4) {
    const Eigen::Vector3d band1(t[v + 1], t[v + 2], t[v + 3]);
    ASSERT_GT(band1.norm(), 0.1) << what;
    // 256 cosine-weighted rays: the direction is right to about 3e-3.
    EXPECT_LT((band1.normalized() - expected_band1).norm(), 1e-2) << what << " vertex " << v / 4 << ": "
                                                                   << band1.transpose();
  }
}

// The arrays of a table, by name, as bytes.
std::vector<std::pair<std::string, std::vector<std::byte>>> arrays_of(const fs::path& path) {
  shtool::Result<shtool::Table> t = shtool::read_table(path);
  EXPECT_TRUE(t) << t.error().message;
  std::vector<std::pair<std::string, std::vector<std::byte>>> out;
  if (t)
    for (const shtool::TableArray& a : t.value().arrays) out.emplace_back(a.name, a.data);
  return out;
}

nlohmann::json meta_of(const fs::path& path) { return nlohmann::json::parse(shtool::read_table(path).value().meta); }

// glTF's +Y and an OBJ's +y (the default --up y) are shtool's +z; glTF's -Z is shtool's
// +y; --up z takes an OBJ as written. The y-up OBJ and the glTF of the same quad give
// the same arrays, and each table records the frame it was read in.
TEST(MeshFrames, UpFacingQuadsBakeAlongZ) {
  const Quad up = quad({1, 0, 0}, {0, 0, -1});    // x cross -z = +y
  const Quad back = quad({1, 0, 0}, {0, -1, 0});  // x cross -y = -z (a glTF asset's front is +Z)
  const std::vector<double> obj_y = bake(write_obj(up, "up.obj"), "obj_y");
  const std::vector<double> gltf_y = bake(write_glb(up, "up.glb"), "gltf_y");
  expect_lobe_along(obj_y, Eigen::Vector3d::UnitZ(), "OBJ facing +y, --up y");
  expect_lobe_along(gltf_y, Eigen::Vector3d::UnitZ(), "glTF facing +Y");
  EXPECT_EQ(obj_y, gltf_y);
  EXPECT_EQ(arrays_of(scratch("obj_y.shtb")), arrays_of(scratch("gltf_y.shtb")));
  EXPECT_EQ(meta_of(scratch("obj_y.shtb"))["mesh_up"], "y");
  EXPECT_EQ(meta_of(scratch("gltf_y.shtb"))["mesh_up"], "y");

  expect_lobe_along(bake(write_glb(back, "minus_z.glb"), "gltf_minus_z"), Eigen::Vector3d::UnitY(),
                    "glTF facing -Z");
  // --up z: as written, the +y-facing quad faces shtool's +y.
  expect_lobe_along(bake(write_obj(up, "up_as_z.obj"), "obj_z", {"--up", "z"}), Eigen::Vector3d::UnitY(),
                    "OBJ facing +y, --up z");
  EXPECT_EQ(meta_of(scratch("obj_z.shtb"))["mesh_up"], "z");
  const nlohmann::json gen = nlohmann::json::parse(shtool::read_table(scratch("obj_z.shtb")).value().generator);
  EXPECT_EQ(gen["parameters"]["up"], "z") << gen.dump();

  // A glTF has no other frame.
  const CommandResult r = run_shtool({"fit-zh", write_glb(up, "up2.glb").string(), "--up", "z", "--out",
                               scratch("refused.shtb").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("+Y up"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(scratch("refused.shtb")));
}

// --gltf writes glTF's frame: a glTF input comes back with its positions bit for bit, a
// y-up OBJ with its own coordinates, a z-up OBJ turned to y up.
// Shadows do not depend on where a mesh is: spot placed 1e4 and 1e5 units away by a glTF
// node's translation (a level's prop, a georeferenced scan) bakes the transfer it bakes
// at the origin, to the bit. Traced in floats where it lies, the rays' offset off the
// surface (2.6e-4) fell below float's spacing there (1e-3 at 1e4) and rays hit their own
// triangles (327 vertices moved at 1e5). An OBJ, which tinyobjloader reads in float, is
// refused that far out: its shape itself is rounded coarser than the offset.
TEST(MeshFrames, FarFromTheOriginShadowsAsAtIt) {
  const fs::path obj = fs::path(SHTOOL_SOURCE_DIR) / "data/spot.obj", glb = scratch("far.glb");
  must(run_shtool({"fit-zh", obj.string(), "--order", "2", "--lobes", "1", "--rays", "16", "--out",
                   scratch("far_fit.shtb").string(), "--gltf", glb.string()}));
  auto transfer = [&](const fs::path& mesh, const std::string& name) {
    must(run_shtool({"fit-zh", mesh.string(), "--order", "2", "--lobes", "1", "--rays", "64", "--out",
                     scratch(name + ".shtb").string(), "--save-transfer", scratch(name + ".t.json").string()}));
    return nlohmann::json::parse(read_file(scratch(name + ".t.json")))["vectors"];
  };
  const nlohmann::json at_origin = transfer(glb, "far0");
  for (double by : {1e4, 1e5}) {
    tinygltf::Model m;
    tinygltf::TinyGLTF loader;
    std::string err, warn;
    ASSERT_TRUE(loader.LoadBinaryFromFile(&m, &err, &warn, glb.string())) << err;
    m.nodes.at(0).translation = {by, -by, 0.5 * by};
    const fs::path moved = scratch("far_moved.glb");
    ASSERT_TRUE(loader.WriteGltfSceneToFile(&m, moved.string(), false, true, false, true));
    EXPECT_EQ(transfer(moved, "far"), at_origin) << "moved by " << by;
  }
  // The OBJ 1e4 out: refused, naming the spacing.
  std::istringstream in(read_file(obj));
  std::ostringstream out;
  out.precision(17);
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("v ", 0) == 0) {
      std::istringstream v(line.substr(2));
      double x, y, z;
      v >> x >> y >> z;
      out << "v " << x + 1e4 << " " << y << " " << z << "\n";
    } else {
      out << line << "\n";
    }
  }
  write_file(scratch("far.obj"), out.str());
  expect_refused("fit-zh", {scratch("far.obj").string(), "--order", "2", "--rays", "16"},
                 "an OBJ's single precision (as tinyobjloader reads it) spaces them", scratch("far_obj.shtb"));
}

// An OBJ's material library is part of the asset (bake-probes reads its colours): no
// output of fit-zh replaces it, whether or not fit-zh reads it.
TEST(MeshFrames, AnObjsMaterialLibraryIsAnInput) {
  const fs::path dir = scratch("mtl_input");
  fs::create_directories(dir);
  shtool::test::write_file(dir / "q.obj", "mtllib m.mtl\nv -5 -5 0\nv 5 -5 0\nv 0 5 0\nf 1 2 3\n");
  shtool::test::write_file(dir / "m.mtl", "newmtl a\nKd 1 1 1\n");
  for (const char* option : {"--out", "--json"}) {
    const std::vector<std::string> args = {(dir / "q.obj").string(), "--order", "2", "--rays", "8"};
    std::vector<std::string> argv = {"fit-zh"};
    argv.insert(argv.end(), args.begin(), args.end());
    if (std::string(option) == "--json") argv.insert(argv.end(), {"--out", (dir / "o.shtb").string()});
    argv.insert(argv.end(), {option, (dir / "m.mtl").string()});
    const CommandResult r = run_shtool(argv);
    EXPECT_EQ(r.exit_code, 1) << option;
    EXPECT_NE(r.err.find("(a file of the mesh); refusing to overwrite it"), std::string::npos) << r.err;
    EXPECT_EQ(read_file(dir / "m.mtl"), "newmtl a\nKd 1 1 1\n") << option;
  }
}

TEST(MeshFrames, GltfOutputIsInGltfsFrame) {
  const Quad q = quad({1, 0, 0}, {0, 0.5f, -1});
  for (const std::string& kind : {"glb", "obj_y", "obj_z"}) {
    const fs::path in = kind == "glb" ? write_glb(q, "tilted.glb") : write_obj(q, "tilted_" + kind + ".obj");
    const fs::path out = scratch("tilted_" + kind + ".out.glb");
    std::vector<std::string> args = {"fit-zh", in.string(), "--order", "2", "--lobes", "1", "--rays", "16",
                                     "--out", scratch("tilted_" + kind + ".shtb").string(), "--gltf", out.string()};
    if (kind == "obj_z") args.insert(args.end(), {"--up", "z"});
    must(run_shtool(args));
    const std::vector<float> p = glb_positions(out);
    ASSERT_EQ(p.size(), q.positions.size()) << kind;
    for (std::size_t v = 0; v < p.size() / 3; ++v) {
      const float* in_p = &q.positions[3 * v];
      // --up z: the file's (x, y, z) is shtool's, written as glTF's (x, z, -y).
      const std::array<float, 3> expected =
          kind == "obj_z" ? std::array<float, 3>{in_p[0], in_p[2], -in_p[1]} : std::array<float, 3>{in_p[0], in_p[1], in_p[2]};
      for (int c = 0; c < 3; ++c) EXPECT_EQ(p[3 * v + c], expected[c]) << kind << " vertex " << v;
    }
  }
  // Bit for bit, signed zeros too: a flat quad whose first corner has y = -0.0 (once
  // written back as +0.0 by the node transform's + 0).
  const Quad flat = quad({1, 0, 0}, {0, 0, 1});
  ASSERT_TRUE(std::signbit(flat.positions[1]));
  const fs::path out = scratch("flat.out.glb");
  must(run_shtool({"fit-zh", write_glb(flat, "flat.glb").string(), "--order", "2", "--lobes", "1", "--rays", "16",
                   "--out", scratch("flat.shtb").string(), "--gltf", out.string()}));
  const std::vector<float> p = glb_positions(out);
  ASSERT_EQ(p.size(), flat.positions.size());
  EXPECT_EQ(std::memcmp(p.data(), flat.positions.data(), p.size() * sizeof(float)), 0) << "not the input's bits";
}

// The zenith (+z, shtool's frame) lights a quad facing up; the nadir leaves it dark
// (order 2: the clamped cosine truncated to bands 0 and 1 is 1/4 - 1/2 < 0 there).
TEST(MeshFrames, ZenithLightsAnUpFacingQuad) {
  const fs::path mesh = write_obj(quad({1, 0, 0}, {0, 0, -1}), "lit.obj");
  bake(mesh, "lit");
  for (const std::string& dir : {"0,0,1", "0,0,-1"}) {
    const fs::path light = scratch("light" + dir + ".json");
    must(run_shtool({"light", "--type", "directional", "--dir", dir, "--color", "1,1,1", "--order", "2", "--json",
              light.string()}));
    const fs::path out = scratch("lit" + dir + ".exr");
    const CommandResult rendered = run_shtool({"render", mesh.string(), "--transfer", scratch("lit.t.json").string(),
                                        "--light", light.string(), "--width", "64", "--height", "64", "--out",
                                        out.string()});
    ASSERT_EQ(rendered.exit_code, 0) << rendered.err;
    // render counts what it could not show: none under the zenith, the whole quad under the nadir.
    EXPECT_EQ(rendered.err.find("below zero") != std::string::npos, dir == "0,0,-1") << rendered.err;
    const shtool::lighting::Image image = read_image(out);
    // The background is 0; the quad is uniformly lit (one transfer vector, one light), so
    // every covered pixel has the same sign.
    int positive = 0, negative = 0;
    for (std::size_t i = 0; i < image.texels.size(); i += image.channels)
      positive += image.texels[i] > 0.1f, negative += image.texels[i] < 0;
    if (dir == "0,0,1") {
      EXPECT_GT(positive, 100) << "lit from the zenith";
      EXPECT_EQ(negative, 0);
    } else {
      EXPECT_GT(negative, 100) << "dark from the nadir";
      EXPECT_EQ(positive, 0);
    }
  }
}

// A bake read y-up is not put on the mesh read z-up (nor the other way): render and
// deform refuse, naming --up, and write nothing.
TEST(MeshFrames, RenderAndDeformRefuseToMixFrames) {
  const fs::path mesh = write_obj(quad({1, 0, 0}, {0, 0, -1}), "mix.obj");
  bake(mesh, "mix");
  must(run_shtool({"light", "--type", "constant", "--color", "1,1,1", "--order", "2", "--json",
            scratch("white.json").string()}));
  const fs::path image = scratch("mix.png");
  CommandResult r = run_shtool({"render", mesh.string(), "--up", "z", "--fit", scratch("mix.shtb").string(), "--light",
                         scratch("white.json").string(), "--out", image.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--up"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(image));
  must(run_shtool({"render", mesh.string(), "--fit", scratch("mix.shtb").string(), "--light", scratch("white.json").string(),
            "--width", "16", "--height", "16", "--out", image.string()}));
  // The transfer vectors carry the record, and so does a fit made from them.
  EXPECT_EQ(nlohmann::json::parse(read_file(scratch("mix.t.json")))["mesh_up"], "y");
  must(run_shtool({"fit-zh", "--transfer", scratch("mix.t.json").string(), "--out", scratch("mix.from_t.shtb").string()}));
  EXPECT_EQ(meta_of(scratch("mix.from_t.shtb"))["mesh_up"], "y");
  for (const std::string& input : {"--transfer", "--fit"}) {
    const fs::path baked = input == "--transfer" ? scratch("mix.t.json") : scratch("mix.from_t.shtb");
    const fs::path refused = scratch("mix_refused.png");
    r = run_shtool({"render", mesh.string(), "--up", "z", input, baked.string(), "--light", scratch("white.json").string(),
             "--out", refused.string()});
    EXPECT_EQ(r.exit_code, 1) << input;
    EXPECT_NE(r.err.find("--up"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(refused));
  }
  const fs::path posed = scratch("mix.posed.shtb");
  r = run_shtool({"deform", scratch("mix.shtb").string(), "--rest", mesh.string(), "--pose", mesh.string(), "--up", "z",
           "--out", posed.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--up"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(posed));
  must(run_shtool({"deform", scratch("mix.shtb").string(), "--rest", mesh.string(), "--pose", mesh.string(), "--out",
            posed.string()}));
  EXPECT_EQ(meta_of(posed)["mesh_up"], "y");
}

// A bake is put back only on the mesh it was made on: another mesh with as many vertices
// (the same quad turned to face the front) is refused by render, deform and export-web,
// which name it and write nothing, through the loaded mesh's checksum the table records.
// A bake that computed its normals from a file with its own is still its mesh's. A table
// read z-up put on a glTF (which takes no --up) is refused with the advice that applies.
TEST(MeshFrames, RenderDeformAndExportWebRefuseAnotherMesh) {
  const fs::path mesh = write_obj(quad({1, 0, 0}, {0, 0, -1}), "same_a.obj");
  const fs::path other = write_obj(quad({1, 0, 0}, {0, 1, 0}), "same_b.obj");
  bake(mesh, "same");
  must(run_shtool({"light", "--type", "directional", "--dir", "0,0,1", "--order", "2", "--json",
                   scratch("zenith.json").string()}));
  const std::string table = scratch("same.shtb").string(), light = scratch("zenith.json").string();
  const fs::path image = scratch("same_refused.png"), posed = scratch("same_refused.shtb"),
                 folder = scratch("same_refused_web");
  const std::vector<std::pair<std::vector<std::string>, fs::path>> runs = {
      {{"render", other.string(), "--fit", table, "--light", light, "--out", image.string()}, image},
      {{"deform", table, "--rest", other.string(), "--pose", other.string(), "--out", posed.string()}, posed},
      {{"export-web", other.string(), "--fit", table, "--light", light, "--out", folder.string()}, folder},
      // The transfer vectors record the mesh too (render --transfer once took another
      // mesh's with as many vertices).
      {{"render", other.string(), "--transfer", scratch("same.t.json").string(), "--light", light, "--out",
        image.string()},
       image},
      // A fit of those vectors (fit-zh --transfer) keeps their mesh's checksum.
      {{"render", other.string(), "--fit", scratch("same_refit.shtb").string(), "--light", light, "--out",
        image.string()},
       image}};
  must(run_shtool({"fit-zh", "--transfer", scratch("same.t.json").string(), "--lobes", "1", "--out",
                   scratch("same_refit.shtb").string()}));
  for (const auto& [args, out] : runs) {
    const CommandResult r = run_shtool(args);
    EXPECT_EQ(r.exit_code, 1) << args[0];
    EXPECT_NE(r.err.find("another mesh"), std::string::npos) << args[0] << ": " << r.err;
    EXPECT_NE(r.err.find("same_b.obj"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out)) << args[0];
  }
  must(run_shtool({"render", mesh.string(), "--fit", table, "--light", light, "--width", "16", "--height", "16", "--out",
                   image.string()}));

  // The same quad with tilted normals in the file, baked with --normals computed: render
  // loads the file's normals, so the checksum needs the mesh read again as it was baked.
  const fs::path with_normals = scratch("same_n.obj");
  std::string text = read_file(mesh);
  std::string faces;
  for (std::size_t pos = text.find("f "); pos != std::string::npos; pos = text.find("f ", pos + 1)) {
    int a = 0, b = 0, c = 0;
    std::sscanf(text.c_str() + pos, "f %d %d %d", &a, &b, &c);
    faces += "f " + std::to_string(a) + "//1 " + std::to_string(b) + "//1 " + std::to_string(c) + "//1\n";
  }
  shtool::test::write_file(with_normals, text.substr(0, text.find("f ")) + "vn 0.6 0.8 0\n" + faces);
  bake(with_normals, "same_n", {"--normals", "computed"});
  must(run_shtool({"render", with_normals.string(), "--fit", scratch("same_n.shtb").string(), "--light", light,
                   "--width", "16", "--height", "16", "--out", scratch("same_n.png").string()}));
  must(run_shtool({"render", with_normals.string(), "--transfer", scratch("same_n.t.json").string(), "--light",
                   light, "--width", "16", "--height", "16", "--out", scratch("same_nt.png").string()}));
  must(run_shtool({"fit-zh", "--transfer", scratch("same_n.t.json").string(), "--lobes", "1", "--out",
                   scratch("same_n_refit.shtb").string()}));
  must(run_shtool({"render", with_normals.string(), "--fit", scratch("same_n_refit.shtb").string(), "--light", light,
                   "--width", "16", "--height", "16", "--out", scratch("same_nr.png").string()}));
  must(run_shtool({"render", mesh.string(), "--transfer", scratch("same.t.json").string(), "--light", light,
                   "--width", "16", "--height", "16", "--out", scratch("same_t.png").string()}));

  // A table read z-up on a glTF.
  bake(mesh, "same_z", {"--up", "z"});
  const fs::path glb = write_glb(quad({1, 0, 0}, {0, 0, -1}), "same.glb");
  const fs::path glb_image = scratch("same_glb_refused.png");
  const CommandResult r = run_shtool({"render", glb.string(), "--fit", scratch("same_z.shtb").string(), "--light",
                                      light, "--out", glb_image.string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("a glTF is always read y-up"), std::string::npos) << r.err;
  EXPECT_FALSE(fs::exists(glb_image));
}

}  // namespace
