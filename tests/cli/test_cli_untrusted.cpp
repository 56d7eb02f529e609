// The command line on the inputs that once crashed it, overwrote an input, left partial
// outputs or said "internal error": each must exit 1 with a message naming the problem
// and leave no output behind (docs/reliability.md).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <cstdint>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "cli_test.h"
#include "scratch_files.h"

namespace shtool {
namespace {

using namespace test;

class CliUntrusted : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = test::empty_folder_for_this_test(test::Scratch("untrusted"));
    mesh_ = dir_ / "m.obj";
    fs::copy_file(fs::path(SHTOOL_SOURCE_DIR) / "data/spot.obj", mesh_);
    std::ofstream(dir_ / "t.json") << R"({"order":2,"vectors":[[1,0.1,0.2,0.3]]})";
  }
  CommandResult run(const std::vector<std::string>& args, const std::string& stdin_data = "") {
    return test::run_shtool(args, {.stdin_data = stdin_data});
  }
  // Exit 1, the fragment in the message, no "internal error".
  void expect_refused(const CommandResult& r, const std::string& fragment) {
    EXPECT_EQ(r.exit_code, 1) << r.err;
    EXPECT_NE(r.err.find(fragment), std::string::npos) << "stderr '" << r.err << "' lacks '" << fragment << "'";
    EXPECT_EQ(r.err.find("internal error"), std::string::npos) << r.err;
  }
  std::vector<std::string> listing() const {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
  }
  fs::path dir_, mesh_;
};

TEST_F(CliUntrusted, OutputsThatAreTheInputOrEachOtherAreRefused) {
  const std::uintmax_t size = fs::file_size(mesh_);
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--out", mesh_.string()}), "is the input");
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--ply", (dir_ / "." / "m.obj").string()}),
                 "is the input");
  EXPECT_EQ(fs::file_size(mesh_), size) << "the mesh was overwritten";
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--out", (dir_ / "x").string(), "--json",
                      (dir_ / "x").string()}),
                 "name the same file");
  EXPECT_EQ(listing(), (std::vector<std::string>{"m.obj", "t.json"}));
}

TEST_F(CliUntrusted, AllOutputsOrNone) {
  // The second output's folder does not exist: refused before the bake, nothing written.
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--out", (dir_ / "ok.shtb").string(), "--json",
                      (dir_ / "nodir" / "x.json").string()}),
                 "does not exist");
  expect_refused(run({"search-lobes", "--band", "2", "--restarts", "1", "--out", (dir_ / "l.shtb").string(),
                      "--json", (dir_ / "nodir" / "l.json").string()}),
                 "does not exist");
  // gen-tensors whose kernel target is a folder: no table, no temporary file.
  fs::create_directories(dir_ / "k" / "rotation_kernels_generated.inc");
  expect_refused(run({"gen-tensors", "--what", "rotation,rotation-kernels", "--out", (dir_ / "k").string()}),
                 "is a folder");
  EXPECT_FALSE(fs::exists(dir_ / "k" / "rotation-helpers.shtb"));
  EXPECT_EQ(listing(), (std::vector<std::string>{"k", "m.obj", "t.json"}));
  std::size_t in_k = 0;
  for (const auto& e : fs::directory_iterator(dir_ / "k")) in_k += e.path().filename() != "rotation_kernels_generated.inc";
  EXPECT_EQ(in_k, 0u);
}

// Output folders are made with their missing parents by every command that writes one,
// and a file in the way is named before any work.
TEST_F(CliUntrusted, OutputFoldersAreMadeWithTheirParentsOrRefused) {
  const CommandResult made =
      run({"gen-tensors", "--order", "3", "--what", "rotation", "--out", (dir_ / "a" / "b" / "c").string()});
  EXPECT_EQ(made.exit_code, 0) << made.err;
  EXPECT_TRUE(fs::is_regular_file(dir_ / "a" / "b" / "c" / "rotation-helpers.shtb"));
  expect_refused(run({"gen-tensors", "--order", "3", "--what", "rotation", "--out", (dir_ / "m.obj" / "b").string()}),
                 "--out " + (dir_ / "m.obj" / "b").string() + ": cannot be made: " + (dir_ / "m.obj").string() +
                     " is not a folder");
  expect_refused(run({"gen-tensors", "--order", "3", "--what", "rotation", "--out", mesh_.string()}),
                 "exists and is not a folder");
  EXPECT_EQ(listing(), (std::vector<std::string>{"a", "m.obj", "t.json"}));
}

