#include "fit/zh_fit_table.h"

#include "common/finite.h"
#include "common/table_writer.h"

#include <cmath>

namespace shtool::fit {

double normalized_rms(const ZhFitTable<double>& fits) {
  double sum_res = 0, sum_norm = 0;
  for (std::size_t v = 0; v < fits.vertices; ++v) {
    sum_res += fits.residual[v] * fits.residual[v];
    sum_norm += fits.norm[v] * fits.norm[v];
  }
  return sum_norm > 0 ? std::sqrt(sum_res / sum_norm) : 0.0;
}

Table zh_fit_table(const ZhFitTable<double>& fits, nlohmann::json meta, const nlohmann::json& generator) {
  const std::size_t count = fits.vertices;
  const int order = fits.order, lobes = fits.lobes;
  // The axes as the table stores them: [V, N, 3] doubles.
  std::vector<double> axes(count * lobes * 3);
  for (std::size_t a = 0; a < fits.axes.size(); ++a)
    for (int c = 0; c < 3; ++c) axes[a * 3 + c] = fits.axes[a][c];
  meta["vectors"] = count;
  meta["lobes"] = lobes;
  meta["normalized_rms"] = normalized_rms(fits);
  meta["layout"] = "axes[v][k] unit axis, coeffs[v][k][l] = g*_l (lobe k adds g*_l y_l^m(axis) to SH (l,m)); "
                   "residual[v] = ||fit - t||, norm[v] = ||t||";
  Table table = new_table(kZhFitKind, order, generator, meta);
  // 1.1 added meta "shard" (partial tables of a sharded bake, docs/fit-zh.md), 1.2 meta
  // "texture" (texture-space bakes); other tables keep 1.1 and their bytes.
  table.kind_version = meta.contains("texture") ? "1.2" : "1.1";
  const auto V = static_cast<std::int64_t>(count), N = static_cast<std::int64_t>(lobes);
  table.arrays.push_back(TableArray::from<double>("axes", {V, N, 3}, axes));
  table.arrays.push_back(TableArray::from<double>("coeffs", {V, N, order}, fits.coeffs));
  table.arrays.push_back(TableArray::from<double>("residual", {V}, fits.residual));
  table.arrays.push_back(TableArray::from<double>("norm", {V}, fits.norm));
  if (fits.direct_count)
    table.arrays.push_back(TableArray::from<double>("direct", {V, fits.direct_count}, fits.direct));
  if (!fits.vertex_index.empty())
    table.arrays.push_back(TableArray::from<std::uint32_t>("vertex_index", {V}, fits.vertex_index));
  return table;
}

std::string fits_json(const ZhFitTable<double>& fits) {
  nlohmann::json doc = {{"order", fits.order}, {"lobes", fits.lobes}, {"fits", nlohmann::json::array()}};
  for (std::size_t v = 0; v < fits.vertices; ++v) {
    nlohmann::json jf = {{"lobes", nlohmann::json::array()}};
    const std::span<const double> coeffs = fits.coeffs_of(v);
    for (int k = 0; k < fits.lobes; ++k) {
      const Eigen::Vector3d& axis = fits.axes_of(v)[k];
      jf["lobes"].push_back({{"axis", {axis.x(), axis.y(), axis.z()}},
                             {"coeffs", coeffs.subspan(static_cast<std::size_t>(k) * fits.order, fits.order)}});
    }
    jf["residual"] = fits.residual[v];
    jf["norm"] = fits.norm[v];
    if (fits.direct_count) jf["direct"] = fits.direct_of(v);
    doc["fits"].push_back(std::move(jf));
  }
  return dump_finite(doc, "--json") + "\n";
}

}  // namespace shtool::fit
