#include "probes/probe_grid_table.h"

#include <algorithm>
#include <optional>
#include <span>

#include "common/atomic_file.h"
#include "common/finite.h"
#include "common/input_error.h"
#include "common/job_outputs.h"
#include "common/table_writer.h"
#include "interop/three_probe_grid.h"
#include "shtool/probe_grid.h"

namespace shtool::probes {
namespace {

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw InputError(name + ": " + what); }

nlohmann::json bounds_json(const ProbeGridSpec& spec) {
  return {{"min", {spec.lower.x(), spec.lower.y(), spec.lower.z()}},
          {"max", {spec.upper.x(), spec.upper.y(), spec.upper.z()}}};
}

// The grid's own meta values beside the scene's; `encoding` null for a partial table
// (its coefficients are the bake's, encoded when the parts are joined).
nlohmann::json grid_meta(const ProbeGridSpec& spec, nlohmann::json meta, std::size_t invalid, std::size_t unfilled,
                         const GridEncoding* encoding) {
  meta["quantity"] = "radiance";
  if (encoding) {
    meta["encoding"] = probe_encoding_name(encoding->encoding);
    if (encoding->encoding == ProbeEncoding::zh3) {
      meta["zh3_axis"] = zh3_axis_name(encoding->zh3_axis);
      meta["zh3_fit"] = zh3_fit_name(encoding->zh3_fit);
    }
  }
  meta["channels"] = {"r", "g", "b"};
  meta["resolution"] = {spec.resolution[0], spec.resolution[1], spec.resolution[2]};
  meta["bounds"] = bounds_json(spec);
  meta["frame"] = "shtool (right-handed, z up)";
  meta["back_face_threshold"] = kInvalidBackFaceShare;
  meta["invalid_probes"] = invalid;
  meta["unfilled_probes"] = unfilled;
  std::string layout =
      "coefficients[iz][iy][ix][k][c]: probe at min + (i + 1/2) (max - min) / n, SH index k = l(l+1)+m, "
      "c = r, g, b; incident radiance c_k = integral L y_k dw; valid[iz][iy][ix] = 0: inside geometry, "
      "filled from valid neighbours";
  if (encoding && encoding->encoding == ProbeEncoding::l1)
    layout += "; encoding l1: bands 0 and 1 only, irradiance by Geomerics' non-linear L1 reconstruction";
  const std::string axis = encoding && encoding->zh3_axis == Zh3Axis::per_channel
                               ? "each channel's own L1 axis"
                               : "the luminance-weighted L1 axis";
  if (encoding && encoding->stores_zonal())
    layout += "; encoding zh3: bands 0 and 1, and zonal[iz][iy][ix][c], the l = 2 zonal coefficient along " + axis +
              " (explicit least-squares fit of band 2)";
  if (encoding && encoding->encoding == ProbeEncoding::zh3 && !encoding->stores_zonal())
    layout += "; encoding zh3, hallucinated: bands 0 and 1 only; the l = 2 zonal coefficient along " + axis +
              " is f = c00 r (0.08 + 0.6 r), r = |d . a| / c00, from the L1 band being evaluated";
  meta["layout"] = std::move(layout);
  return meta;
}

std::size_t count_invalid(const std::vector<std::uint8_t>& valid) {
  return static_cast<std::size_t>(std::count(valid.begin(), valid.end(), std::uint8_t{0}));
}

std::vector<double> bounds_values(const ProbeGridSpec& spec) {
  return {spec.lower.x(), spec.lower.y(), spec.lower.z(), spec.upper.x(), spec.upper.y(), spec.upper.z()};
}

}  // namespace

int lowest_bake_order(const GridEncoding& encoding) {
  switch (encoding.encoding) {
    case ProbeEncoding::l1: return 2;
    case ProbeEncoding::zh3: return encoding.stores_zonal() ? 3 : 2;
    case ProbeEncoding::l2: break;
  }
  return 1;
}