TEST_F(CliUntrusted, FoldersAndMissingFilesAreNamed) {
  expect_refused(run({"product", "--order", "2", "--in", dir_.string()}), "is a folder");
  expect_refused(run({"fit-zh", "--transfer", dir_.string()}), "is a folder");
  expect_refused(run({"rotate", "--order", "2", "--zyz", "0,0,0", "--in", dir_.string()}), "is a folder");
  expect_refused(run({"fit-zh", mesh_.string(), "--rays", "8", "--ply", dir_.string()}), "is a folder");
}

TEST_F(CliUntrusted, LimitsAreRefusedWithTheirFigures) {
  expect_refused(run({"fit-zh", "--transfer", (dir_ / "t.json").string(), "--threads", "100000"}), "at most");
  expect_refused(run({"search-lobes", "--band", "3", "--threads", "100000"}), "at most");
  expect_refused(run({"search-lobes", "--band", "100"}), "GiB");
  // Each within its range, together 16.7 million samples (5 GB, hours with no output).
  expect_refused(run({"fit-wrinkles", "--grid", "256", "--samples", "16", "--out", (dir_ / "w.shtb").string()}),
                 "--grid 256 with --samples 16 makes 16715776 samples");
  // Refused before the search, naming the option's rule (inf used to run the whole
  // search and then fail on the table's record; 0 and -5 generations ran one).
  expect_refused(run({"search-lobes", "--band", "3", "--max-cond", "inf", "--out", (dir_ / "c.shtb").string()}),
                 "max condition number must be finite");
  for (const char* g : {"0", "-5"})
    expect_refused(run({"search-lobes", "--band", "3", "--max-generations", g}), "max generations must be at least 1");
  expect_refused(run({"search-lobes", "--band", "0"}), "--band must be in 1..");
  EXPECT_FALSE(fs::exists(dir_ / "c.shtb"));
  expect_refused(run({"fit-zh", mesh_.string(), "--mode", "interreflected", "--bounces", "2147483647"}),
                 "--bounces must be in 1..64");
  const CommandResult seed = run({"fit-zh", "--transfer", (dir_ / "t.json").string(), "--seed", "-1"});
  EXPECT_EQ(seed.exit_code, 1) << seed.err;
  EXPECT_NE(seed.err.find("must not be negative"), std::string::npos) << seed.err;
}

TEST_F(CliUntrusted, HugeValuesNeverBecomeNullOrNan) {
  std::ofstream(dir_ / "huge.json") << R"({"order":3,"vectors":[[1,8,1e308,3,8,8,0,3,3]]})";
  expect_refused(run({"fit-zh", "--transfer", (dir_ / "huge.json").string(), "--out", (dir_ / "h.shtb").string()}),
                 "beyond 1e100");
  EXPECT_FALSE(fs::exists(dir_ / "h.shtb"));
  expect_refused(run({"rotate", "--order", "2", "--zyz", "0.3,1,0.2", "--coeffs", "1.7e308,1.7e308,1.7e308,1.7e308",
                      "--method", "reference"}),
                 "overflow");
}

TEST_F(CliUntrusted, DeepJsonIsAnErrorNotACrash) {
  const std::string deep = "{\"inputs\": " + std::string(52000, '[') + std::string(52000, ']') + "}";
  expect_refused(run({"product", "--order", "2", "--in", "-"}, deep), "nested more than");
  std::ofstream(dir_ / "deep.json") << "{\"order\": 2, \"vectors\": " << std::string(52000, '[') << "}";
  expect_refused(run({"fit-zh", "--transfer", (dir_ / "deep.json").string()}), "nested more than");
  std::ofstream(dir_ / "deep.shtb") << "{\"format\": " << std::string(52000, '[');
  expect_refused(run({"inspect", (dir_ / "deep.shtb").string()}), "nested more than");
}

// The smallest inputs of each failure class a fuzzing round found in the readers and
// writers of later rounds: each exits 1 naming the problem, writes nothing and leaves
// its inputs as they were.

// A glTF of one triangle, its buffer in tri.bin beside it; `node` adds to its node's
// fields (a transform), `extras` goes into the asset object as written.
fs::path write_triangle_gltf(const fs::path& dir, const std::string& node, const std::string& extras = "null") {
  const float p[9] = {0, 0, 0, 1, 0, 0, 0, 0, -1};  // faces glTF +Y
  std::ofstream(dir / "tri.bin", std::ios::binary).write(reinterpret_cast<const char*>(p), sizeof p);
  std::ofstream(dir / "tri.gltf")
      << R"({"asset":{"version":"2.0","extras":)" << extras
      << R"(},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{)" << node
      << R"("mesh":0}],"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
      << R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,-1],"max":[1,0,0]}],)"
      << R"("bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"uri":"tri.bin","byteLength":36}]})";
  return dir / "tri.gltf";
}

