// render of a texture-space bake (fit-zh --texture): the exit radiance of each pixel from
// the LDPRT textures at the hit's interpolated UV, [4] Sec. 7: the DC and linear map
// filtered bilinearly, the ZH lobes point-sampled (the nearest texel), shaded with Eq. 13
// (or its tabulated form, Eq. 24-25) in double.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

#include "fit/mesh.h"
#include "lighting/image_io.h"
#include "lighting/lighting_output.h"
#include "shtool/table.h"

namespace shtool::render {

struct TextureBake {
  int resolution = 0, order = 0, lobes = 0;
  std::uint32_t uv_crc32 = 0;  // fit/mesh.h uv_layout_crc32 of the mesh it was baked on
  lighting::ChannelImage dc_linear, lobes_map;  // channels in fit/texture_bake.h's order
};

// The bake of the zh-fit `table` read from `fit`, its maps read from the folder of the
// table under the names its meta records; none when the table is a per-vertex bake.
// Throws InputError naming the file: a missing or unreadable map, a map whose size or
// channels do not match the table.
std::optional<TextureBake> texture_bake_of(const std::filesystem::path& fit, const Table& table);

// RGBA image (alpha: coverage) of the pixels' hits (triangle -1: none; w1, w2 the hit's
// barycentric weights of corners 1 and 2). The mesh needs its UVs (InputError otherwise).
// zh_table_resolution > 0 shades with ZhLightTable of that resolution.
lighting::Image shade_texture_bake(const TextureBake& bake, const fit::Mesh& mesh, const lighting::Lighting& light,
                                   int width, int height, const std::vector<int>& triangle,
                                   const std::vector<double>& w1, const std::vector<double>& w2,
                                   int zh_table_resolution, int threads);

}  // namespace shtool::render
