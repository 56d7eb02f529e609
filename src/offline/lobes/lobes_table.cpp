// The "zhf-lobes" table and JSON summary of search results (layout in lobes.h).
#include "lobes/lobes.h"

#include <cstdint>
#include <stdexcept>

#include "common/input_error.h"
#include "common/table_writer.h"
#include "shtool/zhf_rotation.h"

namespace shtool::lobes {

// The summary's fields of a band and of a run are the structs' members of the same names
// (the band's directions and the run's band list are added beside them).
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(BandReport, l, sparsity, zeros, entries, cond, largest_zero, smallest_nonzero,
                                   lobes_per_function)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SearchResult, sparsity, zeros, entries, generations, evaluations, best_restart,
                                   restart_sparsity)

namespace {

struct Layout {
  std::vector<const BandReport*> bands;
  std::vector<int> offsets;
  std::vector<double> theta, phi;
};

Layout layout_of(const std::vector<SearchResult>& searches) {
  if (searches.empty()) throw InputError("make_lobes_table: no search results");
  const bool shared = searches[0].shared;
  if (shared && searches.size() != 1) throw InputError("make_lobes_table: one shared result per table");
  Layout lay;
  for (const SearchResult& s : searches) {
    if (s.shared != shared) throw InputError("make_lobes_table: mixed modes");
    const int base = static_cast<int>(lay.theta.size());
    lay.theta.insert(lay.theta.end(), s.theta.begin(), s.theta.end());
    lay.phi.insert(lay.phi.end(), s.phi.begin(), s.phi.end());
    for (const BandReport& b : s.bands) {
      if (!b.invertible) throw InputError("make_lobes_table: singular band " + std::to_string(b.l));
      lay.bands.push_back(&b);
      lay.offsets.push_back(base);
    }
  }
  return lay;
}

nlohmann::json band_json(const BandReport& b, std::span<const double> theta, std::span<const double> phi,
                         int offset) {
  nlohmann::json dirs = nlohmann::json::array();
  for (int d = 0; d < 2 * b.l + 1; ++d) dirs.push_back({theta[offset + d], phi[offset + d]});
  nlohmann::json j = b;
  j["directions"] = dirs;
  return j;
}

}  // namespace