TEST_F(CliUntrusted, DeepGltfExtrasAreRefusedBeforeTheParser) {
  const fs::path gltf = write_triangle_gltf(dir_, "", std::string(20000, '[') + std::string(20000, ']'));
  const std::string out = (dir_ / "o.shtb").string();
  expect_refused(run({"fit-zh", gltf.string(), "--rays", "8", "--out", out}), "nested more than");
  expect_refused(run({"fit-glossy", gltf.string(), "--rays", "8", "--out", out}), "nested more than");
  expect_refused(run({"render", gltf.string(), "--shading", "normals", "--out", (dir_ / "o.png").string()}),
                 "nested more than");
  // deform reads its table first (the mesh is loaded with the normals it records).
  const std::string fit = (dir_ / "fit.shtb").string();
  ASSERT_EQ(run({"fit-zh", mesh_.string(), "--rays", "8", "--order", "2", "--lobes", "1", "--out", fit}).exit_code, 0);
  expect_refused(run({"deform", fit, "--rest", gltf.string(), "--pose", gltf.string(), "--out", out}),
                 "nested more than");
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliUntrusted, CamerasAndThreadsOutsideTheirRangeAreRefused) {
  const std::string out = (dir_ / "o.png").string();
  expect_refused(run({"render", mesh_.string(), "--shading", "normals", "--fov", "1e-300", "--out", out}), "--fov");
  expect_refused(run({"render", mesh_.string(), "--shading", "normals", "--camera", "1e300,0,0,0,0,0,0,0,1", "--out",
                      out}),
                 "--camera");
  // Past Embree's ray range (about 1.8e18) it once aborted inside Embree (exit 134).
  expect_refused(
      run({"render", mesh_.string(), "--shading", "normals", "--camera", "1e19,0,0,0,0,0,0,0,1", "--out", out}),
      "--camera: every coordinate must be a finite number of magnitude at most 1e15");
  expect_refused(run({"fit-zh", "--transfer", (dir_ / "t.json").string(), "--threads", "-2"}),
                 "--threads must be");
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliUntrusted, ImportLightChecksEveryFieldAndRefusesOverflow) {
  const std::string json = (dir_ / "l.json").string();
  std::ofstream(dir_ / "raw.json") << R"({"order":1,"condon_shortley":"yes","coefficients":[[1,1,1]]})";
  expect_refused(run({"import-light", (dir_ / "raw.json").string(), "--format", "raw", "--json", json}),
                 "\"condon_shortley\" must be true or false");
  std::ofstream(dir_ / "raw2.json") << R"({"order":1,"normalization":3,"coefficients":[[1,1,1]]})";
  expect_refused(run({"import-light", (dir_ / "raw2.json").string(), "--format", "raw", "--json", json}),
                 "must be a string");
  // Finite in the file, beyond a double once converted (pi / A_2 > 1).
  std::string unity = R"({"SphericalHarmonicsL2":[)";
  for (int i = 0; i < 27; ++i) unity += std::string(i ? "," : "") + "1.7e308";
  std::ofstream(dir_ / "unity.json") << unity << "]}";
  expect_refused(run({"import-light", (dir_ / "unity.json").string(), "--format", "unity", "--json", json}),
                 "overflows");
  std::string three = R"({"object":{"intensity":1e308,"sh":[)";
  for (int i = 0; i < 27; ++i) three += std::string(i ? "," : "") + "1e308";
  std::ofstream(dir_ / "three.json") << three << "]}}";
  expect_refused(run({"import-light", (dir_ / "three.json").string(), "--format", "threejs", "--json", json}),
                 "overflows");
  EXPECT_FALSE(fs::exists(json));
}

// A 3DGS splat PLY of one splat, ASCII.
void write_splat(const fs::path& path, const std::string& x, const std::string& element_count = "1") {
  std::ofstream(path) << "ply\nformat ascii 1.0\nelement vertex " << element_count
                      << "\nproperty float x\nproperty float y\nproperty float z\n"
                         "property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\n"
                         "property float opacity\nproperty float scale_0\nproperty float scale_1\n"
                         "property float scale_2\nproperty float rot_0\nproperty float rot_1\n"
                         "property float rot_2\nproperty float rot_3\nend_header\n"
                      << x << " 2 3 0.1 0.2 0.3 0.5 -1 -1 -1 1 0 0 0\n";
}

