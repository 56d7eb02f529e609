// OBJ loading for fit-zh: triangulation, skipped vertices and faces, normals, and the
// errors for bad input. References are hand-built meshes whose answers are known.
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fit/mesh.h"

namespace {

using shtool::UpAxis;
using shtool::fit::NormalSource;

// The meshes here are written in shtool's frame (z up): read as written.
shtool::fit::Mesh load_as_written(const std::filesystem::path& path, NormalSource normals = NormalSource::automatic) {
  return shtool::fit::load_obj(path, normals, UpAxis::z);
}
using shtool::fit::Mesh;
using shtool::fit::MeshError;

std::filesystem::path write_obj(const std::string& name, const std::string& text) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "shtool_test_fit_mesh";
  std::filesystem::create_directories(dir);
  const std::filesystem::path path = dir / name;
  std::ofstream(path) << text;
  return path;
}

std::string load_error(const std::filesystem::path& path) {
  try {
    load_as_written(path);
  } catch (const MeshError& e) {
    return e.what();
  }
  return "";
}

// Normals are normalised sums; 1e-14 allows a few roundings of unit-size values.
constexpr double kNormalTol = 1e-14;

TEST(FitMesh, QuadIsTriangulatedWithUpNormals) {
  const Mesh m = load_as_written(write_obj("quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n"));
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.polygons_triangulated, 1u);
  EXPECT_FALSE(m.normals_from_file);
  for (const Eigen::Vector3d& n : m.normals) EXPECT_NEAR((n - Eigen::Vector3d::UnitZ()).norm(), 0.0, kNormalTol) << n.transpose();
}

// An OBJ is y-up by default (shtool = (X, -Z, Y) of its coordinates): a quad facing +y
// faces shtool's +z, its positions and file normals turned alike; z keeps it as written.
TEST(FitMesh, YUpFilesAreTurnedIntoShtoolsFrame) {
  const auto path = write_obj("quad_y.obj", "v 0 0 0\nv 0 0 -1\nv 1 0 -1\nv 1 0 0\nvn 0 3 0\nf 1//1 4//1 3//1 2//1\n");
  for (const NormalSource source : {NormalSource::file, NormalSource::computed}) {
    const Mesh m = shtool::fit::load_obj(path, source);
    EXPECT_EQ(m.up, UpAxis::y);
    for (const Eigen::Vector3d& n : m.normals) EXPECT_NEAR((n - Eigen::Vector3d::UnitZ()).norm(), 0.0, kNormalTol);
    EXPECT_EQ(m.positions[1], Eigen::Vector3d(0, 1, 0));  // the file's (0, 0, -1)
    EXPECT_EQ(m.positions[2], Eigen::Vector3d(1, 1, 0));
  }
  const Mesh z = load_as_written(path);
  EXPECT_EQ(z.up, UpAxis::z);
  for (const Eigen::Vector3d& n : z.normals) EXPECT_NEAR((n - Eigen::Vector3d::UnitY()).norm(), 0.0, kNormalTol);
  EXPECT_EQ(z.positions[1], Eigen::Vector3d(0, 0, -1));
  // The two maps are each other's inverse, exactly.
  const Eigen::Vector3d p(0.1, -2.5, 3e-7);
  EXPECT_EQ(shtool::to_y_up(shtool::from_y_up(p)), p);
  EXPECT_EQ(shtool::to_y_up_matrix() * p, shtool::to_y_up(p));
  EXPECT_NEAR(shtool::to_y_up_matrix().determinant(), 1.0, 0.0);
}

TEST(FitMesh, UnreferencedVerticesAreSkippedAndCounted) {
  const Mesh m = load_as_written(write_obj("unref.obj", "v 9 9 9\nv 0 0 0\nv 1 0 0\nv 5 5 5\nv 0 1 0\nf 2 3 5\n"));
  EXPECT_EQ(m.obj_vertices, 5u);
  EXPECT_EQ(m.unreferenced_vertices, 2u);
  ASSERT_EQ(m.positions.size(), 3u);
  EXPECT_EQ(m.source_index, (std::vector<std::uint32_t>{1, 2, 4}));
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
}

TEST(FitMesh, DegenerateFacesAreSkippedAndCounted) {
  // A repeated index, a zero-area (collinear) triangle and a good one.
  const Mesh m = load_as_written(write_obj("degen.obj",
                                    "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 2\nf 1 2 3\nf 1 2 4\n"));
  EXPECT_EQ(m.degenerate_faces, 2u);
  EXPECT_EQ(m.triangles.size(), 1u);
  EXPECT_EQ(m.unreferenced_vertices, 1u);  // vertex 3 only appears in the collinear face
}

