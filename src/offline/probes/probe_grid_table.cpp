#include "probes/probe_grid_table.h"

#include <algorithm>

#include "common/atomic_file.h"
#include "common/input_error.h"
#include "common/job_outputs.h"
#include "common/table_writer.h"
#include "shtool/probe_grid.h"

namespace shtool::probes {
namespace {

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw InputError(name + ": " + what); }

nlohmann::json bounds_json(const ProbeGridSpec& spec) {
  return {{"min", {spec.lower.x(), spec.lower.y(), spec.lower.z()}},
          {"max", {spec.upper.x(), spec.upper.y(), spec.upper.z()}}};
}

// The grid's own meta values beside the scene's.
nlohmann::json grid_meta(const ProbeGridSpec& spec, nlohmann::json meta, std::size_t invalid, std::size_t unfilled) {
  meta["quantity"] = "radiance";
  meta["channels"] = {"r", "g", "b"};
  meta["resolution"] = {spec.resolution[0], spec.resolution[1], spec.resolution[2]};
  meta["bounds"] = bounds_json(spec);
  meta["frame"] = "shtool (right-handed, z up)";
  meta["back_face_threshold"] = kInvalidBackFaceShare;
  meta["invalid_probes"] = invalid;
  meta["unfilled_probes"] = unfilled;
  meta["layout"] = "coefficients[iz][iy][ix][k][c]: probe at min + (i + 1/2) (max - min) / n, SH index k = l(l+1)+m, "
                   "c = r, g, b; incident radiance c_k = integral L y_k dw; valid[iz][iy][ix] = 0: inside geometry, "
                   "filled from valid neighbours";
  return meta;
}

std::size_t count_invalid(const std::vector<std::uint8_t>& valid) {
  return static_cast<std::size_t>(std::count(valid.begin(), valid.end(), std::uint8_t{0}));
}

std::vector<double> bounds_values(const ProbeGridSpec& spec) {
  return {spec.lower.x(), spec.lower.y(), spec.lower.z(), spec.upper.x(), spec.upper.y(), spec.upper.z()};
}

}  // namespace

Table probe_grid_table(const ProbeGridSpec& spec, const ProbeBake& bake, const nlohmann::json& generator,
                       nlohmann::json meta) {
  const std::int64_t nx = spec.resolution[0], ny = spec.resolution[1], nz = spec.resolution[2];
  meta = grid_meta(spec, std::move(meta), count_invalid(bake.valid), bake.unfilled);
  Table table = new_table(kProbeGridKind, spec.order, generator, meta);
  const std::int64_t nn = static_cast<std::int64_t>(spec.order) * spec.order;
  table.arrays.push_back(TableArray::from<double>("bounds", {2, 3}, bounds_values(spec)));
  table.arrays.push_back(TableArray::from<double>("coefficients", {nz, ny, nx, nn, 3}, bake.coefficients));
  table.arrays.push_back(TableArray::from<std::uint8_t>("valid", {nz, ny, nx}, bake.valid));
  return table;
}

Table probe_grid_part_table(const ProbeGridSpec& spec, const ProbeBake& part, const fit::Shard& shard,
                            const fit::VertexRange& range, const nlohmann::json& generator, nlohmann::json meta) {
  meta = grid_meta(spec, std::move(meta), count_invalid(part.valid), 0);
  meta["shard"] = {{"index", shard.index},
                   {"count", shard.count},
                   {"first_probe", range.begin},
                   {"end_probe", range.end},
                   {"probes", spec.probe_count()}};
  Table table = new_table(kProbeGridKind, spec.order, generator, meta);
  const std::int64_t rows = static_cast<std::int64_t>(range.end - range.begin);
  const std::int64_t nn = static_cast<std::int64_t>(spec.order) * spec.order;
  table.arrays.push_back(TableArray::from<double>("bounds", {2, 3}, bounds_values(spec)));
  table.arrays.push_back(TableArray::from<double>("coefficients", {rows, nn, 3}, part.coefficients));
  table.arrays.push_back(TableArray::from<std::uint8_t>("valid", {rows}, part.valid));
  return table;
}