EncodedProbes encode_probes(const ProbeBake& bake, int order, const GridEncoding& encoding) {
  EncodedProbes out;
  out.encoding = encoding;
  out.valid = bake.valid;
  out.unfilled = bake.unfilled;
  if (encoding.encoding == ProbeEncoding::l2) {
    out.order = order;
    out.coefficients = bake.coefficients;
    return out;
  }
  if (order < lowest_bake_order(encoding))
    throw InputError("encoding " + std::string(probe_encoding_name(encoding.encoding)) + " needs a bake of order " +
                     std::to_string(lowest_bake_order(encoding)) + " or more, not " + std::to_string(order));
  out.order = 2;
  const std::size_t per_probe = static_cast<std::size_t>(order) * order * 3, probes = bake.valid.size();
  out.coefficients.reserve(probes * 12);
  if (encoding.stores_zonal()) out.zonal.reserve(probes * 3);
  for (std::size_t p = 0; p < probes; ++p) {
    const std::span<const double> radiance(bake.coefficients.data() + p * per_probe, per_probe);
    // Hallucinated ZH3 stores what l1 stores: its zonal coefficient is the reader's to make.
    if (!encoding.stores_zonal()) {
      const L1Probe<double> l1 = encode_l1(radiance);
      out.coefficients.insert(out.coefficients.end(), l1.coefficients.begin(), l1.coefficients.end());
    } else {
      const Zh3Probe<double> zh3 = encode_zh3(radiance, encoding.zh3_axis, Zh3Fit::explicit_fit);
      out.coefficients.insert(out.coefficients.end(), zh3.l1.coefficients.begin(), zh3.l1.coefficients.end());
      out.zonal.insert(out.zonal.end(), zh3.zonal.begin(), zh3.zonal.end());
    }
  }
  return out;
}

Table probe_grid_table(const ProbeGridSpec& spec, const EncodedProbes& probes, const nlohmann::json& generator,
                       nlohmann::json meta) {
  const std::int64_t nx = spec.resolution[0], ny = spec.resolution[1], nz = spec.resolution[2];
  meta = grid_meta(spec, std::move(meta), count_invalid(probes.valid), probes.unfilled, &probes.encoding);
  Table table = new_table(kProbeGridKind, probes.order, generator, meta);
  table.kind_version = kProbeGridKindVersion;
  const std::int64_t nn = static_cast<std::int64_t>(probes.order) * probes.order;
  table.arrays.push_back(TableArray::from<double>("bounds", {2, 3}, bounds_values(spec)));
  table.arrays.push_back(TableArray::from<double>("coefficients", {nz, ny, nx, nn, 3}, probes.coefficients));
  table.arrays.push_back(TableArray::from<std::uint8_t>("valid", {nz, ny, nx}, probes.valid));
  if (probes.encoding.stores_zonal())
    table.arrays.push_back(TableArray::from<double>("zonal", {nz, ny, nx, 3}, probes.zonal));
  return table;
}

Table probe_grid_part_table(const ProbeGridSpec& spec, const ProbeBake& part, const fit::Shard& shard,
                            const fit::VertexRange& range, const nlohmann::json& generator, nlohmann::json meta) {
  meta = grid_meta(spec, std::move(meta), count_invalid(part.valid), 0, nullptr);
  meta["shard"] = {{"index", shard.index},
                   {"count", shard.count},
                   {"first_probe", range.begin},
                   {"end_probe", range.end},
                   {"probes", spec.probe_count()}};
  Table table = new_table(kProbeGridKind, spec.order, generator, meta);
  table.kind_version = kProbeGridKindVersion;
  const std::int64_t rows = static_cast<std::int64_t>(range.end - range.begin);
  const std::int64_t nn = static_cast<std::int64_t>(spec.order) * spec.order;
  table.arrays.push_back(TableArray::from<double>("bounds", {2, 3}, bounds_values(spec)));
  table.arrays.push_back(TableArray::from<double>("coefficients", {rows, nn, 3}, part.coefficients));
  table.arrays.push_back(TableArray::from<std::uint8_t>("valid", {rows}, part.valid));
  return table;
}