TEST(FitMesh, CubeCornerNormalsAreAngleWeighted) {
  // Each corner of a cube touches three faces split into one or two triangles; angle
  // weighting gives every face the weight pi/2 there, so the normal is the diagonal
  // (+-1, +-1, +-1)/sqrt(3) exactly. Area weighting would tilt it toward faces
  // contributing two triangles.
  const std::string cube =
      "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
      "f 1 4 3\nf 1 3 2\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\nf 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n";
  const Mesh m = load_as_written(write_obj("cube.obj", cube));
  ASSERT_EQ(m.positions.size(), 8u);
  for (std::size_t i = 0; i < 8; ++i) {
    const Eigen::Vector3d expected = m.positions[i] / std::sqrt(3.0);
    EXPECT_NEAR((m.normals[i] - expected).norm(), 0.0, kNormalTol) << "vertex " << i << ": " << m.normals[i].transpose();
  }
}

TEST(FitMesh, FileNormalsAreUsedWhenComplete) {
  const Mesh m = load_as_written(write_obj("vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 1 0 0\nf 1//1 2//2 3//1\n"));
  EXPECT_TRUE(m.normals_from_file);
  EXPECT_NEAR((m.normals[0] - Eigen::Vector3d::UnitZ()).norm(), 0.0, kNormalTol);  // normalised from length 2
  EXPECT_NEAR((m.normals[1] - Eigen::Vector3d::UnitX()).norm(), 0.0, kNormalTol);
  const Mesh c = load_as_written(write_obj("vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 2\nvn 1 0 0\nf 1//1 2//2 3//1\n"),
                          shtool::fit::NormalSource::computed);
  EXPECT_NEAR((c.normals[1] - Eigen::Vector3d::UnitZ()).norm(), 0.0, kNormalTol);
}

TEST(FitMesh, BadInputGivesClearErrors) {
  EXPECT_NE(load_error("/nonexistent/shtool/none.obj").find("no such file"), std::string::npos);
  // {file name, OBJ text, what the message must say}
  const std::vector<std::array<std::string, 3>> cases = {
      {"nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: non-finite coordinate"},
      {"inf.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n", "non-finite"},
      {"range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n", "refers to vertex 7, but the file has 3 vertices"},
      {"qrange.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3 99\n", "refers to vertex 99"},
      {"none.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"},
      {"flat.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n", "no usable triangle"},
      // tinyobjloader would read these as 0: a hexadecimal coordinate, a texture coordinate
      // that is not a finite number.
      {"hex.obj", "v 0 0 0\nv 0x10 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: missing or unreadable coordinate"},
      {"uvnan.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt nan 0\nf 1/1 2/1 3/1\n", "line 4: non-finite coordinate"},
      {"uvinf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.5 inf\nf 1/1 2/1 3/1\n", "line 4: non-finite coordinate"},
      {"uvword.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt u 0\nf 1/1 2/1 3/1\n", "line 4: missing or unreadable"},
      // A file cut inside its last face line: tinyobjloader would drop the face silently.
      {"cut.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 4",
       "line 6: a face needs at least 3 vertices, 'f 4' has 1"},
      {"two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 # a comment 3\n", "line 5: a face needs at least 3"},
      // Compressed meshes are named as such, not read as garbled face lines.
      {"spot.obj.gz", std::string("\x1f\x8b\x08\x00garbage", 12), "is gzip-compressed; shtool reads OBJ and glTF"},
      {"spot.obj.zst", "\x28\xb5\x2f\xfd rest", "is zstd-compressed"},
  };
  for (const auto& [name, text, needle] : cases) {
    const std::string error = load_error(write_obj(name, text));
    EXPECT_NE(error.find(needle), std::string::npos) << name << ": " << error;
  }
  const std::string empty = load_error(write_obj("empty.obj", ""));
  EXPECT_FALSE(empty.empty());
  // One, two or three texture coordinates are all a vt line may hold.
  for (const char* vt : {"vt 0.5", "vt 0.5 0.25", "vt 0.5 0.25 0 ", "vt 1e-3\t2E+0"}) {
    const std::string text = std::string("v 0 0 0\nv 1 0 0\nv 0 1 0\n") + vt + "\nf 1/1 2/1 3/1\n";
    EXPECT_EQ(load_error(write_obj("uv_ok.obj", text)), "") << vt;
  }
}

}  // namespace
