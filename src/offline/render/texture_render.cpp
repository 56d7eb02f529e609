#include "render/texture_render.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "common/input_error.h"
#include "common/input_file.h"
#include "common/parallel_for.h"
#include "fit/texture_bake.h"
#include "shtool/table.h"
#include "shtool/zh_fit_table.h"
#include "shtool/zh_shading.h"

namespace shtool::render {
namespace {

lighting::ChannelImage read_map(const std::filesystem::path& path, int resolution,
                                const std::vector<std::string>& names) {
  lighting::ChannelImage image =
      lighting::decode_exr_channels(read_input_file(path, "texture map"), path, lighting::kMaxImageTexels, names);
  if (image.width != resolution || image.height != resolution)
    throw InputError(path.string() + ": " + std::to_string(image.width) + " x " + std::to_string(image.height) +
                     ", but the table's bake is " + std::to_string(resolution) + " x " + std::to_string(resolution));
  // A NaN or infinity would shade as NaN pixels without a word.
  for (std::size_t i = 0; i < image.texels.size(); ++i)
    if (!std::isfinite(image.texels[i]))
      throw InputError(path.string() + ": channel '" + names[i % names.size()] + "' of texel " +
                       std::to_string(i / names.size()) + " is not finite");
  return image;
}

}  // namespace

std::optional<TextureBake> texture_bake_of(const std::filesystem::path& fit, const Table& table) {
  const nlohmann::json meta = nlohmann::json::parse(table.meta, nullptr, false);
  if (!meta.is_object() || !meta.contains("texture")) return std::nullopt;
  const nlohmann::json& t = meta["texture"];
  const auto number = [&](const nlohmann::json& j, const char* key) {
    if (!j.is_object() || !j.contains(key) || !j[key].is_number_integer())
      throw InputError("--fit " + fit.string() + ": meta." + (&j == &t ? "texture." : "") + key + " is missing");
    return j[key].get<long long>();
  };
  TextureBake bake;
  const long long res = number(t, "resolution"), lobes = number(meta, "lobes");
  if (res < 1 || res > fit::kMaxTextureResolution || lobes < 1 || lobes > 64)
    throw InputError("--fit " + fit.string() + ": meta.texture.resolution or meta.lobes out of range");
  const long long uv_crc = number(t, "uv_crc32");
  if (uv_crc < 0 || uv_crc > 0xFFFFFFFFll) throw InputError("--fit " + fit.string() + ": meta.texture.uv_crc32 out of range");
  bake.uv_crc32 = static_cast<std::uint32_t>(uv_crc);
  bake.resolution = static_cast<int>(res);
  bake.lobes = static_cast<int>(lobes);
  bake.order = table.order;
  for (const char* key : {"dc_linear_map", "lobes_map"})
    if (!t.contains(key) || !t[key].is_string() || std::filesystem::path(t[key].get<std::string>()).has_parent_path())
      throw InputError("--fit " + fit.string() + ": meta.texture." + key + " must name a file beside the table");
  const std::filesystem::path folder = fit.parent_path();
  bake.dc_linear = read_map(folder / t["dc_linear_map"].get<std::string>(), bake.resolution, fit::dc_linear_channels());
  bake.lobes_map = read_map(folder / t["lobes_map"].get<std::string>(), bake.resolution,
                            fit::lobe_channels(bake.lobes, bake.order));
  return bake;
}

lighting::Image shade_texture_bake(const TextureBake& bake, const fit::Mesh& mesh, const lighting::Lighting& light,
                                   int width, int height, const std::vector<int>& triangle,
                                   const std::vector<double>& w1, const std::vector<double>& w2,
                                   int zh_table_resolution, int threads) {
  if (mesh.uvs.empty())
    throw InputError("the mesh has no texture coordinates: a texture-space bake is sampled at the hit's UV");
  const int res = bake.resolution, order = bake.order, lobes = bake.lobes;
  const std::size_t n2 = static_cast<std::size_t>(order) * order;
  const std::size_t kl = bake.lobes_map.names.size();
  // One lighting vector per colour channel, padded or truncated to the bake's order.
  std::vector<std::vector<double>> e;
  for (int c = 0; c < 3; ++c) e.push_back(lighting::light_channel(light, c, order));
  std::vector<std::optional<ZhLightTable<double>>> tables(3);
  if (zh_table_resolution > 0)
    for (int c = 0; c < 3; ++c) tables[c].emplace(order, e[c], zh_table_resolution);

  lighting::Image image{width, height, 4, std::vector<float>(std::size_t(width) * height * 4, 0.0f)};
  parallel_for(static_cast<std::size_t>(height), threads, [&](std::size_t y) {
    std::vector<Vec3<double>> axes(lobes);
    std::vector<double> coeffs(static_cast<std::size_t>(lobes) * order);
    for (int x = 0; x < width; ++x) {
      const std::size_t p = y * width + x;
      if (triangle[p] < 0) continue;
      const auto& uv = mesh.uvs[triangle[p]];
      const Eigen::Vector2d at = (1.0 - w1[p] - w2[p]) * uv[0] + w1[p] * uv[1] + w2[p] * uv[2];
      // Texel coordinates with y down; texel centres at integer + 1/2.
      const double tx = at.x() * res, ty = (1.0 - at.y()) * res;
      // DC and linear: bilinear between the four nearest centres, clamped at the border.
      const double fx = tx - 0.5, fy = ty - 0.5;
      const double x0f = std::floor(fx), y0f = std::floor(fy);
      const double ax = fx - x0f, ay = fy - y0f;
      const auto clamp = [res](double v) { return static_cast<int>(std::clamp(v, 0.0, double(res - 1))); };
      const int xs[2] = {clamp(x0f), clamp(x0f + 1)}, ys[2] = {clamp(y0f), clamp(y0f + 1)};
      double band01[4] = {0, 0, 0, 0};
      for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i) {
          const double w = (i ? ax : 1 - ax) * (j ? ay : 1 - ay);
          const float* d = &bake.dc_linear.texels[(std::size_t(ys[j]) * res + xs[i]) * 5];
          for (int k = 0; k < 4; ++k) band01[k] += w * d[k];
        }
      // Lobes: the texel the hit lies in. Bands 0 and 1 come from the filtered map.
      const float* o = &bake.lobes_map.texels[(std::size_t(clamp(std::floor(ty))) * res + clamp(std::floor(tx))) * kl];
      for (int k = 0; k < lobes; ++k, o += 3 + order) {
        const Eigen::Vector3d a(o[0], o[1], o[2]);
        axes[k] = a.norm() > 0 ? Eigen::Vector3d(a.normalized()) : Eigen::Vector3d::UnitZ();
        for (int l = 0; l < order; ++l) coeffs[k * order + l] = l < 2 ? 0.0 : o[3 + l];
      }
      float* px = &image.texels[p * 4];
      for (int c = 0; c < 3; ++c) {
        double r = tables[c] ? tables[c]->shade(axes, coeffs) : zh_shade_exact<double>(e[c], axes, coeffs);
        for (std::size_t i = 0; i < 4 && i < n2; ++i) r += band01[i] * e[c][i];
        px[c] = static_cast<float>(r);
      }
      px[3] = 1.0f;
    }
  });
  return image;
}

}  // namespace shtool::render
