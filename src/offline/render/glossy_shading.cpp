#include "render/glossy_shading.h"

#include <string>

#include "common/input_error.h"
#include "common/parallel_for.h"
#include "fit/deformation.h"

namespace shtool::render {

GlossyFit<double> glossy_fit_for_mesh(GlossyFit<double> fit, const fit::Mesh& mesh, const std::string& what) {
  if (fit.vertices != mesh.positions.size())
    throw InputError(what + ": " + std::to_string(fit.vertices) + " vertices for a mesh of " +
                     std::to_string(mesh.positions.size()) + " (was it fitted on another mesh?)");
  if (!fit.vertex_index.empty() &&
      !std::equal(fit.vertex_index.begin(), fit.vertex_index.end(), mesh.source_index.begin()))
    throw InputError(what + ": its vertices are not the mesh's, in the mesh's order (was it fitted on another mesh?)");
  return fit;
}

GlossyFit<double> deform_glossy_fit(const GlossyFit<double>& fit, const std::vector<Eigen::Matrix3d>& rotations) {
  std::vector<Eigen::Matrix3d> per_row;
  per_row.reserve(fit.rows.vertices);
  for (std::size_t v = 0; v < fit.vertices; ++v)
    for (int j = 0; j < fit.terms; ++j) per_row.push_back(rotations[v]);
  GlossyFit<double> out = fit;
  out.rows = fit::deform_fit(fit.rows, per_row);
  return out;
}

lighting::Image glossy_panel(const PixelHits& hits, const fit::Mesh& mesh, const std::vector<Eigen::Matrix3d>& frames,
                             const GlossyFit<double>& fit, const lighting::Lighting& light, const Eigen::Vector3d& eye,
                             int threads) {
  const std::size_t vertices = mesh.positions.size(), nb = static_cast<std::size_t>(fit.terms);
  // r_j per vertex and channel: rows[(v * 3 + c) * n_b + j].
  std::vector<double> rows(vertices * 3 * nb);
  for (int c = 0; c < 3; ++c) {
    const std::vector<double> e = lighting::light_channel(light, c, fit.rows.order);
    parallel_for(vertices, threads, [&](std::size_t v) {
      fit.row_radiance(e, v, std::span<double>(&rows[(v * 3 + c) * nb], nb));
    });
  }
  lighting::Image image{hits.width, hits.height, 4,
                        std::vector<float>(std::size_t(hits.width) * hits.height * 4, 0.0f)};
  parallel_for(static_cast<std::size_t>(hits.height), threads, [&](std::size_t y) {
    double u[kMaxGlossyTerms];
    for (int x = 0; x < hits.width; ++x) {
      const std::size_t p = y * hits.width + x;
      if (hits.triangle[p] < 0) continue;
      const Eigen::Vector3i& tri = mesh.triangles[hits.triangle[p]];
      const double w[3] = {1.0 - hits.w1[p] - hits.w2[p], hits.w1[p], hits.w2[p]};
      const Eigen::Vector3d point =
          w[0] * mesh.positions[tri[0]] + w[1] * mesh.positions[tri[1]] + w[2] * mesh.positions[tri[2]];
      const Eigen::Vector3d to_eye = (eye - point).normalized();
      double rgb[3] = {0, 0, 0};
      for (int k = 0; k < 3; ++k) {
        const std::size_t v = static_cast<std::size_t>(tri[k]);
        fit.view_factors_at(frames[v].transpose() * to_eye, std::span<double>(u, nb));
        for (int c = 0; c < 3; ++c) {
          double r = 0;
          for (std::size_t j = 0; j < nb; ++j) r += u[j] * rows[(v * 3 + c) * nb + j];
          rgb[c] += w[k] * r;
        }
      }
      float* px = &image.texels[p * 4];
      for (int c = 0; c < 3; ++c) px[c] = static_cast<float>(rgb[c]);
      px[3] = 1.0f;
    }
  });
  return image;
}

}  // namespace shtool::render
