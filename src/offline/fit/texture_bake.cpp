#include "fit/texture_bake.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <string>

#include "common/input_error.h"
#include "shtool/sh.h"

namespace shtool::fit {
namespace {

// Barycentric slack for a centre on an edge: the two triangles sharing the edge compute
// their weights from different corners, and one of them must still take the texel.
constexpr double kEdgeSlack = 1e-12;

}  // namespace

TexelSamples rasterize_texels(const Mesh& mesh, int resolution, const std::filesystem::path& path) {
  if (resolution < 1 || resolution > kMaxTextureResolution)
    throw InputError("--texture " + std::to_string(resolution) + ": the resolution must be in 1.." +
                     std::to_string(kMaxTextureResolution));
  if (mesh.uvs.empty() || mesh.uvs.size() != mesh.triangles.size())
    throw InputError(path.string() + ": no texture coordinates (OBJ 'vt' on every face corner, glTF TEXCOORD_0 on "
                                     "every primitive): --texture bakes per texel of the UV atlas");
  const std::size_t texels = std::size_t(resolution) * resolution;
  const double res = resolution;
  // Triangle t's corners in texel units, y down: the centre of texel (x, y) is
  // (x + 1/2, y + 1/2).
  auto corners = [&](std::size_t t) {
    std::array<Eigen::Vector2d, 3> q;
    for (int c = 0; c < 3; ++c) q[c] = Eigen::Vector2d(mesh.uvs[t][c].x() * res, (1.0 - mesh.uvs[t][c].y()) * res);
    return q;
  };
  auto signed_area = [](const std::array<Eigen::Vector2d, 3>& q) {
    return (q[1] - q[0]).x() * (q[2] - q[0]).y() - (q[1] - q[0]).y() * (q[2] - q[0]).x();
  };
  // Barycentric weights of texel (x, y)'s centre.
  auto weights = [](const std::array<Eigen::Vector2d, 3>& q, double area, int x, int y) {
    const Eigen::Vector2d p(x + 0.5, y + 0.5);
    auto edge = [&](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
      return ((b - a).x() * (p - a).y() - (b - a).y() * (p - a).x()) / area;
    };
    return Eigen::Vector3d(edge(q[1], q[2]), edge(q[2], q[0]), edge(q[0], q[1]));
  };
  // The owner only (4 bytes a texel): the weights are recomputed for the covered texels.
  std::vector<std::int32_t> owner(texels, -1);
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const std::array<Eigen::Vector2d, 3> q = corners(t);
    const double area = signed_area(q);
    if (!(std::abs(area) > 0)) continue;  // a UV triangle of no area holds no centre
    const double lo_x = std::min({q[0].x(), q[1].x(), q[2].x()}), hi_x = std::max({q[0].x(), q[1].x(), q[2].x()});
    const double lo_y = std::min({q[0].y(), q[1].y(), q[2].y()}), hi_y = std::max({q[0].y(), q[1].y(), q[2].y()});
    const int x0 = static_cast<int>(std::clamp(std::ceil(lo_x - 0.5), 0.0, res - 1));
    const int x1 = static_cast<int>(std::clamp(std::floor(hi_x - 0.5), -1.0, res - 1));
    const int y0 = static_cast<int>(std::clamp(std::ceil(lo_y - 0.5), 0.0, res - 1));
    const int y1 = static_cast<int>(std::clamp(std::floor(hi_y - 0.5), -1.0, res - 1));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const std::size_t index = std::size_t(y) * resolution + x;
        if (owner[index] >= 0) continue;  // overlapping islands: the first triangle keeps it
        if (weights(q, area, x, y).minCoeff() >= -kEdgeSlack) owner[index] = static_cast<std::int32_t>(t);
      }
  }
  TexelSamples s;
  s.resolution = resolution;
  for (std::size_t index = 0; index < texels; ++index) {
    if (owner[index] < 0) continue;
    const std::array<Eigen::Vector2d, 3> q = corners(owner[index]);
    const Eigen::Vector3d raw = weights(q, signed_area(q), static_cast<int>(index % resolution),
                                        static_cast<int>(index / resolution));
    // Within the slack of an edge a weight can be a hair below 0: the point stays on the triangle.
    const Eigen::Vector3d w = raw.cwiseMax(0.0) / raw.cwiseMax(0.0).sum();
    const Eigen::Vector3i& tri = mesh.triangles[owner[index]];
    const Eigen::Vector3d p =
        w[0] * mesh.positions[tri[0]] + w[1] * mesh.positions[tri[1]] + w[2] * mesh.positions[tri[2]];
    Eigen::Vector3d n = w[0] * mesh.normals[tri[0]] + w[1] * mesh.normals[tri[1]] + w[2] * mesh.normals[tri[2]];
    // Opposite vertex normals (a crease folded back) can cancel: the face's normal then.
    if (!(n.norm() > 1e-12))
      n = (mesh.positions[tri[1]] - mesh.positions[tri[0]]).cross(mesh.positions[tri[2]] - mesh.positions[tri[0]]);
    s.texel.push_back(index);
    s.triangle.push_back(static_cast<std::uint32_t>(owner[index]));
    s.barycentric.push_back(w);
    s.positions.push_back(p);
    s.normals.push_back(n.normalized());
  }
  if (s.texel.empty())
    throw InputError(path.string() + ": no texel centre of the " + std::to_string(resolution) + " x " +
                     std::to_string(resolution) + " atlas lies in a UV triangle (UVs outside [0, 1], or too small "
                     "for this resolution)");
  return s;
}

