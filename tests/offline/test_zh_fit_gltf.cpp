// zh_fit_glb on made-up meshes: the index type at the primitive-restart boundary and the
// refusal of fits that do not match the mesh (the end-to-end checks of the attributes are
// tests/cli/test_cli_fit_zh_gltf.cpp).
#include <tiny_gltf.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "common/input_error.h"
#include "fit/zh_fit_gltf.h"

namespace {

using shtool::fit::Mesh;
using shtool::ZhFitTable;

// `vertices` vertices on a line of triangles, each fitted with one lobe of order 2.
Mesh strip(std::size_t vertices) {
  Mesh m;
  for (std::size_t v = 0; v < vertices; ++v) {
    m.positions.emplace_back(double(v / 2), double(v % 2), 0.0);
    m.normals.emplace_back(0.0, 0.0, 1.0);
  }
  for (int v = 0; v + 2 < static_cast<int>(vertices); ++v) m.triangles.emplace_back(v, v + 1, v + 2);
  return m;
}

ZhFitTable<double> fits_of(std::size_t vertices) {
  ZhFitTable<double> fits;
  fits.order = 2;
  fits.lobes = 1;
  fits.vertices = vertices;
  fits.axes.assign(vertices, Eigen::Vector3d::UnitZ());
  for (std::size_t v = 0; v < vertices; ++v) fits.coeffs.insert(fits.coeffs.end(), {0.5, 0.25});
  fits.residual.assign(vertices, 0.0);
  fits.norm.assign(vertices, 1.0);
  return fits;
}

tinygltf::Model parse(const std::string& glb) {
  tinygltf::Model model;
  tinygltf::TinyGLTF loader;
  std::string err, warn;
  EXPECT_TRUE(loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(glb.data()),
                                          static_cast<unsigned int>(glb.size())))
      << err;
  return model;
}

TEST(ZhFitGltf, IndicesAreShortBelowTheirRestartValue) {
  for (const auto& [vertices, type] : {std::pair<std::size_t, int>{65534, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT},
                                       std::pair<std::size_t, int>{65535, TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT}}) {
    const std::vector<double> dc(vertices, 0.1);
    const tinygltf::Model m = parse(zh_fit_glb(strip(vertices), fits_of(vertices), dc, "test"));
    ASSERT_EQ(m.meshes.size(), 1u);
    const tinygltf::Accessor& indices = m.accessors.at(m.meshes[0].primitives.at(0).indices);
    EXPECT_EQ(indices.componentType, type) << vertices << " vertices";
    EXPECT_EQ(indices.count, (vertices - 2) * 3);
    EXPECT_EQ(m.asset.generator, "test");
  }
}

TEST(ZhFitGltf, FitsThatDoNotMatchTheMeshAreRefused) {
  const std::vector<double> dc(4, 0.1), short_dc(3, 0.1);
  EXPECT_THROW(zh_fit_glb(strip(4), fits_of(3), dc, "test"), shtool::InputError);
  EXPECT_THROW(zh_fit_glb(strip(4), fits_of(4), short_dc, "test"), shtool::InputError);
  EXPECT_NO_THROW(zh_fit_glb(strip(4), fits_of(4), dc, "test"));
}

TEST(ZhFitGltf, GreyIsTheDcOfAnOpenPlaneClamped) {
  const double y00 = 0.28209479177387814;
  EXPECT_DOUBLE_EQ(shtool::fit::transfer_dc_grey(y00), 1.0);
  EXPECT_DOUBLE_EQ(shtool::fit::transfer_dc_grey(0.5 * y00), 0.5);
  EXPECT_EQ(shtool::fit::transfer_dc_grey(2 * y00), 1.0);
  EXPECT_EQ(shtool::fit::transfer_dc_grey(-0.1), 0.0);
}

}  // namespace
