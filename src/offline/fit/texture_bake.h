// Texture-space bakes (fit-zh --texture RES): the transfer simulated at the texel centres
// of the mesh's UV atlas instead of at its vertices, fitted as for vertices, and stored as
// [4]'s LDPRT textures (Sec. 7): DC and linear SH in one bilinearly filterable map, the
// ZH lobes in another that is point-sampled. docs/fit-zh.md describes the files.
//
// Texel (x, y) of a RES x RES atlas, rows top first, has its centre at
// u = (x + 1/2) / RES, v = 1 - (y + 1/2) / RES (Mesh::uvs: v up), index y * RES + x.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fit/mesh.h"
#include "lighting/image_io.h"
#include "shtool/zh_fit_table.h"

namespace shtool::fit {

// 4096^2 texels hold 16.7M rows of fits: far beyond what a bake finishes in hours.
inline constexpr int kMaxTextureResolution = 4096;
// Rings of texels around the covered ones that copy their nearest covered texel, so that
// bilinear filtering (which reads one texel beyond) and a mip level or two never pull in
// an empty texel at a UV seam.
inline constexpr int kGutterTexels = 2;

// The covered texels, in increasing texel index, and the surface point each stands for.
struct TexelSamples {
  int resolution = 0;
  std::vector<std::uint64_t> texel;          // y * resolution + x
  std::vector<std::uint32_t> triangle;       // the mesh triangle whose UV image holds the centre
  std::vector<Eigen::Vector3d> barycentric;  // of the centre in that triangle's UV image
  std::vector<Eigen::Vector3d> positions;    // the barycentric point of the triangle
  std::vector<Eigen::Vector3d> normals;      // the vertex normals interpolated, normalised
};

// Every texel whose centre lies in the UV image of a triangle (edges included, so that
// texels on a shared edge are covered once). Where UV islands overlap, the first triangle
// in mesh order that holds a centre takes it. Throws InputError (naming `path`) when the
// mesh has no texture coordinates, the resolution is outside 1..kMaxTextureResolution, or
// no texel centre falls in any triangle.
TexelSamples rasterize_texels(const Mesh& mesh, int resolution, const std::filesystem::path& path);

// Per texel of the atlas: the row (index into samples.texel) whose values it holds after
// `rings` rings of dilation, -1 where none. A covered texel holds its own row; an
// uncovered texel within Chebyshev distance `rings` of a covered one holds the nearest
// (Euclidean, in texels) covered texel's row, found ring by ring through the 8
// neighbours, ties to the first neighbour in row-major order.
std::vector<std::int64_t> dilate_gutter(const TexelSamples& samples, int rings = kGutterTexels);

// Channel names of the two maps. dc_linear: "sh0".."sh3" (flat SH index l(l+1)+m of the
// fitted vector's bands 0 and 1) and "A". lobes: "lobe<k>.axis.x/y/z", "lobe<k>.g<l>"
// (g*_l, l < order) for every lobe k, and "A". A is 1 on a baked texel, 0.5 on a gutter
// texel (a copy), 0 elsewhere (every other channel 0 there too).
std::vector<std::string> dc_linear_channels();
std::vector<std::string> lobe_channels(int lobes, int order);

struct TextureMaps {
  lighting::ChannelImage dc_linear, lobes;
};

// The maps of fits whose row r is texel samples.texel[r]: bands 0 and 1 of the fitted
// SH vector (direct coefficients plus the lobes' projections) and the lobes themselves,
// as float.
TextureMaps texture_maps(const TexelSamples& samples, const ZhFitTable<double>& fits);

// Where the maps of a table at `out` go: <out without extension>.dc_linear.exr and
// <...>.lobes.exr.
std::filesystem::path dc_linear_map_path(const std::filesystem::path& out);
std::filesystem::path lobes_map_path(const std::filesystem::path& out);

}  // namespace shtool::fit