TEST_F(CliUntrusted, SplatsNeverGetInfinityOrNan) {
  const fs::path in = dir_ / "s.ply", out = dir_ / "o.ply";
  write_splat(in, "1");
  expect_refused(run({"transform-splats", in.string(), "--quat", "1,0,0,0", "--translate", "1e39,0,0", "--out", out.string()}),
                 "overflows its type");
  expect_refused(run({"transform-splats", in.string(), "--quat", "1,0,0,0", "--scale", "1e300", "--out", out.string()}),
                 "overflows its type");
  write_splat(in, "3e38");
  expect_refused(run({"transform-splats", in.string(), "--quat", "1,0,0,0", "--scale", "2", "--out", out.string()}), "overflows its type");
  write_splat(in, "nan");
  expect_refused(run({"transform-splats", in.string(), "--quat", "0.6,0.8,0,0", "--out", out.string()}),
                 "splat 0: 'x' is not finite");
  write_splat(in, "1", "20abc");
  expect_refused(run({"transform-splats", in.string(), "--quat", "1,0,0,0", "--out", out.string()}),
                 "malformed element line");
  EXPECT_FALSE(fs::exists(out));
}

TEST_F(CliUntrusted, ImagesAndRendersNeverGetInfinity) {
  // An HDR of 4 x 2 texels at the largest RGBE value (2^128 x 255/256 each).
  {
    std::ofstream f(dir_ / "max.hdr", std::ios::binary);
    f << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 4\n" << std::string(4 * 8, '\xff');
  }
  // Its irradiance (pi times the radiance) is beyond a float.
  const std::string json = (dir_ / "l.json").string();
  expect_refused(run({"project-env", (dir_ / "max.hdr").string(), "--quantity", "irradiance", "--json", json,
                      "--render-back", (dir_ / "back.exr").string()}),
                 "is not finite");
  EXPECT_FALSE(fs::exists(json));
  EXPECT_FALSE(fs::exists(dir_ / "back.exr"));
  // A render under a light of 1e308.
  const fs::path tri = write_triangle_gltf(dir_, "");
  const CommandResult fit =
      run({"fit-zh", tri.string(), "--rays", "8", "--lobes", "1", "--out", (dir_ / "tri.shtb").string()});
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  std::ofstream(dir_ / "bright.json")
      << R"({"order":1,"quantity":"radiance","channels":["r","g","b"],"coefficients":[[1e308,1e308,1e308]]})";
  expect_refused(run({"render", tri.string(), "--fit", (dir_ / "tri.shtb").string(), "--light",
                      (dir_ / "bright.json").string(), "--out", (dir_ / "r.exr").string()}),
                 "the image's pixel (");
  EXPECT_FALSE(fs::exists(dir_ / "r.exr"));
  // A glTF scaled and placed at 1e39: single-precision rays cannot reach it, and its
  // --gltf output would hold inf positions.
  const fs::path far = write_triangle_gltf(dir_, R"("translation":[1e39,0,0],"scale":[1e39,1e39,1e39],)");
  expect_refused(run({"fit-zh", far.string(), "--rays", "8", "--lobes", "1", "--out", (dir_ / "f.shtb").string(),
                      "--gltf", (dir_ / "f.glb").string()}),
                 "lies beyond +-1e15");
  EXPECT_FALSE(fs::exists(dir_ / "f.glb"));
  EXPECT_FALSE(fs::exists(dir_ / "f.shtb"));
}

TEST_F(CliUntrusted, NoOutputMayNameAnInputOfAnyKind) {
  // A face set: --render-back onto one of the six faces.
  for (const char* face : {"px", "nx", "py", "ny", "pz", "nz"}) {
    std::ofstream f(dir_ / ("f_" + std::string(face) + ".hdr"), std::ios::binary);
    f << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 2 +X 2\n" << std::string(4 * 4, '\x80');
  }
  const std::uintmax_t face_size = fs::file_size(dir_ / "f_py.hdr");
  expect_refused(run({"project-env", (dir_ / "f_%s.hdr").string(), "--json", (dir_ / "l.json").string(),
                      "--render-back", (dir_ / "f_py.hdr").string()}),
                 "is the input");
  EXPECT_EQ(fs::file_size(dir_ / "f_py.hdr"), face_size);
  // deform: --out or --json naming its fit or a mesh.
  expect_refused(run({"deform", (dir_ / "t.json").string(), "--rest", mesh_.string(), "--pose",
                      mesh_.string(), "--out", (dir_ / "t.json").string()}),
                 "is the input");
  expect_refused(run({"deform", (dir_ / "t.json").string(), "--rest", mesh_.string(), "--pose",
                      mesh_.string(), "--out", (dir_ / "d.shtb").string(), "--json", mesh_.string()}),
                 "is the input");
  // gen-shader: --out naming its --lobes table.
  fs::copy_file(fs::path(SHTOOL_SOURCE_DIR) / "tables/zhf-shared-N4.shtb", dir_ / "lobes.shtb");
  const std::uintmax_t lobes_size = fs::file_size(dir_ / "lobes.shtb");
  expect_refused(run({"gen-shader", "--lang", "glsl", "--what", "zhf-rotate", "--order", "4", "--lobes",
                      (dir_ / "lobes.shtb").string(), "--out", (dir_ / "lobes.shtb").string()}),
                 "is the input");
  EXPECT_EQ(fs::file_size(dir_ / "lobes.shtb"), lobes_size);
  // fit-zh: --out naming a glTF's external buffer.
  const fs::path gltf = write_triangle_gltf(dir_, "");
  expect_refused(run({"fit-zh", gltf.string(), "--rays", "8", "--out", (dir_ / "tri.bin").string()}),
                 "(a file of the mesh)");
  EXPECT_EQ(fs::file_size(dir_ / "tri.bin"), 36u);
}