nlohmann::json probe_grid_json(const ProbeGridSpec& spec, const ProbeBake& bake) {
  nlohmann::json doc;
  doc["order"] = spec.order;
  doc["quantity"] = "radiance";
  doc["channels"] = {"r", "g", "b"};
  doc["resolution"] = {spec.resolution[0], spec.resolution[1], spec.resolution[2]};
  doc["bounds"] = bounds_json(spec);
  nlohmann::json probes = nlohmann::json::array();
  const std::size_t nn = static_cast<std::size_t>(spec.order) * spec.order;
  for (std::size_t p = 0; p < spec.probe_count(); ++p) {
    const std::array<int, 3> i = spec.grid_index(p);
    const Eigen::Vector3d x = spec.position(p);
    nlohmann::json rows = nlohmann::json::array();
    for (std::size_t k = 0; k < nn; ++k) {
      const double* c = bake.coefficients.data() + (p * nn + k) * 3;
      rows.push_back({c[0], c[1], c[2]});
    }
    probes.push_back({{"index", {i[0], i[1], i[2]}},
                      {"position", {x.x(), x.y(), x.z()}},
                      {"valid", bake.valid[p] != 0},
                      {"coefficients", std::move(rows)}});
  }
  doc["probes"] = std::move(probes);
  return doc;
}