std::vector<std::int64_t> dilate_gutter(const TexelSamples& samples, int rings) {
  const int res = samples.resolution;
  const std::size_t texels = std::size_t(res) * res;
  std::vector<std::int64_t> row(texels, -1);
  for (std::size_t r = 0; r < samples.texel.size(); ++r) row[samples.texel[r]] = static_cast<std::int64_t>(r);
  std::vector<std::int64_t> next;
  for (int ring = 0; ring < rings; ++ring) {
    // Each ring reads the previous ring's state only, so the result does not depend on
    // the scan order.
    next = row;
    for (int y = 0; y < res; ++y)
      for (int x = 0; x < res; ++x) {
        const std::size_t index = std::size_t(y) * res + x;
        if (row[index] >= 0) continue;
        std::int64_t best = -1;
        double best_d = std::numeric_limits<double>::infinity();
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = x + dx, ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= res || ny >= res) continue;
            const std::int64_t r = row[std::size_t(ny) * res + nx];
            if (r < 0) continue;
            const std::uint64_t src = samples.texel[r];
            const double sx = static_cast<double>(src % res) - x, sy = static_cast<double>(src / res) - y;
            const double d = sx * sx + sy * sy;
            if (d < best_d) {
              best_d = d;
              best = r;
            }
          }
        next[index] = best;
      }
    row.swap(next);
  }
  return row;
}

std::vector<std::string> dc_linear_channels() { return {"sh0", "sh1", "sh2", "sh3", "A"}; }

std::vector<std::string> lobe_channels(int lobes, int order) {
  std::vector<std::string> names;
  for (int k = 0; k < lobes; ++k) {
    const std::string lobe = "lobe" + std::to_string(k);
    for (const char* c : {".axis.x", ".axis.y", ".axis.z"}) names.push_back(lobe + c);
    for (int l = 0; l < order; ++l) names.push_back(lobe + ".g" + std::to_string(l));
  }
  names.push_back("A");
  return names;
}

TextureMaps texture_maps(const TexelSamples& samples, const ZhFitTable<double>& fits) {
  const int res = samples.resolution;
  const std::size_t texels = std::size_t(res) * res;
  const int order = fits.order, lobes = fits.lobes;
  TextureMaps maps;
  maps.dc_linear = {res, res, dc_linear_channels(), {}};
  maps.lobes = {res, res, lobe_channels(lobes, order), {}};
  const std::size_t kd = maps.dc_linear.names.size(), kl = maps.lobes.names.size();
  // Bands 0 and 1 of every row, computed once: the gutter copies them.
  const int low = std::min(4, sh_count(order));
  std::vector<double> band01(fits.vertices * 4, 0.0);
  std::vector<double> y(sh_count(std::min(order, 2)));
  for (std::size_t r = 0; r < fits.vertices; ++r) {
    const auto direct = fits.direct_of(r);
    for (std::size_t i = 0; i < direct.size() && i < 4; ++i) band01[r * 4 + i] += direct[i];
    for (int k = 0; k < lobes; ++k) {
      eval_sh<double>(std::min(order, 2), fits.axes_of(r)[k], y);
      for (int i = 0; i < low; ++i) {
        const int l = i == 0 ? 0 : 1;
        band01[r * 4 + i] += fits.coeffs_of(r)[k * order + l] * y[i];
      }
    }
  }
  maps.dc_linear.texels.assign(texels * kd, 0.0f);
  maps.lobes.texels.assign(texels * kl, 0.0f);
  const std::vector<std::int64_t> row = dilate_gutter(samples);
  for (std::size_t index = 0; index < texels; ++index) {
    const std::int64_t r = row[index];
    if (r < 0) continue;
    const float alpha = samples.texel[r] == index ? 1.0f : 0.5f;
    float* d = &maps.dc_linear.texels[index * kd];
    for (int i = 0; i < 4; ++i) d[i] = static_cast<float>(band01[r * 4 + i]);
    d[4] = alpha;
    float* o = &maps.lobes.texels[index * kl];
    for (int k = 0; k < lobes; ++k) {
      for (int c = 0; c < 3; ++c) *o++ = static_cast<float>(fits.axes_of(r)[k][c]);
      for (int l = 0; l < order; ++l) *o++ = static_cast<float>(fits.coeffs_of(r)[k * order + l]);
    }
    *o = alpha;
  }
  return maps;
}

namespace {
std::filesystem::path beside(const std::filesystem::path& out, const char* suffix) {
  return out.parent_path() / (out.stem().string() + suffix);
}
}  // namespace

std::filesystem::path dc_linear_map_path(const std::filesystem::path& out) { return beside(out, ".dc_linear.exr"); }
std::filesystem::path lobes_map_path(const std::filesystem::path& out) { return beside(out, ".lobes.exr"); }

}  // namespace shtool::fit