TEST_F(CliUntrusted, TinyImagesClaimingHugeSizesAreRefusedBeforeAllocating) {
  test::CommandOptions o;
  o.timeout_seconds = 120;
  // ASan reserves terabytes of address space for its shadow memory: the limit only
  // applies outside it (gcc says so with __SANITIZE_ADDRESS__, clang with __has_feature).
#if defined(__has_feature)
#if !__has_feature(address_sanitizer)
  o.address_space_bytes = std::uint64_t(1) << 30;  // 1 GiB
#endif
#elif !defined(__SANITIZE_ADDRESS__)
  o.address_space_bytes = std::uint64_t(1) << 30;  // 1 GiB
#endif
  auto project = [&](const fs::path& image) {
    return test::run_command({SHTOOL_EXE, "project-env", image.string(), "--json", (dir_ / "l.json").string()}, o);
  };
  // PNG: signature, IHDR of 16384 x 16384 8-bit RGB (CRC unchecked by the claim), IEND.
  {
    std::ofstream f(dir_ / "huge.png", std::ios::binary);
    const unsigned char png[] = {0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13, 'I', 'H', 'D', 'R',
                                 0, 0, 0x40, 0, 0, 0, 0x40, 0, 8, 2, 0, 0, 0, 0x0f, 0x8d, 0x6e, 0x2e,
                                 0, 0, 0, 0, 'I', 'D', 'A', 'T', 0x35, 0xaf, 0x06, 0x1e,
                                 0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60, 0x82};
    f.write(reinterpret_cast<const char*>(png), sizeof png);
  }
  expect_refused(project(dir_ / "huge.png"), "cannot be coded in a file of");
  // A side past the decoder's limit (2^25 x 2, within the texel count), and no IHDR.
  {
    std::string png = read_file(dir_ / "huge.png");
    write_file(dir_ / "wide.png",
               png.substr(0, 16) + std::string("\x02\x00\x00\x00\x00\x00\x00\x02", 8) + png.substr(24));
    write_file(dir_ / "no_ihdr.png", png.substr(0, 8) + png.substr(33));
  }
  expect_refused(project(dir_ / "wide.png"), "PNG: 33554432 x 2 texels: a side is longer than the 16777216");
  expect_refused(project(dir_ / "no_ihdr.png"), "PNG: the file does not begin with its 13-byte IHDR chunk");
  // JPEG: SOI, a baseline frame header of 16384 x 8192 with three components, EOI.
  auto jpeg = [&](const fs::path& path, bool with_scan) {
    std::string b = "\xff\xd8";
    b += std::string("\xff\xc0\x00\x11\x08\x20\x00\x40\x00\x03\x01\x11\x00\x02\x11\x00\x03\x11\x00", 19);
    if (with_scan) b += std::string("\xff\xda\x00\x0c\x03\x01\x00\x02\x00\x03\x00\x00\x3f\x00", 14);
    b += "\xff\xd9";
    std::ofstream(path, std::ios::binary) << b;
  };
  jpeg(dir_ / "huge.jpg", true);
  expect_refused(project(dir_ / "huge.jpg"), "cannot be coded in a file of");
  jpeg(dir_ / "noscan.jpg", false);
  expect_refused(project(dir_ / "noscan.jpg"), "JPEG: no scan");
  EXPECT_FALSE(fs::exists(dir_ / "l.json"));
}

}  // namespace
}  // namespace shtool
