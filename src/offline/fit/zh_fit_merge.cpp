#include "fit/zh_fit_merge.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "common/job_outputs.h"
#include "common/input_error.h"
#include "common/table_writer.h"
#include "fit/shard.h"
#include "fit/zh_fit_table.h"

namespace shtool::fit {
namespace {

struct Part {
  std::string name;
  Table table;
  nlohmann::json generator, meta;  // meta without the shard record and the part's own summaries
  Shard shard;
  VertexRange range;
  std::size_t total = 0;
  std::size_t rows = 0;
  int lobes = 0;
  std::int64_t direct = -1;  // columns of 'direct', -1: none
  bool vertex_index = false;
};

[[noreturn]] void fail(const std::string& name, const std::string& what) { throw InputError(name + ": " + what); }

// The first place two JSON values differ, as "a.b.c (x vs y)"; empty when equal.
std::string first_difference(const nlohmann::json& a, const nlohmann::json& b, const std::string& where) {
  if (a.is_object() && b.is_object()) {
    for (const auto& [key, value] : a.items()) {
      if (!b.contains(key)) return where + "." + key + " (" + value.dump() + " vs absent)";
      if (std::string d = first_difference(value, b.at(key), where + "." + key); !d.empty()) return d;
    }
    for (const auto& [key, value] : b.items())
      if (!a.contains(key)) return where + "." + key + " (absent vs " + value.dump() + ")";
    return {};
  }
  return a == b ? std::string() : where + " (" + a.dump() + " vs " + b.dump() + ")";
}

std::size_t shard_field(const Part& p, const nlohmann::json& shard, const char* name) {
  if (!shard.contains(name) || !shard.at(name).is_number_unsigned())
    fail(p.name, std::string("shard record has no non-negative integer '") + name + "'");
  return shard.at(name).get<std::size_t>();
}

// The part's shape, checked against its own shard record, before any comparison.
Part read_part(NamedTable named) {
  Part p;
  p.name = std::move(named.name);
  p.table = std::move(named.table);
  const std::string& path = p.name;
  if (p.table.kind != kZhFitKind) fail(path, "a table of kind '" + p.table.kind + "', not zh-fit");
  p.generator = table_generator(p.table);
  p.meta = table_meta(p.table);
  if (!p.meta.is_object() || !p.meta.contains("shard") || !p.meta.at("shard").is_object())
    fail(path, "not a partial table (no shard record): merge joins the outputs of fit-zh --shard K/N");
  const nlohmann::json shard = p.meta.at("shard");
  p.shard.index = shard_field(p, shard, "index");
  p.shard.count = shard_field(p, shard, "count");
  p.range = {shard_field(p, shard, "first_vertex"), shard_field(p, shard, "end_vertex")};
  p.total = shard_field(p, shard, "vertices");
  // 2^32 vertices at most: vertex_index is u32 (and keeps the range products in 64 bits).
  if (p.shard.count < 1 || p.shard.count > kMaxShards || p.shard.index >= p.shard.count ||
      p.shard.count > p.total || p.total > (std::size_t{1} << 32))
    fail(path, "shard record " + shard.dump() + " is not a shard K of N of its vertices");
  const VertexRange expected = shard_range(p.total, p.shard);
  if (p.range.begin != expected.begin || p.range.end != expected.end)
    fail(path, "shard record " + shard.dump() + ": shard " + std::to_string(p.shard.index) + " of " +
                   std::to_string(p.shard.count) + " covers vertices [" + std::to_string(expected.begin) + ", " +
                   std::to_string(expected.end) + ")");
  p.rows = p.range.end - p.range.begin;

  const TableArray* axes = p.table.find("axes");
  if (!axes || axes->dtype != DType::f64 || axes->shape.size() != 3 || axes->shape[2] != 3 ||
      axes->shape[0] != static_cast<std::int64_t>(p.rows) || axes->shape[1] < 1)
    fail(path, "array 'axes' is missing or not of shape [" + std::to_string(p.rows) + ", N, 3]");
  p.lobes = static_cast<int>(axes->shape[1]);
  const std::int64_t rows = static_cast<std::int64_t>(p.rows);
  auto expect_shape = [&](const char* name, DType dtype, const std::vector<std::int64_t>& shape) {
    const TableArray* a = p.table.find(name);
    if (!a || a->dtype != dtype || a->shape != shape) fail(path, std::string("array '") + name + "' is missing or misshapen");
  };
  expect_shape("coeffs", DType::f64, {rows, p.lobes, p.table.order});
  expect_shape("residual", DType::f64, {rows});
  expect_shape("norm", DType::f64, {rows});
  if (const TableArray* d = p.table.find("direct")) {
    if (d->shape.size() != 2) fail(path, "array 'direct' is not of shape [V, D]");
    p.direct = d->shape[1];
    expect_shape("direct", DType::f64, {rows, p.direct});
  }
  if (p.table.find("vertex_index")) {
    p.vertex_index = true;
    expect_shape("vertex_index", DType::u32, {rows});
  }
  // What describes the whole bake stays; the part's own row count and error go.
  for (const char* key : {"shard", "vectors", "normalized_rms"}) p.meta.erase(key);
  return p;
}

}  // namespace

MergedFits merge_zh_fit_tables(std::vector<NamedTable> named) {
  if (named.empty()) throw InputError("no partial tables to join");
  std::vector<Part> parts;
  parts.reserve(named.size());
  for (NamedTable& t : named) parts.push_back(read_part(std::move(t)));

  const Part& first = parts.front();
  for (const Part& p : parts) {
    auto differ = [&](const std::string& what) {
      // In the order of the values in `what`: the first part's, then this one's.
      throw InputError("'" + first.name + "' and '" + p.name + "' are not parts of the same bake: " + what);
    };
    if (std::string d = first_difference(first.generator, p.generator, "generator"); !d.empty()) differ(d);
    if (std::string d = first_difference(first.meta, p.meta, "meta"); !d.empty()) differ(d);
    if (p.table.order != first.table.order)
      differ("order " + std::to_string(first.table.order) + " vs " + std::to_string(p.table.order));
    if (p.lobes != first.lobes) differ("lobes " + std::to_string(first.lobes) + " vs " + std::to_string(p.lobes));
    if (p.direct != first.direct) differ("'direct' columns differ");
    if (p.vertex_index != first.vertex_index) differ("one has 'vertex_index', the other not");
    if (p.shard.count != first.shard.count || p.total != first.total)
      differ("shard " + std::to_string(first.shard.index) + " of " + std::to_string(first.shard.count) + " (" +
             std::to_string(first.total) + " vertices) vs shard " + std::to_string(p.shard.index) + " of " +
             std::to_string(p.shard.count) + " (" + std::to_string(p.total) + " vertices)");
  }
  const std::size_t count = first.shard.count;
  std::vector<const Part*> by_index(count, nullptr);
  for (const Part& p : parts) {
    if (by_index[p.shard.index])
      throw InputError("shard " + std::to_string(p.shard.index) + " of " + std::to_string(count) +
                       " is given twice ('" + by_index[p.shard.index]->name + "' and '" + p.name + "')");
    by_index[p.shard.index] = &p;
  }
  std::string missing;
  std::size_t missing_count = 0;
  for (std::size_t k = 0; k < count; ++k)
    if (!by_index[k] && ++missing_count <= 10) missing += (missing.empty() ? "" : ", ") + std::to_string(k);
  if (missing_count)
    throw InputError(std::to_string(missing_count) + " of " + std::to_string(count) +
                     " shards missing (" + missing + (missing_count > 10 ? ", ..." : "") + ")");

  // The rows in vertex order, through the writer a one-process run uses.
  MergedFits merged;
  ZhFitTable<double>& fits = merged.fits;
  fits.order = first.table.order;
  fits.lobes = first.lobes;
  fits.direct_count = static_cast<int>(std::max<std::int64_t>(first.direct, 0));
  for (const Part* p : by_index) {
    fits.vertices += p->rows;
    const std::vector<double> axes = p->table.find("axes")->values<double>();
    for (std::size_t a = 0; a < axes.size(); a += 3) fits.axes.emplace_back(axes[a], axes[a + 1], axes[a + 2]);
    auto append = [&]<class T>(std::vector<T>& to, const char* name) {
      const std::vector<T> values = p->table.find(name)->values<T>();
      to.insert(to.end(), values.begin(), values.end());
    };
    append(fits.coeffs, "coeffs");
    append(fits.residual, "residual");
    append(fits.norm, "norm");
    if (fits.direct_count) append(fits.direct, "direct");
    if (p->vertex_index) append(fits.vertex_index, "vertex_index");
  }
  merged.table = zh_fit_table(fits, first.meta, first.generator);
  // What render and the engine's loader check (unit axes, residuals and norms of 0 or
  // more, finite values), checked before the table is written: parts edited with valid
  // checksums, or written by a faulty tool, are refused here rather than shipped.
  if (const Result<ZhFitTable<double>> loads = ZhFitTable<double>::from_table(merged.table); !loads)
    throw InputError("the joined table would not load: " + loads.error().message);
  return merged;
}

MergeReport merge_zh_fit_parts(const MergeRequest& r) {
  if (r.parts.empty()) throw InputError("merge: give the partial tables to join");
  if (r.out.empty()) throw InputError("merge: give --out TABLE");
  JobOutputs io;
  for (std::size_t i = 0; i < r.parts.size(); ++i) {
    io.input(r.parts[i], "a part");
    for (std::size_t j = 0; j < i; ++j)
      if (same_file(r.parts[i], r.parts[j]))
        throw InputError("merge: '" + r.parts[i].string() + "' is given twice");
  }
  io.output(r.out, "--out");
  std::vector<NamedTable> tables;
  tables.reserve(r.parts.size());
  for (const std::filesystem::path& path : r.parts) {
    Result<Table> t = read_table(path, {std::string(kZhFitKind), 1});
    if (!t) throw InputError(t.error().message);
    // A part edited by hand (or damaged with a valid checksum) is named here, not as an
    // overflow of the merged table.
    for (const TableArray& a : t.value().arrays) {
      if (a.dtype != DType::f64) continue;
      const std::vector<double> values = a.values<double>();
      for (std::size_t k = 0; k < values.size(); ++k)
        if (!std::isfinite(values[k]))
          throw InputError("merge: '" + path.string() + "': array '" + a.name + "' value " + std::to_string(k) +
                           " is not finite");
    }
    tables.push_back({path.string(), std::move(t).value()});
  }
  MergedFits merged;
  try {
    merged = merge_zh_fit_tables(std::move(tables));
  } catch (const InputError& e) {
    throw InputError(std::string("merge: ") + e.what());
  }
  io.set("--out", encode_table(merged.table, r.encoding));
  io.commit();
  return {r.parts.size(), merged.fits.vertices};
}

}  // namespace shtool::fit