nlohmann::json probe_grid_json(const ProbeGridSpec& spec, const EncodedProbes& bake) {
  nlohmann::json doc;
  doc["order"] = bake.order;
  if (bake.encoding.encoding != ProbeEncoding::l2) doc["encoding"] = probe_encoding_name(bake.encoding.encoding);
  if (bake.encoding.encoding == ProbeEncoding::zh3) {
    doc["zh3_axis"] = zh3_axis_name(bake.encoding.zh3_axis);
    doc["zh3_fit"] = zh3_fit_name(bake.encoding.zh3_fit);
  }
  doc["quantity"] = "radiance";
  doc["channels"] = {"r", "g", "b"};
  doc["resolution"] = {spec.resolution[0], spec.resolution[1], spec.resolution[2]};
  doc["bounds"] = bounds_json(spec);
  nlohmann::json probes = nlohmann::json::array();
  const std::size_t nn = static_cast<std::size_t>(bake.order) * bake.order;
  for (std::size_t p = 0; p < spec.probe_count(); ++p) {
    const std::array<int, 3> i = spec.grid_index(p);
    const Eigen::Vector3d x = spec.position(p);
    nlohmann::json rows = nlohmann::json::array();
    for (std::size_t k = 0; k < nn; ++k) {
      const double* c = bake.coefficients.data() + (p * nn + k) * 3;
      rows.push_back({c[0], c[1], c[2]});
    }
    nlohmann::json probe = {{"index", {i[0], i[1], i[2]}},
                            {"position", {x.x(), x.y(), x.z()}},
                            {"valid", bake.valid[p] != 0},
                            {"coefficients", std::move(rows)}};
    if (bake.encoding.stores_zonal())
      probe["zonal"] = {bake.zonal[p * 3], bake.zonal[p * 3 + 1], bake.zonal[p * 3 + 2]};
    probes.push_back(std::move(probe));
  }
  doc["probes"] = std::move(probes);
  return doc;
}

GridEncoding generator_encoding(const nlohmann::json& parameters, const std::string& name) {
  // One reading of each name for every record: absent is JSON null, which names nothing.
  const auto named = [&](const char* key) {
    const nlohmann::json v = parameters.is_object() ? parameters.value(key, nlohmann::json()) : nlohmann::json();
    return std::pair<bool, std::string>(v.is_string(), v.is_string() ? v.get<std::string>() : v.dump());
  };
  GridEncoding g;
  const auto [has_encoding, encoding] = named("encoding");
  const std::optional<ProbeEncoding> e = has_encoding ? parse_probe_encoding(encoding) : std::nullopt;
  if (!e) fail(name, "generator record's encoding " + encoding + " is not one of l2, l1, zh3");
  g.encoding = *e;
  if (g.encoding != ProbeEncoding::zh3) return g;
  const auto [has_axis, axis] = named("zh3_axis");
  const auto [has_fit, fit] = named("zh3_fit");
  if (has_axis || parameters.contains("zh3_axis")) {
    const std::optional<Zh3Axis> a = has_axis ? parse_zh3_axis(axis) : std::nullopt;
    if (!a) fail(name, "generator record's zh3_axis " + axis + " is not luminance or per-channel");
    g.zh3_axis = *a;
  }
  if (has_fit || parameters.contains("zh3_fit")) {
    const std::optional<Zh3Fit> f = has_fit ? parse_zh3_fit(fit) : std::nullopt;
    if (!f) fail(name, "generator record's zh3_fit " + fit + " is not explicit or hallucinated");
    g.zh3_fit = *f;
  }
  return g;
}

