#include "fit/zh_fit_table.h"

#include "common/table_writer.h"

#include <cmath>

namespace shtool::fit {

double normalized_rms(const std::vector<ZhFit>& fits) {
  double sum_res = 0, sum_norm = 0;
  for (const ZhFit& f : fits) {
    sum_res += f.residual * f.residual;
    sum_norm += f.norm * f.norm;
  }
  return sum_norm > 0 ? std::sqrt(sum_res / sum_norm) : 0.0;
}

Table zh_fit_table(const std::vector<ZhFit>& fits, int order, int lobes,
                   const std::vector<std::uint32_t>& vertex_index, nlohmann::json meta,
                   const nlohmann::json& generator) {
  const std::size_t count = fits.size();
  const std::size_t nl = static_cast<std::size_t>(lobes);
  std::vector<double> axes(count * nl * 3), coeffs(count * nl * order), residual(count), norm(count);
  const std::size_t nd = fits.empty() ? 0 : fits[0].direct.size();
  std::vector<double> direct(count * nd);
  for (std::size_t v = 0; v < count; ++v) {
    for (std::size_t k = 0; k < nl; ++k) {
      for (int c = 0; c < 3; ++c) axes[(v * nl + k) * 3 + c] = fits[v].lobes[k].axis[c];
      for (int l = 0; l < order; ++l) coeffs[(v * nl + k) * order + l] = fits[v].lobes[k].coeffs[l];
    }
    residual[v] = fits[v].residual;
    norm[v] = fits[v].norm;
    for (std::size_t d = 0; d < nd; ++d) direct[v * nd + d] = fits[v].direct[d];
  }
  meta["vectors"] = count;
  meta["lobes"] = lobes;
  meta["normalized_rms"] = normalized_rms(fits);
  meta["layout"] = "axes[v][k] unit axis, coeffs[v][k][l] = g*_l (lobe k adds g*_l y_l^m(axis) to SH (l,m)); "
                   "residual[v] = ||fit - t||, norm[v] = ||t||";
  Table table = new_table("zh-fit", order, generator, meta);
  // 1.1 added meta "shard" (partial tables of a sharded bake, docs/fit-zh.md).
  table.kind_version = "1.1";
  const auto V = static_cast<std::int64_t>(count), N = static_cast<std::int64_t>(nl);
  table.arrays.push_back(TableArray::from<double>("axes", {V, N, 3}, axes));
  table.arrays.push_back(TableArray::from<double>("coeffs", {V, N, order}, coeffs));
  table.arrays.push_back(TableArray::from<double>("residual", {V}, residual));
  table.arrays.push_back(TableArray::from<double>("norm", {V}, norm));
  if (nd) table.arrays.push_back(TableArray::from<double>("direct", {V, static_cast<std::int64_t>(nd)}, direct));
  if (!vertex_index.empty())
    table.arrays.push_back(TableArray::from<std::uint32_t>("vertex_index", {V}, vertex_index));
  return table;
}

}  // namespace shtool::fit