Table merge_probe_grid_tables(const std::vector<std::pair<std::string, Table>>& parts) {
  if (parts.empty()) throw InputError("merge: no parts");
  struct Part {
    const std::string* name;
    const Table* table;
    fit::Shard shard;
    fit::VertexRange range;
  };
  std::vector<Part> read;
  std::string generator;
  nlohmann::json common_meta;
  std::size_t total = 0;
  std::vector<double> bounds;
  for (const auto& [name, table] : parts) {
    if (table.kind != kProbeGridKind) fail(name, "a table of kind '" + table.kind + "', not probe-grid");
    nlohmann::json meta = table_meta(table);
    if (!meta.is_object() || !meta.contains("shard") || !meta["shard"].is_object())
      fail(name, "not a partial table (no shard record): merge joins the outputs of bake-probes --shard K/N");
    const nlohmann::json shard = meta["shard"];
    for (const char* key : {"index", "count", "first_probe", "end_probe", "probes"})
      if (!shard.contains(key) || !shard[key].is_number_unsigned())
        fail(name, std::string("shard record has no non-negative integer '") + key + "'");
    Part p{&name, &table, {shard["index"].get<std::size_t>(), shard["count"].get<std::size_t>()},
           {shard["first_probe"].get<std::size_t>(), shard["end_probe"].get<std::size_t>()}};
    const std::size_t probes = shard["probes"].get<std::size_t>();
    if (p.shard.count < 1 || p.shard.index >= p.shard.count || probes < 1)
      fail(name, "shard record " + shard.dump() + " is not a shard K of N");
    const fit::VertexRange expected = fit::shard_range(probes, p.shard);
    if (expected.begin != p.range.begin || expected.end != p.range.end)
      fail(name, "shard record " + shard.dump() + " does not match its shard's probes");
    meta.erase("shard");
    meta.erase("invalid_probes");
    meta.erase("unfilled_probes");
    const TableArray* c = table.find("coefficients");
    const TableArray* v = table.find("valid");
    const TableArray* b = table.find("bounds");
    const std::int64_t rows = static_cast<std::int64_t>(p.range.end - p.range.begin);
    const std::int64_t nn = static_cast<std::int64_t>(table.order) * table.order;
    if (!c || c->dtype != DType::f64 || c->shape != std::vector<std::int64_t>{rows, nn, 3} || !v ||
        v->dtype != DType::u8 || v->shape != std::vector<std::int64_t>{rows} || !b || b->dtype != DType::f64 ||
        b->shape != std::vector<std::int64_t>{2, 3})
      fail(name, "arrays do not have the shapes of its shard (coefficients [R, N^2, 3], valid [R], bounds [2, 3])");
    if (read.empty()) {
      generator = table.generator;
      common_meta = meta;
      total = probes;
      bounds = b->values<double>();
    } else {
      const Part& first = read.front();
      if (table.generator != generator || meta != common_meta || table.order != first.table->order ||
          probes != total || p.shard.count != first.shard.count || b->values<double>() != bounds)
        fail(name, "comes from another bake than " + *first.name +
                       " (generator records, grids or shard counts differ)");
    }
    read.push_back(p);
  }
  std::sort(read.begin(), read.end(), [](const Part& a, const Part& b) { return a.shard.index < b.shard.index; });
  const std::size_t count = read.front().shard.count;
  for (std::size_t k = 0; k < read.size(); ++k)
    if (read[k].shard.index != k || (k > 0 && read[k - 1].shard.index == k))
      fail(*read[std::min(k, read.size() - 1)].name,
           "shard " + std::to_string(k) + " of " + std::to_string(count) + " is missing or given twice");
  if (read.size() != count)
    throw InputError("merge: " + std::to_string(read.size()) + " parts given for a bake in " + std::to_string(count) +
                     " shards");

  const nlohmann::json gen = nlohmann::json::parse(generator);
  const nlohmann::json grid = gen["parameters"]["grid"];
  ProbeGridSpec spec;
  for (int a = 0; a < 3; ++a) spec.resolution[a] = grid.at(a).get<int>();
  spec.lower = Eigen::Vector3d(bounds[0], bounds[1], bounds[2]);
  spec.upper = Eigen::Vector3d(bounds[3], bounds[4], bounds[5]);
  spec.order = read.front().table->order;
  if (spec.probe_count() != total) throw InputError("merge: the parts' grid does not hold their probe count");
  ProbeBake bake;
  for (const Part& p : read) {
    const std::vector<double> c = p.table->find("coefficients")->values<double>();
    const std::vector<std::uint8_t> v = p.table->find("valid")->values<std::uint8_t>();
    bake.coefficients.insert(bake.coefficients.end(), c.begin(), c.end());
    bake.valid.insert(bake.valid.end(), v.begin(), v.end());
  }
  bake.unfilled = fill_invalid_probes(spec.resolution, spec.order * spec.order * 3, bake.valid, bake.coefficients);
  // The scene's meta values, without the grid's (probe_grid_table adds them again).
  for (const char* key : {"quantity", "channels", "resolution", "bounds", "frame", "back_face_threshold", "layout"})
    common_meta.erase(key);
  return probe_grid_table(spec, bake, gen, common_meta);
}

bool is_probe_grid_file(const std::filesystem::path& path) {
  const Result<Table> t = read_table(path);
  return t.ok() && t.value().kind == kProbeGridKind;
}

ProbeMergeReport merge_probe_grid_parts(const std::vector<std::filesystem::path>& paths,
                                        const std::filesystem::path& out, TableEncoding encoding) {
  JobOutputs io;
  for (const std::filesystem::path& p : paths) io.input(p, "a part");
  io.output(out, "--out");
  std::vector<std::pair<std::string, Table>> parts;
  for (const std::filesystem::path& p : paths) {
    Result<Table> t = read_table(p, TableExpectation{std::string(kProbeGridKind), 1, 0});
    if (!t) throw InputError(t.error().message);
    parts.emplace_back(p.string(), std::move(t).value());
  }
  const Table merged = merge_probe_grid_tables(parts);
  ProbeMergeReport report;
  report.parts = parts.size();
  report.probes = merged.find("valid")->element_count();
  io.set("--out", encode_table(merged, encoding));
  io.commit();
  return report;
}

}  // namespace shtool::probes