MergedProbeGrid merge_probe_grid(const std::vector<std::pair<std::string, Table>>& parts) {
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
  // Sorted by index: a repeat sits beside its first, and the first index not in its place
  // is the missing one.
  for (std::size_t k = 1; k < read.size(); ++k)
    if (read[k].shard.index == read[k - 1].shard.index)
      throw InputError("merge: shard " + std::to_string(read[k].shard.index) + " of " + std::to_string(count) +
                       " is given twice (" + *read[k - 1].name + " and " + *read[k].name + ")");
  for (std::size_t k = 0; k < read.size(); ++k)
    if (read[k].shard.index != k)
      throw InputError("merge: shard " + std::to_string(k) + " of " + std::to_string(count) + " is missing");
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
  const GridEncoding encoding = generator_encoding(gen["parameters"], *read.front().name);
  // The scene's meta values, without the grid's (probe_grid_table adds them again).
  for (const char* key : {"quantity", "channels", "resolution", "bounds", "frame", "back_face_threshold", "layout"})
    common_meta.erase(key);
  MergedProbeGrid merged;
  merged.spec = spec;
  merged.probes = encode_probes(bake, spec.order, encoding);
  merged.table = probe_grid_table(spec, merged.probes, gen, common_meta);
  return merged;
}

Table merge_probe_grid_tables(const std::vector<std::pair<std::string, Table>>& parts) {
  return merge_probe_grid(parts).table;
}

bool is_probe_grid_file(const std::filesystem::path& path) {
  const Result<Table> t = read_table(path);
  return t.ok() && t.value().kind == kProbeGridKind;
}

std::vector<double> three_coefficients(const EncodedProbes& probes, int& order, const std::string& option) {
  const GridEncoding& e = probes.encoding;
  if (e.encoding == ProbeEncoding::l1)
    throw InputError(option + " of an l1 grid: " + interop::kThreeCannotShowL1);
  order = probes.order;
  if (e.encoding == ProbeEncoding::l2) return probes.coefficients;
  order = 3;
  const std::size_t count = probes.valid.size();
  std::vector<double> out;
  out.reserve(count * 27);
  for (std::size_t p = 0; p < count; ++p) {
    const std::array<double, 27> sh = interop::zh3_as_order3_sh(
        std::span<const double, 12>(probes.coefficients.data() + p * 12, 12),
        e.stores_zonal() ? probes.zonal.data() + p * 3 : nullptr, e.zh3_axis);
    out.insert(out.end(), sh.begin(), sh.end());
  }
  return out;
}

ProbeMergeReport merge_probe_grid_parts(const std::vector<std::filesystem::path>& paths,
                                        const std::filesystem::path& out, TableEncoding encoding,
                                        const std::filesystem::path& json, const std::filesystem::path& threejs) {
  JobOutputs io;
  for (const std::filesystem::path& p : paths) io.input(p, "a part");
  io.output(out, "--out");
  io.output(json, "--json");
  if (!threejs.empty()) interop::declare_three_probe_grid(io, threejs, "--threejs");
  std::vector<std::pair<std::string, Table>> parts;
  for (const std::filesystem::path& p : paths) {
    Result<Table> t = read_table(p, TableExpectation{std::string(kProbeGridKind), 1, 0});
    if (!t) throw InputError(t.error().message);
    parts.emplace_back(p.string(), std::move(t).value());
  }
  const MergedProbeGrid merged = merge_probe_grid(parts);
  ProbeMergeReport report;
  report.parts = parts.size();
  report.probes = merged.table.find("valid")->element_count();
  io.set("--out", encode_table(merged.table, encoding));
  if (io.requested("--json")) io.set("--json", dump_finite(probe_grid_json(merged.spec, merged.probes), "--json") + "\n");
  if (!threejs.empty()) {
    interop::ThreeProbeGridInput three;
    three.resolution = merged.spec.resolution;
    three.min = merged.spec.lower;
    three.max = merged.spec.upper;
    three.coefficients = three_coefficients(merged.probes, three.order, "--threejs");
    interop::set_three_probe_grid(io, "--threejs", interop::three_probe_grid_files(three));
  }
  io.commit();
  return report;
}

}  // namespace shtool::probes