Table make_lobes_table(const std::vector<SearchResult>& searches, const nlohmann::json& generator,
                       const SearchOptions& options) {
  const Layout lay = layout_of(searches);
  const bool shared = searches[0].shared;
  Table t = new_table(kZhfLobesKind, 0, generator, nlohmann::json::object());
  std::vector<std::int32_t> bands, offsets, row_start{0}, cols, lobes, zeros;
  std::vector<double> dirs, a_hat, vals, sparsity, cond, largest, smallest;
  for (std::size_t i = 0; i < lay.theta.size(); ++i) {
    const Vec3<double> w = lobe_direction(lay.theta[i], lay.phi[i]);
    dirs.insert(dirs.end(), {w.x(), w.y(), w.z()});
  }
  for (std::size_t b = 0; b < lay.bands.size(); ++b) {
    const BandReport& r = *lay.bands[b];
    const int n = 2 * r.l + 1;
    bands.push_back(r.l);
    offsets.push_back(lay.offsets[b]);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        const double a = r.a_hat(i, j);
        a_hat.push_back(a);
        if (a != 0.0) {
          cols.push_back(j);
          vals.push_back(a);
        }
      }
      row_start.push_back(static_cast<std::int32_t>(cols.size()));
      lobes.push_back(r.lobes_per_function[i]);
    }
    zeros.push_back(r.zeros);
    sparsity.push_back(r.sparsity);
    cond.push_back(r.cond);
    largest.push_back(r.largest_zero);
    smallest.push_back(r.smallest_nonzero);
  }
  const auto nb = static_cast<std::int64_t>(bands.size());
  const auto nd = static_cast<std::int64_t>(lay.theta.size());
  t.order = bands.back() + 1;
  t.arrays.push_back(TableArray::from<std::int32_t>("bands", {nb}, bands));
  t.arrays.push_back(TableArray::from<std::int32_t>("direction_offset", {nb}, offsets));
  t.arrays.push_back(TableArray::from<double>("theta", {nd}, lay.theta));
  t.arrays.push_back(TableArray::from<double>("phi", {nd}, lay.phi));
  t.arrays.push_back(TableArray::from<double>("directions", {nd, 3}, dirs));
  t.arrays.push_back(TableArray::from<double>("a_hat", {static_cast<std::int64_t>(a_hat.size())}, a_hat));
  t.arrays.push_back(TableArray::from<std::int32_t>("sparse_row_start", {static_cast<std::int64_t>(row_start.size())}, row_start));
  t.arrays.push_back(TableArray::from<std::int32_t>("sparse_col", {static_cast<std::int64_t>(cols.size())}, cols));
  t.arrays.push_back(TableArray::from<double>("sparse_val", {static_cast<std::int64_t>(vals.size())}, vals));
  t.arrays.push_back(TableArray::from<std::int32_t>("lobes_per_function", {static_cast<std::int64_t>(lobes.size())}, lobes));
  t.arrays.push_back(TableArray::from<std::int32_t>("zeros", {nb}, zeros));
  t.arrays.push_back(TableArray::from<double>("sparsity", {nb}, sparsity));
  t.arrays.push_back(TableArray::from<double>("cond", {nb}, cond));
  t.arrays.push_back(TableArray::from<double>("largest_zero", {nb}, largest));
  t.arrays.push_back(TableArray::from<double>("smallest_nonzero", {nb}, smallest));

  nlohmann::json runs = nlohmann::json::array();
  for (const SearchResult& s : searches) {
    nlohmann::json sb = nlohmann::json::array();
    for (const BandReport& b : s.bands) sb.push_back(b.l);
    nlohmann::json run = s;
    run["bands"] = sb;
    runs.push_back(run);
  }
  nlohmann::json meta = {{"mode", shared ? "shared" : "band"},
                         {"zero_threshold", kZeroThreshold},
                         {"max_cond", options.max_cond},
                         {"searches", runs}};
  if (shared) {
    meta["sparsity"] = searches[0].sparsity;
    meta["counted_bands"] = "2..N-1";
  }
  t.meta = meta.dump();
  return t;
}

nlohmann::json lobes_summary_json(const std::vector<SearchResult>& searches) {
  const Layout lay = layout_of(searches);
  const bool shared = searches[0].shared;
  nlohmann::json out = {{"mode", shared ? "shared" : "band"}, {"order", lay.bands.back()->l + 1}};
  if (shared) {
    nlohmann::json dirs = nlohmann::json::array();
    for (std::size_t d = 0; d < lay.theta.size(); ++d) dirs.push_back({lay.theta[d], lay.phi[d]});
    out["directions"] = dirs;
    out["sparsity"] = searches[0].sparsity;
  }
  nlohmann::json bands = nlohmann::json::array();
  for (std::size_t b = 0; b < lay.bands.size(); ++b)
    bands.push_back(band_json(*lay.bands[b], lay.theta, lay.phi, lay.offsets[b]));
  out["bands"] = bands;
  return out;
}

std::shared_ptr<const ZhfLobes> zhf_lobes_for(int order, const std::filesystem::path& table) {
  const std::filesystem::path path = table.empty() ? default_zhf_lobes_path(order) : table;
  if (path.empty())
    throw InputError("no shipped zhf-lobes table covering order " + std::to_string(order) +
                     " was found (set SHTOOL_TABLES to the tables folder, or give one with --tables; make one with "
                     "`shtool search-lobes --shared`)");
  Result<ZhfLobes> loaded = ZhfLobes::load(path);
  if (loaded) loaded = loaded.value().bands_below(order);
  if (!loaded) throw InputError(loaded.error().message);
  return std::make_shared<const ZhfLobes>(std::move(loaded).value());
}

}  // namespace shtool::lobes
